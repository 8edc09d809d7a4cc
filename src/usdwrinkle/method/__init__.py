"""The method's neutral parts, no GL and no stage: the Python <-> GLSL contract
(contract.py), the fold law in numpy (folds.py), the wave profiles (profiles.py), the
phase history's bookkeeping (history.py) and walks over polygons (polygons.py)."""
