"""RenderJob: a shot's frames to image files, with every check and warning of a render.

The command line (``usdwrinkle render``), the Python API (``usdwrinkle.api.render``) and
usdview's "Render current frame" all run this job, so a render policy (a check, a
warning) is written once. The job renders here, or on Dask when its options name a
scheduler (``dask``): then farm/client.py checks with the job's ``plan_chunks``, bakes
through ``bake_fields``, and its workers render chunks with farm/worker.render_chunk.
Warnings go to the ``usdwrinkle`` logger (usdwrinkle/process/log.py); errors are
UsdWrinkleError, naming option fields in backquotes.
"""
from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from ..process.errors import UsdWrinkleError
from .options import RenderOptions
from .shot import Progress, Shot, ShotJob, no_progress

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RenderPlan:
    """What a render will do, known before any GL work: the frames and their files."""

    frames: list[float | None]
    outputs: list[str]


@dataclass(frozen=True)
class ChunkPlan:
    """What a farm spreads: each chunk's frame request (render/request.FrameRequest) and
    write options (outputs/writer.WriteOptions), and whether wave fields must be baked
    first."""

    request: Any
    writing: Any
    needs_bake: bool


@dataclass
class RenderResult:
    """What a render did."""

    #: the frames of the shot, and the file of each (written, or kept by ``skip_existing``)
    frames: list[float | None]
    outputs: list[str]
    #: the frames written this run
    written: list[float | None]
    width: int
    height: int
    #: seconds of the frame loop (after the checks and the engine's start; on Dask, from
    #: the cluster's start, its bake included)
    elapsed: float
    #: the meshes drawn from baked wave fields (on Dask: those the workers drew so)
    baked: list[str] = field(default_factory=list)
    #: frames ``skip_existing`` found complete
    skipped: int = 0
    #: per-frame timings (``stats``), else None
    stats: dict[str, Any] | None = None
    #: on Dask (``dask``): the workers and the frames per chunk; 0 when rendered here
    workers: int = 0
    chunk: int = 0


