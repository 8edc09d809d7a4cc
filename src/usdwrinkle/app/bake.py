"""BakeJob: a shot's wrinkle fields into a USD layer (and its maps and displaced geometry),
with every check and warning of a bake.

The command line (``usdwrinkle bake``), the Python API (``usdwrinkle.api.bake``) and the
farm's client (which bakes once before it renders chunks) run this job. A bake is one
process on purpose: each frame's phases start from the previous frame's (the phase
history), so its frames cannot be computed apart.
"""
from __future__ import annotations

import dataclasses
import logging
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from ..process.errors import UsdWrinkleError
from .options import GEOMETRY_FIELDS, MAP_FIELDS, BakeOptions
from .shot import Progress, Shot, ShotJob, frame_spec_of, no_progress

_log = logging.getLogger(__name__)


@dataclass
class BakeResult:
    """What a bake did."""

    #: the layer written
    layer: str
    frames: list[float | None]
    #: how many meshes the layer holds
    count: int
    #: the wrinkled meshes, each with its width's summary (scene/params.width_summary)
    meshes: dict[str, str]
    #: seconds of the frame work (after the checks and the engine's start)
    elapsed: float


def _given(options: BakeOptions, fields: dict[str, str]) -> dict[str, Any]:
    """{target field: value} of the options in ``fields`` (option -> target) given."""
    return {target: getattr(options, name) for name, target in fields.items()
            if getattr(options, name) is not None}


def _refuse_without(options: BakeOptions, fields: dict[str, str], needed: str) -> None:
    given = [f"`{name}`" for name in fields if getattr(options, name) is not None]
    if given:
        raise UsdWrinkleError(f"{', '.join(given)} need `{needed}`")


def map_options(options: BakeOptions) -> Any:
    """maps/options.MapOptions of ``options`` (None without maps); what is not given keeps
    MapOptions' default."""
    from ..maps.options import MapOptions

    if options.maps is None:
        _refuse_without(options, MAP_FIELDS, "maps")
        return None
    from ..maps.bake import check_map_options
    from ..maps.files import parse_map_kinds

    if options.map_layout == "islands" and options.uv is not None:
        raise UsdWrinkleError("`uv` names the texture coordinates of `map_layout` asset; "
                              "`map_layout` islands lays the maps out in their own")
    maps = dataclasses.replace(MapOptions(), kinds=parse_map_kinds(",".join(options.maps)),
                               uv_named=options.uv is not None,
                               **_given(options, MAP_FIELDS))
    check_map_options(maps)
    return maps


def geometry_options(options: BakeOptions) -> Any:
    """geometry/options.GeometryOptions of ``options`` (None without geometry)."""
    from ..geometry.options import GeometryOptions

    if not options.geometry:
        _refuse_without(options, GEOMETRY_FIELDS, "geometry")
        return None
    from ..geometry.bake import check_geometry_options

    geometry = dataclasses.replace(GeometryOptions(), **_given(options, GEOMETRY_FIELDS))
    check_geometry_options(geometry)
    return geometry


def check_map_folder(folder: str, layer: str | None = None) -> None:
    """Refuse a map folder that cannot be written, before any work; one that does not
    exist yet is made only when the maps are committed (a failed bake leaves none). The
    folder may not be the layer's own path: the maps would be moved there first and the
    layer then fail to replace a folder, leaving a partial map set."""
    from ..outputs.atomic import check_writable

    if layer is not None and os.path.realpath(folder) == os.path.realpath(layer):
        raise UsdWrinkleError(f"`map_dir` '{folder}' is the layer's own path; the maps go in "
                              "a folder of their own (default: LAYER_maps beside the layer)")
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise UsdWrinkleError(f"cannot write maps to '{folder}': it is a file, not a folder")
    probe = folder if os.path.isdir(folder) else os.path.dirname(os.path.abspath(folder))
    check_writable([os.path.join(probe, ".usdwrinkle-maps-probe")])


