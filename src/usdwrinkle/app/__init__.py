"""The application layer: one object per job, that every door stands on.

The command line (cli/), the Python API (api.py), the farm (farm/), usdview's plugin
(usdview/) and the paint window (paint/) are doors: each maps what its user gives to a
job's typed options and shows what the job reports. A job owns its checks, its warnings
(the ``usdwrinkle`` logger), its frame loop and its writers:

- :class:`Shot`: a stage as a job opens it (composition, wrinkle options, frames);
- :class:`RenderJob`: a shot's frames to image files;
- :class:`BakeJob`: a shot's wrinkle fields (and maps, geometry) into a USD layer.

They live in app/shot.py, app/render.py and app/bake.py, their options in
app/options.py; ``usdwrinkle.api`` re-exports them (this package imports none of its
modules, so that importing one runs no other).
"""