class RenderJob(ShotJob):
    """Render ``frames`` of ``shot`` to ``output`` (a path with a '#' frame placeholder, or
    one file for one frame; the format follows the extension). The rest as ShotJob's (the
    command line prints its header line at ``on_start``)."""

    def __init__(self, shot: Shot, output: str | os.PathLike[str],
                 frames: str | Sequence[float] | None = None,
                 options: RenderOptions | None = None, progress: Progress = no_progress,
                 on_start: Callable[[], None] | None = None):
        super().__init__(shot, output, frames, progress, on_start)
        self.options = options if options is not None else RenderOptions()

    # --- checks -------------------------------------------------------------------------

    def check(self) -> None:
        """What can be refused before the stage is read."""
        from ..outputs.images import check_format
        from ..scene.stage import refuse_overwriting_inputs

        if not self.shot.held:
            refuse_overwriting_inputs(self.shot.path, [self.output])
        check_format(self.output)
        self.options.check()
        self.options.chosen_aovs(str(self.output))
        self.shot.check()

    def prepare(self) -> RenderPlan:
        """Open the stage and check what a render writes, before any GL work: the frames,
        their files (writable, not the stage's inputs), and the stats file. Removes what
        a killed render of these frames left behind."""
        from ..outputs.atomic import check_writable, sweep_dead_temporaries
        from ..scene.stage import refuse_overwriting_inputs
        from .frames import frame_paths

        self.check()
        stage = self.shot.open()
        frames = self.shot.frames(self.frames)
        outputs = frame_paths(self.output, frames)
        stats = self.options.stats
        extra = [stats] if stats else []
        if stats and os.path.realpath(stats) in {os.path.realpath(o) for o in outputs}:
            raise UsdWrinkleError(f"`stats` '{stats}' is the path of a frame this run "
                                  "writes; choose another file for the timings")
        if not self.shot.held:
            refuse_overwriting_inputs(self.shot.path, outputs + extra, stage)
        check_writable(outputs + extra)
        sweep_dead_temporaries(outputs)  # what a killed run of these frames left behind
        return RenderPlan(frames, outputs)

    @property
    def wrinkles(self) -> bool:
        return not self.options.no_wrinkles

    @property
    def uses_baked(self) -> bool:
        """Whether wave fields baked into the stage may be drawn (not recomputed); a render
        without wrinkles needs none."""
        return not (self.options.recompute or self.options.no_wrinkles)

    def mesh_notes(self, stage: Any, wrinkled: Sequence[str]) -> list[str]:
        """The warnings about which meshes get wrinkles (``wrinkled``: the wrinkled mesh
        paths): controls authored without WrinkleAPI, a displaced-geometry bake, no mesh to
        wrinkle. The serial render and the farm's client both say them."""
        from ..frameloop import NO_WRINKLED_MESH, unapplied_note
        from ..scene.baked import geometry_bake

        notes = []
        all_meshes = self.shot.options.all_meshes
        unapplied = None if all_meshes or not self.wrinkles else unapplied_note(stage)
        if unapplied:
            notes.append(unapplied)
        found = geometry_bake(stage)
        if found is not None and self.wrinkles and not wrinkled:
            notes.append("the stage holds usdwrinkle's displaced geometry, whose wrinkles are "
                         "in its meshes: render with `no_wrinkles` (`all_meshes` would "
                         f"wrinkle them a second time) ({found[0]})")
        if not wrinkled and self.wrinkles and found is None and unapplied is None:
            notes.append("the stage has no Mesh to wrinkle; rendering without wrinkles"
                         if all_meshes else NO_WRINKLED_MESH)
        return notes

    def frame_notes(self, stage: Any, frames: list[float | None]) -> list[str]:
        """Warnings about the frames: those outside what a displaced-geometry bake holds."""

        from ..scene.baked import geometry_bake

        found = geometry_bake(stage)
        if found is None:
            return []
        layer, first, last = found
        if first is None or last is None:
            return []
        outside = [f for f in frames if f is not None and not first <= f <= last]
        if not outside:
            return []
        return [f"{len(outside)} frame(s) lie outside the frames the displaced geometry was "
                f"baked for ({first:g}..{last:g}), from {outside[0]:g}: they show its nearest "
                f"baked frame ({layer})"]

    def _engine_notes(self, engine: Any, frames: list[float | None]) -> None:
        from ..process.timecode import format_frame
        from ..scene.baked import holds_bake
        from ..scene.stage import outside_range_note

        computed = self.wrinkles and any(path not in engine.baked
                                         for path in engine.wrinkled_paths)
        options = self.shot.options
        from_start = computed and self.frames is not None and options.history_start is None
        note = outside_range_note(engine.stage, frames) if from_start else None
        if note:
            _log.warning(note)  # a preroll from the shot's start (not for baked frames)
        if self.uses_baked and holds_bake(engine.stage):
            # a farm chunk that renders a bake but finds wrinkled meshes without baked
            # fields computes them itself, with a preroll: what the farm's bake avoids
            unbaked = [path for path in engine.wrinkled_paths if path not in engine.baked]
            if unbaked:
                start = engine.history_start()
                preroll = ""
                if start is not None:
                    preroll = f", with a phase-history preroll from frame {format_frame(start)}"
                _log.warning(f"the stage holds a usdwrinkle bake, but {len(unbaked)} wrinkled "
                             f"mesh(es) have no baked wave fields in it; computing them "
                             f"here{preroll} (other machines may compute them slightly "
                             "differently: bake with the options the render uses, e.g. "
                             f"`all_meshes`) ({unbaked[0]})")
        for note in self.mesh_notes(engine.stage, engine.wrinkled_paths):
            _log.warning(note)
        for note in self.frame_notes(engine.stage, frames):
            _log.warning(note)
        mapped = [path for path in engine.wrinkled_paths
                  if engine.meshes[path].material.wrinkle_maps]
        if mapped and self.wrinkles:
            _log.warning(f"{len(mapped)} mesh(es) have baked wrinkle maps in their material "
                         "and are drawn with wrinkles too, so their wrinkles show twice; "
                         f"pass `no_wrinkles` to draw the maps alone ({mapped[0]})")

    def plan_chunks(self, plan: RenderPlan) -> ChunkPlan:
        """What a farm needs before it spreads ``plan`` in chunks, checked without a GL
        context: the camera (a missing one fails before any worker starts), the warnings
        of a serial render, the image size, and whether the stage's own baked wave fields
        cover every frame (else the farm bakes them once)."""
        from ..engine import image_size
        from ..scene.stage import StageSceneDelegate

        stage = self.shot.open()
        options = self.shot.options
        scene = StageSceneDelegate(stage, all_meshes=options.all_meshes,
                                   relax_iterations=options.relax_iterations,
                                   use_baked=self.uses_baked)
        scene.camera(self.options.camera)
        wrinkled = [path for path, record in scene.meshes.items() if record.wrinkled]
        for note in self.mesh_notes(stage, wrinkled) + self.frame_notes(stage, plan.frames):
            _log.warning(note)
        needs_bake = False
        if self.wrinkles:
            for path in wrinkled:
                source = None if self.options.recompute else scene.baked.get(path)
                if source is None or not all(source.covers(f) for f in plan.frames):
                    needs_bake = True
        width, height = image_size(scene, self.options.camera, self.options.width,
                                   self.options.height, plan.frames[0])
        return ChunkPlan(self.frame_request(width, height),
                         self.write_options(width, height, chunked=True), needs_bake)

    def check_output(self, path: str) -> None:
        """Refuse a further file the job writes (a farm's bake) that is one of the stage's
        inputs."""
        from ..scene.stage import refuse_overwriting_inputs

        if not self.shot.held:
            refuse_overwriting_inputs(self.shot.path, [path], self.shot.open())

    def chunk_engine(self, stage_path: str, baked: bool) -> Any:
        """The engine.EngineOptions a chunk renders with: ``stage_path`` is the stage, or the
        farm's bake of it (``baked``: then the bake's layer carries the sublayers and
        variant selections, and only the population mask is applied again)."""
        import dataclasses

        shot_options = self.shot.options
        composition = (dataclasses.replace(shot_options, sublayer=(), variant=()) if baked
                       else shot_options).composition()
        return dataclasses.replace(
            self.shot.engine_options(self.options.camera, use_baked=self.wrinkles),
            stage=os.path.abspath(stage_path), composition=composition or None)

    # --- the work -----------------------------------------------------------------------

    def frame_request(self, width: int, height: int) -> Any:
        """The render/request.FrameRequest of every frame, at the resolved size."""
        return self.options.frame_request(width, height, str(self.output))

    def write_options(self, width: int, height: int, chunked: bool = False) -> Any:
        """The frame loop's outputs/writer.WriteOptions at the resolved size (``chunked``:
        for a farm's worker process, one of several on its node: one writer thread unless
        asked)."""
        from ..outputs.writer import WriteOptions, default_threads, exr_threads, frames_in_flight

        o = self.options
        exr = str(self.output).lower().endswith(".exr")
        threads = o.write_threads
        if threads is None:
            threads = 1 if chunked else default_threads(exr)
        # what a frame holds until it is written: at most 32 bytes a pixel (an EXR's
        # colour, normals, depth and wrinkle fields)
        in_flight = frames_in_flight(threads, 32 * width * height)
        return WriteOptions(threads, in_flight, o.exr_compression, exr_threads(chunked))

    def bake_fields(self, layer: str, frame_spec: str | None) -> None:
        """Bake the shot's wave fields to ``layer`` (a farm's bake before its chunks)."""
        from .bake import BakeJob

        BakeJob(self.shot, layer, frame_spec, progress=self.progress).run()

    def start_engine(self, ctx: Any = None) -> Any:
        """The engine this job renders with (``run(engine=...)``): the shot's, with the
        job's camera, baked fields and profiling."""
        return self.shot.start_engine(self.options.camera, use_baked=self.uses_baked,
                                      profile=bool(self.options.stats and
                                                   self.options.stats_passes),
                                      progress=self.progress, ctx=ctx)

    def run(self, ctx: Any = None, engine: Any = None) -> RenderResult:
        """Check, start the engine, render every frame, here or on Dask (``dask``);
        ``ctx``: a moderngl context to share (None: the process's own). ``engine``: one
        that ``start_engine`` of a job of the same shot and options made, kept after the
        run (its phase history too: usdview writes one frame as EXR and PNG with one
        engine); None: the job starts its own and releases it."""
        if self.options.dask is not None:
            return self._run_on_dask()
        if self.options.chunk is not None or self.options.workers is not None:
            _log.warning("`chunk` and `workers` apply to `dask` only; ignored")
        return self._run_here(ctx, engine)

    def _run_on_dask(self) -> RenderResult:
        from ..farm.client import FarmRender, render_on_dask
        from .shot import frame_spec_of

        plan = self.prepare()  # every refusal comes first
        o = self.options
        if o.stats:
            _log.warning("`stats` applies to a serial render; ignored with `dask`")
        spec = None if self.frames is None else frame_spec_of(self.frames)
        assert o.dask is not None
        farm = render_on_dask(FarmRender(self, plan, spec, o.dask, o.workers, o.chunk,
                                         self.progress, self.say, self.on_start))
        return RenderResult(plan.frames, plan.outputs, farm.written, farm.width, farm.height,
                            farm.elapsed, farm.baked, farm.skipped, None, farm.workers,
                            farm.chunk)

    def _run_here(self, ctx: Any, engine: Any) -> RenderResult:
        from ..frameloop import render_frames
        from ..images.aovs import exr_channels
        from ..images.imagefiles import is_complete_image

        plan = self.prepare()
        own = engine is None
        if own:
            engine = self.start_engine(ctx)
        try:
            engine.check_baked(plan.frames)
            self._engine_notes(engine, plan.frames)
            width, height = engine.resolution(self.options.width, self.options.height,
                                              plan.frames[0])
            request = self.frame_request(width, height)
            engine.check_relax_work(plan.frames, self.wrinkles)  # a refusal: before start
            if self.on_start is not None:
                self.on_start()
            started = time.perf_counter()
            stats: dict[str, Any] | None = {} if self.options.stats else None
            channels = exr_channels(request.layout.aovs)
            skip = (lambda path: is_complete_image(path, width, height, channels)) \
                if self.options.skip_existing else (lambda path: False)
            written = render_frames(engine, request, self.write_options(width, height),
                                    plan.frames, plan.outputs, skip=skip,
                                    progress=lambda items: self.progress(items, "render"),
                                    stats=stats)
            if stats is not None and self.options.stats:
                write_stats(self.options.stats, stats)
            skipped = len(plan.frames) - len(written) if self.options.skip_existing else 0
            return RenderResult(plan.frames, plan.outputs, written, width, height,
                                time.perf_counter() - started, list(engine.baked_paths),
                                skipped, stats)
        finally:
            if own:
                engine.release()


def write_stats(path: str, stats: dict[str, Any]) -> None:
    """The timings as JSON, written atomically."""
    import json

    from ..outputs.atomic import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as handle:
        json.dump(stats, handle, indent=1)
