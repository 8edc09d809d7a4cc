"""Render farms: chunks of a shot rendered from baked wave fields on many machines.

- :mod:`.client`: ``usdwrinkle render --dask``: bake once, submit chunks, gather. Each
  Dask task is ``app.chunks.render_chunk`` (one engine per worker process, kept across
  tasks, made lazily on the task's own thread).

Farm managers that run command lines (OpenCue, Deadline, Tractor) need none of this:
one ``usdwrinkle render`` per chunk on the baked layer (README, "Rendering on a farm").
"""
