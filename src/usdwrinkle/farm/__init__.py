"""Render farms: chunks of a shot rendered from baked wave fields on many machines.

A room below the jobs: app/render.RenderJob runs a render here when its options name a
Dask scheduler (``dask``), as it runs the serial frame loop (frameloop.render_frames) when
they do not; the command line and the Python API only build the job.

- :mod:`.client`: bake once (through the job), submit chunks, gather.
- :mod:`.worker`: each Dask task, ``render_chunk`` (one engine per worker process, kept
  across tasks, made lazily on the task's own thread).

Farm managers that run command lines (OpenCue, Deadline, Tractor) need none of this:
one ``usdwrinkle render`` per chunk on the baked layer (README, "Rendering on a farm").
"""
