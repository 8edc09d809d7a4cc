"""USD values and the schema: the WrinkleAPI (schema.py) and its rules (validation.py),
authored values (values.py) and USD's diagnostics as one-line messages
(diagnostics.py). The stage metadata a layer carries stays at the package's root
(layerinfo.py, pxr only): usdview's plugin imports it in a Python without numpy."""
