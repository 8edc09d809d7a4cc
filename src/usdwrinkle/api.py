"""usdwrinkle from Python: render and bake a shot in-process.

    from usdwrinkle import api

    frames = api.render("shot.usda", "out/shot.####.exr", frames="1:24", width=960)
    layer = api.bake("shot.usda", "shot_wrinkles.usdc", maps=["normal"], with_points=True)

Each call runs the job the command line runs (usdwrinkle.app: ``RenderJob``, ``BakeJob``),
with the same checks and defaults; the keywords are the jobs' option fields
(app/options.py: ``RenderOptions``, ``BakeOptions``, ``ShotOptions``), which are the
command line's long options with ``_`` for ``-``. ``frames`` takes usdrecord's FrameSpec
text ("1:24", "1,5,9", "1:24x2") or a list of numbers; None is the stage's range.

A problem with the input raises :class:`UsdWrinkleError` (also ``usdwrinkle.api.
UsdWrinkleError``) with a one-line message that names option fields in backquotes
(`` `width` and `height` must be positive``). Warnings go through the ``usdwrinkle``
logger (usdwrinkle/process/log.py): on stderr as ``usdwrinkle: warning: ...`` unless the caller
collects them (``with usdwrinkle.log.collect() as messages: api.render(...)``) or
silences them. ``quiet`` (True by default here) leaves out the progress bars.

For more control, build the jobs yourself::

    from usdwrinkle.api import RenderJob, RenderOptions, Shot, ShotOptions

    shot = Shot("shot.usda", ShotOptions(sublayer=("fixes.usda",)))
    result = RenderJob(shot, "out/f.####.exr", "1:24", RenderOptions(width=640)).run()

Authoring is :class:`usdwrinkle.WrinkleAPI` (and ``usdwrinkle apply`` on the command
line).
"""
from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

from .app.bake import BakeJob, BakeResult
from .app.options import BakeOptions, RenderOptions, ShotOptions
from .app.render import RenderJob, RenderResult
from .app.shot import Progress, Shot, no_progress
from .process.errors import UsdWrinkleError, print_stderr

__all__ = ["BakeJob", "BakeOptions", "BakeResult", "RenderJob", "RenderOptions",
           "RenderResult", "Shot", "ShotOptions", "UsdWrinkleError", "bake", "render"]

Path = str | os.PathLike[str]
Frames = str | Sequence[float] | None


def _progress(quiet: bool) -> Progress:
    if quiet:
        return no_progress
    from .app.shot import progress_bars

    return progress_bars


def _shot(stage: Path, all_meshes: bool, relax_iterations: int | None,
          history_start: float | None, sublayer: Any, variant: Any, mask: Any) -> Shot:
    # ShotOptions takes a single str or path where a list is expected, and names the
    # field of anything else; None is the empty list here, as the keywords' default
    return Shot(stage, ShotOptions(all_meshes=all_meshes, relax_iterations=relax_iterations,
                                   history_start=history_start,
                                   sublayer=() if sublayer is None else sublayer,
                                   variant=() if variant is None else variant,
                                   mask=() if mask is None else mask))


def render(stage: Path, output: Path, frames: Frames = None, *, quiet: bool = True,
           camera: str | None = None, width: int = 960, height: int | None = None,
           samples: int = 4, shade_samples: bool = True, relief: bool = False,
           write_threads: int | None = None,
           readback_buffers: int | None = None, exr_half: bool = True, exr_compression: str = "zip",
           aovs: str | Sequence[str] | None = None,
           no_wrinkles: bool = False, skip_existing: bool = False, recompute: bool = False,
           stats: str | None = None, stats_passes: bool = True,
           all_meshes: bool = False, relax_iterations: int | None = None,
           history_start: float | None = None, sublayer: Sequence[str] = (),
           variant: Sequence[str] = (), mask: str | Sequence[str] | None = None,
           dask: str | None = None, workers: int | None = None,
           chunk: int | None = None) -> list[str]:
    """Render ``stage`` to ``output`` (a path with a '#' frame placeholder, or one file for
    one frame); returns the paths of the frames the shot now has on disk (written, or
    kept by ``skip_existing``). The options are RenderOptions' and ShotOptions' fields
    (``usdwrinkle render --help`` says what each does); ``sublayer`` is a list of layers
    over the stage, strongest first, ``variant`` a list of "/Prim{set=name}" and ``mask``
    prim paths ("/A,/B" or a list), ``aovs`` the AOVs of an EXR ("color,depth" or a list).
    ``dask`` ("local" or a scheduler's address),
    ``workers`` and ``chunk`` render on a Dask cluster, as ``render --dask``."""
    options = RenderOptions(camera=camera, width=width, height=height, samples=samples,
                            shade_samples=shade_samples, relief=relief,
                            write_threads=write_threads,
                            readback_buffers=readback_buffers, exr_half=exr_half,
                            exr_compression=exr_compression,
                            aovs=None if aovs is None else
                            tuple([aovs] if isinstance(aovs, str) else aovs),
                            no_wrinkles=no_wrinkles, skip_existing=skip_existing,
                            recompute=recompute, stats=stats, stats_passes=stats_passes,
                            dask=dask, workers=workers, chunk=chunk)
    job = RenderJob(_shot(stage, all_meshes, relax_iterations, history_start, sublayer,
                          variant, mask), output, frames, options, progress=_progress(quiet))
    if not quiet:
        job.say = print_stderr
    return [path for path in job.run().outputs if os.path.isfile(path)]


def bake(stage: Path, output: Path, frames: Frames = None, *, quiet: bool = True,
         with_points: bool = False, display_color: str | None = None, sparse: bool = False,
         maps: str | Sequence[str] | None = None, map_size: int | None = None,
         map_dir: str | None = None, map_format: str | None = None,
         map_padding: int | None = None, map_layout: str | None = None,
         uv: str | None = None, tangent_space: str | None = None,
         map_displacement: bool | None = None, geometry: bool = False,
         levels: int | None = None, samples_per_wavelength: float | None = None,
         all_meshes: bool = False, relax_iterations: int | None = None,
         history_start: float | None = None, sublayer: Sequence[str] = (),
         variant: Sequence[str] = (), mask: str | Sequence[str] | None = None) -> str:
    """Bake the wrinkle fields of ``stage`` into the layer ``output`` (.usda, .usdc or
    .usd); returns its path. The options are BakeOptions' and ShotOptions' fields
    (``usdwrinkle bake --help``); ``maps`` is "normal,height,amplitude" or a list."""
    kinds = tuple(part.strip() for part in maps.split(",")) if isinstance(maps, str) \
        else (None if maps is None else tuple(maps))
    options = BakeOptions(with_points=with_points, display_color=display_color,
                          sparse=sparse, maps=kinds, map_size=map_size, map_dir=map_dir,
                          map_format=map_format, map_padding=map_padding,
                          map_layout=map_layout, uv=uv, tangent_space=tangent_space,
                          map_displacement=map_displacement, geometry=geometry,
                          levels=levels, samples_per_wavelength=samples_per_wavelength)
    job = BakeJob(_shot(stage, all_meshes, relax_iterations, history_start, sublayer,
                        variant, mask), output, frames, options, progress=_progress(quiet))
    return job.run().layer