class BakeJob(ShotJob):
    """Bake ``frames`` of ``shot`` into the layer ``output`` (.usda, .usdc or .usd). The
    rest as ShotJob's."""

    def __init__(self, shot: Shot, output: str | os.PathLike[str],
                 frames: str | Sequence[float] | None = None,
                 options: BakeOptions | None = None, progress: Progress = no_progress,
                 on_start: Callable[[], None] | None = None):
        super().__init__(shot, output, frames, progress, on_start)
        self.options = options if options is not None else BakeOptions()

    def check(self) -> tuple[Any, Any]:
        """What can be refused before the stage is read; returns (maps, geometry)."""
        from ..outputs.layers import check_layer_path
        from ..scene.stage import refuse_overwriting_inputs

        self.shot.check()
        maps = map_options(self.options)
        geometry = geometry_options(self.options)
        if not self.shot.held:
            refuse_overwriting_inputs(self.shot.path, [self.output])
        check_layer_path(self.output)
        return maps, geometry

    def run(self, ctx: Any = None) -> BakeResult:
        from ..frameloop import BakeRequest, bake_layer
        from ..outputs.atomic import check_writable
        from ..scene.params import width_summary
        from ..scene.stage import outside_range_note, refuse_overwriting_inputs

        maps, geometry = self.check()
        # everything that can be refused without the GPU is checked first
        stage = self.shot.open()
        if not self.shot.held:
            refuse_overwriting_inputs(self.shot.path, [self.output], stage)
        check_writable([self.output])
        from ..outputs.atomic import sweep_dead_temporaries

        sweep_dead_temporaries([self.output])  # what a killed bake of this layer left
        if maps is not None:
            check_map_folder(maps.folder_for(self.output), self.output)
        frames = self.shot.frames(self.frames)
        # a bake always computes: fields already baked into the input are not its input
        engine = self.shot.start_engine(use_baked=False, progress=self.progress, ctx=ctx)
        if self.frames is not None and self.shot.options.history_start is None and \
                engine.wrinkled_paths and (note := outside_range_note(stage, frames)):
            _log.warning(note)
        try:
            if maps is not None:
                from ..maps.bake import check_map_options

                check_map_options(maps, engine.max_texture_size)
            engine.check_relax_work(frames)  # a refusal: before the start
            if self.on_start is not None:
                self.on_start()
            started = time.perf_counter()
            o = self.options
            spec = None if self.frames is None else frame_spec_of(self.frames)
            request = BakeRequest(self.shot.path, self.output, tuple(frames), spec,
                                  with_points=o.with_points, display_color=o.display_color,
                                  sparse=o.sparse, maps=maps, geometry=geometry)
            count = bake_layer(engine, request, progress=lambda items: self.progress(items, "bake"),
                       survey_progress=lambda items: self.progress(items, "survey"))
            meshes = {path: width_summary(record.params)["text"]
                      for path, record in sorted(engine.meshes.items()) if record.wrinkled}
            return BakeResult(self.output, frames, count, meshes,
                              time.perf_counter() - started)
        finally:
            engine.release()


def bake_frame_into(shot: Shot, layer: Any, frame: float,
                    pick: Callable[[list[str]], list[str]] | None = None,
                    display_color: str | None = "amplitude", ctx: Any = None) -> list[str]:
    """Bake one frame of ``shot``'s wrinkle primvars (and a displayColor ramp of
    ``display_color``) into ``layer``, an open Sdf.Layer (usdview's session layer: the
    edit shows at once). ``pick(wrinkled paths)`` chooses the meshes (None: all). Returns
    the baked mesh paths, [] when no mesh has WrinkleAPI (a warning says so)."""
    from ..outputs.layers import LayerBaker, LayerOptions
    from ..outputs.sink import BakeScene
    from ..scene.overrides import read_overrides
    from .shot import at_frame

    engine = shot.start_engine(ctx=ctx)
    try:
        targets = list(engine.wrinkled_paths)
        if pick is not None:
            targets = pick(targets)
        if not targets:
            _log.warning("no mesh on this stage has WrinkleAPI applied")
            return []
        with at_frame(frame):
            engine.compute_frame(frame)
            stage = engine.stage
            records = {path: engine.meshes[path] for path in targets}
            facts = read_overrides(stage, stage.GetRootLayer().realPath or "", records,
                                   (frame,))
            scene = BakeScene(facts, "", (frame,), records, engine.meshes)
            baker = LayerBaker(scene, LayerOptions(display_color=display_color))
            baker.begin(layer)
            baker.add_frame(frame, {path: engine.read_fields(path) for path in targets}, {})
        return targets
    finally:
        engine.release()
