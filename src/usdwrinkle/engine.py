"""The one code path: scene delegate -> render delegate -> passes.

Rendering a frame and baking a frame both call :meth:`WrinkleEngine.compute_frame`;
rendering then draws, baking reads back what the GPU computed.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from .images.aovs import ImageLayout
from .method.contract import WrinkleFields
from .method.history import WaveHistory, cache_capacity, on_grid, reads_index
from .process.errors import UsdWrinkleError
from .process.limits import MAX_HISTORY_FRAMES, MAX_RELAX_WORK
from .render.buffers import AOVS
from .render.context import create_context, current, in_own_context
from .render.delegate import RenderDelegate, RenderPass
from .render.fields import STATE_BYTES_PER_POINT
from .render.request import FrameRequest
from .scene.dirty import DirtyBits
from .scene.stage import StageSceneDelegate

AOV_NAMES = tuple(AOVS)
#: the image aspect of the automatic framing (a stage without a camera)
FRAMING_ASPECT = 16.0 / 9.0


@dataclass(frozen=True)
class EngineOptions:
    """What a WrinkleEngine is made with (picklable: a farm task carries it)."""

    stage: str
    all_meshes: bool = False
    relax_iterations: int | None = None
    camera: str | None = None
    history_start: float | None = None
    use_baked: bool = True
    #: time every pass (GL timer queries, or the wall clock between glFinish calls)
    profile: bool = False
    #: how the stage is composed (scene/composition.Composition; None: as it is): a farm
    #: worker opens the stage with it
    composition: object | None = None

    def create(self, stage: Any = None, preroll_progress: Any = None, ctx: Any = None,
               history_cache: int | None = None) -> Any:
        """The engine; ``stage``: an already opened Usd.Stage of ``self.stage``;
        ``preroll_progress`` wraps the list of preroll frames (a progress bar); ``ctx``: a
        moderngl context to share (None: the process's own)."""
        if stage is None and self.composition:
            from .scene.stage import open_stage

            stage = open_stage(self.stage, self.composition)

        kwargs = {} if preroll_progress is None else {"preroll_progress": preroll_progress}
        if ctx is not None:
            kwargs["ctx"] = ctx
        if history_cache is not None:
            kwargs["history_cache"] = history_cache
        return WrinkleEngine(stage if stage is not None else self.stage,
                             all_meshes=self.all_meshes,
                             relax_iterations=self.relax_iterations, camera=self.camera,
                             history_start=self.history_start, use_baked=self.use_baked,
                             profile=self.profile, **kwargs)


class WrinkleEngine:
    """Renders or computes wrinkles for one stage.

    Parameters
    ----------
    stage : str or Usd.Stage
    all_meshes : bool
        Wrinkle every Mesh, as if WrinkleAPI were applied.
    relax_iterations : int or None
        Override ``wrinkle:relaxIterations`` on every mesh.
    camera : str or None
        ``--camera``: prim path or name.
    profile : bool
        Time every pass (``last_timings``): GL timer queries on a GPU, the wall clock
        between glFinish calls on a software rasteriser.
    history_start : float or None
        First frame of the shot's phase history (default: the stage's start time code).
        Every chunk of a shot must use the same value.
    use_baked : bool
        Draw the baked wave fields of meshes that hold them (scene/baked.py): no crush,
        no relax and no preroll for those meshes. False recomputes everything.
    preroll_progress : callable or None
        Wraps the list of preroll frames (the CLI's progress bar).
    history_cache : int or None
        How many grid frames' wave states to keep (default: HISTORY_CACHE_FRAMES, fewer
        where they would take more than HISTORY_CACHE_BYTES of GPU memory).
    """

    def __init__(self, stage, all_meshes: bool = False, relax_iterations: int | None = None,
                 camera: str | None = None, ctx=None, profile: bool = False,
                 history_start: float | None = None, use_baked: bool = True,
                 preroll_progress=None, history_cache: int | None = None):
        self.scene = StageSceneDelegate(stage, all_meshes=all_meshes,
                                        relax_iterations=relax_iterations, use_baked=use_baked)
        self.camera = camera
        self.scene.camera(camera)  # a missing camera fails before any GPU work
        ctx = ctx if ctx is not None else create_context()
        self._dirty = {}
        with current(ctx):
            self.render_delegate = RenderDelegate(ctx, profile=profile)
            self.render_pass = RenderPass(self.render_delegate)
            for path in self.scene.meshes:
                self.render_delegate.create_rprim(path)
                self._dirty[path] = DirtyBits.ALL
        self.last_timings: dict[str, float] = {}
        self._history_start = history_start
        #: the wave states of grid frames this engine keeps (method/history.py)
        self.history = WaveHistory(history_cache if history_cache is not None else
                                   cache_capacity(self._state_bytes()))
        #: frames computed (drawn or not) and of them preroll steps, since creation
        self._computed = 0
        self._prerolled = 0
        #: wraps the list of preroll frames (the CLI shows a progress bar)
        self.preroll_progress = preroll_progress or (lambda frames: frames)

    @property
    def debug(self) -> EngineDebug:
        """What tests and benchmarks look at inside (EngineDebug). Made on each use: an
        EngineDebug kept on the engine would be a reference cycle, and a dropped engine (its
        scene, its stage and the stage's layers) would then live until a GC pass, so that
        the next open of a changed file in this process got the old layer back."""
        return EngineDebug(self)

    def _state_bytes(self) -> int:
        """GPU bytes of one grid frame's wave state, all meshes (render/fields.py)."""
        return sum(len(record.rest_points) for record in self.scene.meshes.values()) * \
            STATE_BYTES_PER_POINT

    @property
    def wrinkled_paths(self) -> list[str]:
        return [p for p, r in self.scene.meshes.items() if r.wrinkled]

    @property
    def baked_paths(self) -> list[str]:
        """The wrinkled meshes drawn from baked wave fields."""
        return list(self.scene.baked)

    # -- what the shot's loops and the writers may ask (nothing outside this file reaches
    # into the scene or the render delegate) ------------------------------------------

    @property
    def stage(self):
        """The Usd.Stage the scene delegate reads."""
        return self.scene.stage

    @property
    def meshes(self) -> dict:
        """Path -> MeshRecord of every mesh the scene delegate holds."""
        return self.scene.meshes

    @property
    def baked(self) -> dict:
        """Path -> the baked wave fields the scene found (scene/baked.py)."""
        return self.scene.baked

    def check_baked(self, frames: list[float]) -> None:
        """Refuse frames outside the baked range of a mesh drawn from its bake."""
        self.scene.check_baked(frames)

    def corner_primvar(self, path: str, name: str):
        """A primvar of ``path`` per triangle corner ([3t + c]), or None (scene side)."""
        return self.scene.corner_primvar(path, name)

    @property
    def ctx(self):
        """The moderngl context the passes run in."""
        return self.render_delegate.ctx

    @property
    def max_texture_size(self) -> int:
        return self.render_delegate.max_texture_size

    def mesh_resources(self, path: str):
        """The GPU tables of ``path`` after the last computed frame (render/resources.py):
        the one way out of the GPU besides read_fields, for the passes of the bake
        outputs (maps, geometry) that run on the same tables."""
        return self.render_delegate.rprims[path].resources

    @in_own_context
    def set_display_colors(self, path: str, colors) -> None:
        """Draw ``path`` in ``colors`` per point ((n, 3) linear RGB) instead of its
        material's colour (the paint window's display modes), or as its material again
        (None). Held until changed; a mesh not computed yet takes it at its next frame."""
        resources = self.mesh_resources(path)
        if resources is None:
            return
        if colors is None:
            resources.set_display_colors(None)
            return
        colors = np.asarray(colors, np.float32)
        resources.set_display_colors(colors[self.meshes[path].topology.triangles])

    @property
    def rprim_paths(self) -> list[str]:
        """The meshes that hold GPU resources now (Hydra's rprims)."""
        return list(self.render_delegate.rprims)

    def sample(self, frame: float | None, aspect: float):
        """The scene's FrameRecord at ``frame`` through this engine's camera (what
        compute_frame syncs to), without computing anything."""
        return self.scene.sample(frame, aspect, self.camera)

    def camera_aspect(self, frame: float | None) -> float | None:
        """This engine's camera's aspect ratio at ``frame`` (None: no camera)."""
        return self.scene.camera_aspect(self.camera, frame)

    def process_changes(self) -> tuple[dict[str, int], list[str], list[str]]:
        """The stage's edits since the last call, as the scene reads them ({path: dirty
        bits}, added, removed): what pull_changes turns into dirty bits. Consumes them."""
        return self.scene.process_changes()

    def resolution(self, width: int, height: int | None,
                   frame: float | None) -> tuple[int, int]:
        """Fill in ``--height`` from the camera's aspect ratio (image_size)."""
        return image_size(self.scene, self.camera, width, height, frame)

    def check_relax_work(self, frames: list[float], wrinkles: bool = True) -> None:
        """Refuse a run whose relax iterations times computed frames (preroll included)
        exceed MAX_RELAX_WORK: each is within its own limit, but not their product."""
        iterations = max((self.scene.meshes[path].params.relax_iterations
                          for path in self.wrinkled_paths if path not in self.scene.baked),
                         default=0)
        finite = [f for f in frames if f is not None]
        if not wrinkles or not iterations or not finite:
            return
        start = self.history_start()
        preroll = max(0.0, math.ceil(min(finite) - start)) if start is not None else 0.0
        if preroll > MAX_HISTORY_FRAMES:
            return  # the phase history refuses it, with its own bound (_history_plan)
        computed = len(frames) + preroll
        if iterations * computed > MAX_RELAX_WORK:
            raise UsdWrinkleError(
                f"this run would relax {iterations:,} iterations x {computed:,.0f} frames "
                f"({preroll:,.0f} of them phase-history preroll) = "
                f"{iterations * computed:,.0f} iterations; at most {MAX_RELAX_WORK:,} are "
                "accepted (lower wrinkle:relaxIterations or `relax_iterations`, render fewer "
                "frames, or pass `history_start` nearer the first frame)")

    # -- phase history (method/history.py: the wave states of grid frames, as values) ----------
    def history_start(self) -> float | None:
        """The frame where the shot's phase history starts (None: every frame cold)."""
        if self._history_start is not None:
            return self._history_start
        return self.scene.first_frame()

    def _history_plan(self, frame: float | None) -> tuple[list[int], int | None]:
        """The grid frames (as indices: frame - start) to compute before ``frame``, and
        the index of the kept state the first of them (or ``frame`` itself) reads (None:
        a cold start). Plans only: the caller applies it.

        The history runs on the integer grid start, start+1, ... A frame starts from the
        state of the grid frame before it (a sub-frame from the grid frame below it), so
        its phases are a deterministic function of the shot, whichever frames a run
        renders: a farm chunk that starts at frame f replays start..f-1 (compute only, no
        draw), and a frame whose state is kept replays nothing.
        """
        start = self.history_start()
        if start is None or frame is None:
            return [], None
        needed = reads_index(frame, start)
        if needed is None:
            return [], None
        if needed in self.history:
            return [], needed
        base = self.history.nearest_below(needed)
        first = 0 if base is None else base + 1
        if needed - first + 1 > MAX_HISTORY_FRAMES:
            raise UsdWrinkleError(
                f"frame {frame:g} is {frame - (start + first):,.0f} frames after the phase "
                f"history's start {start + first:g}; more than {MAX_HISTORY_FRAMES:,} frames "
                "of history are refused (pass `history_start` nearer, or bake the shot)")
        return list(range(first, needed + 1)), base

    def _compute_only(self, frame: float, write: int, read: int | None,
                      wrinkles: bool) -> None:
        """A preroll step: the meshes that have no baked fields, compute only (never drawn:
        Step.drawn)."""
        self._sync(self.scene.sample_meshes(frame, with_baked=False))
        self.render_pass.compute(wrinkles, None, write, read, skip=frozenset(self.scene.baked),
                                 drawn=False)

    @in_own_context
    def pull_changes(self) -> None:
        """Turn the stage's edits since the last frame into dirty bits (scene/changes.py):
        rprims for meshes that appeared or went, and the parts of each mesh to sync. An
        edit of topology or wrinkle parameters restarts the phase history (the shot is
        replayed from its start, so the frame is the one a fresh run would give)."""
        bits, added, removed = self.scene.process_changes()
        for path in removed:
            self.render_delegate.destroy_rprim(path)
            self._dirty.pop(path, None)
        for path in added:
            self.render_delegate.create_rprim(path)
            self._dirty[path] = DirtyBits.ALL
        for path, value in bits.items():
            self._dirty[path] = self._dirty.get(path, DirtyBits.CLEAN) | value
        if removed or any(value & (DirtyBits.DIRTY_TOPOLOGY | DirtyBits.DIRTY_PRIMVAR)
                          for value in self._dirty.values()):
            self.history.clear()

    def _sync(self, meshes: dict) -> None:
        """Sync every rprim to the scene's sample ``meshes`` (path -> MeshFrame)."""
        for path, mesh in self.render_delegate.rprims.items():
            # a new frame dirties the time-varying state; edits add their own bits
            self._dirty[path] = mesh.sync(self.scene, self._dirty[path] | DirtyBits.FRAME,
                                          meshes.get(path))

    @in_own_context
    def compute_frame(self, frame: float | None, aspect: float | None = None,
                      wrinkles: bool = True):
        """Sync every rprim to ``frame`` and run skin, crush and relax. Returns the FrameRecord.

        With wrinkles, the frame starts from the kept wave state of the grid frame before
        it; grid frames of the shot that this engine does not keep are computed first
        (see :meth:`_history_plan`), so that the result does not depend on which frames
        were rendered before, nor on how often. A grid frame's own state is then kept
        (:meth:`advance`); the state it read is never changed.
        """
        self.pull_changes()
        read: int | None = None
        steps: list[int] = []
        start = self.history_start()
        # meshes drawn from a bake need no history; the others replay the shot's start
        needs_history = any(p not in self.scene.baked for p in self.wrinkled_paths)
        if wrinkles and needs_history:
            steps, base = self._history_plan(frame)
            read = None if base is None else self.history.slot(base)
            # the progress bar counts frames; the history keeps grid indices
            for step, index in zip(self.preroll_progress([start + i for i in steps]), steps,
                                   strict=True):
                write = self.history.work_slot(keep=read)
                self._compute_only(step, write, read, wrinkles)
                self.advance(index, write)
                read = write
        profile = self.render_delegate.profile
        started = time.perf_counter()
        if aspect is None:
            aspect = FRAMING_ASPECT
        record = self.scene.sample(frame, aspect, self.camera)
        read_at = time.perf_counter()
        self._sync(record.meshes)
        synced = time.perf_counter()
        # the USD read and the sync are CPU work: timed always (render --stats)
        self.last_timings = {"usd_read": (read_at - started) * 1e3,
                             "sync": (synced - read_at) * 1e3}
        if profile:
            self.last_timings["preroll_frames"] = float(len(steps))
        self._prerolled += len(steps)
        write = self.history.work_slot(keep=read)
        self.render_pass.compute(wrinkles, self.last_timings, write, read)
        self._computed += 1 + len(steps)
        if wrinkles and needs_history and on_grid(frame, start):
            self.advance(int(frame - start), write)
        return record

    @in_own_context
    def advance(self, index: int, slot: int) -> None:
        """Keep the wave state just computed into ``slot`` as grid frame ``index``'s (the
        chain advances to it): the explicit step after computing a grid frame."""
        self.history.commit(index, slot)
        keep = self.history.slots
        for mesh in self.render_delegate.rprims.values():
            if mesh.resources is not None and mesh.resources.waves.slots > keep:
                mesh.resources.waves.release_slots(keep)

    @in_own_context
    def render(self, frame: float | None, request: FrameRequest):
        """Compute and draw ``frame`` as ``request`` says (render/request.py); returns what
        its layout reads back: {aov name: RenderBuffer}, the frame as an image file stores
        it (render.resolve.ResolvedImage), or with ``request.readback_ring`` > 1 a
        render.resolve.PendingImage, whose ``start()`` copies it out: ask for it after the
        next frame is queued, and the GPU computes that frame meanwhile
        (frameloop.render_frames)."""
        record = self.compute_frame(frame, request.aspect, request.wrinkles)
        timings: dict = {}
        result = self.render_pass.execute(request, record.camera, record.lights, timings)
        self.last_timings.update(timings)
        return result

    @in_own_context
    def render_frame(self, frame: float | None, width: int, height: int, wrinkles: bool = True,
                     samples: int = 4, aovs: tuple = AOV_NAMES, shade_samples: bool = True,
                     relief: bool = False):
        """``render`` at ``width`` x ``height``, read back as float AOVs: returns
        {aov name: RenderBuffer} of ``aovs`` (the tests' and benchmarks' shorthand)."""
        return self.render(frame, FrameRequest(width, height, samples, wrinkles, shade_samples,
                                               relief, ImageLayout("aovs", tuple(aovs))))

    @in_own_context
    def preview_params(self, path: str, **changes) -> None:
        """Draw ``path`` with some wrinkle parameters changed (WrinkleParams fields: q,
        width, amplitude_scale, slack) without an edit of the stage, and without dropping
        the kept wave states: a live preview (the paint window while a stroke or a slider
        moves), exact for the frame's own crush, approximate in its history. The next edit
        of the stage's wrinkle parameters replaces it and restarts the history."""
        from dataclasses import replace

        from .render.resources import vec4

        mesh = self.render_delegate.rprims[path]
        if mesh.resources is None:  # not synced yet: the first frame reads the stage
            return
        record = mesh.resources.record
        params = replace(record.params, **changes)
        mesh.resources.record = replace(record, params=params)
        if "q" in changes or "width" in changes:
            mesh.resources.q_width.write(vec4(params.q, params.width))

    def frame_range(self) -> list[float | None]:
        """The stage's authored start..end frames, or [None] (its default time) when it
        has none."""
        return self.scene.frame_range()

    def is_posed(self, path: str) -> bool:
        """Whether ``path`` has been posed at some frame (compute_frame ran for it)."""
        mesh = self.render_delegate.rprims.get(path)
        return mesh is not None and mesh.frame is not None

    def local_to_world(self, path: str) -> np.ndarray:
        """``path``'s local-to-world transform at the last computed frame ((4, 4) float64,
        USD's row vectors)."""
        return np.asarray(self.render_delegate.rprims[path].frame.local_to_world, np.float64)

    @in_own_context
    def posed_points(self, path: str) -> np.ndarray:
        """``path``'s posed points at the last computed frame, world space, (n, 3)
        float64 (a viewer's picking)."""
        mesh = self.render_delegate.rprims[path]
        local = np.asarray(mesh.resources.posed_points.read(), np.float64)[:, :3]
        return local @ mesh.frame.local_to_world[:3, :3] + mesh.frame.local_to_world[3, :3]

    def visible_paths(self) -> list[str]:
        """The meshes drawn at the last computed frame."""
        return [path for path, mesh in self.render_delegate.rprims.items()
                if mesh.resources is not None and mesh.frame is not None and
                mesh.frame.visible and mesh.resources.num_triangles]

    @in_own_context
    def read_fields(self, path: str) -> WrinkleFields:
        """Per-vertex fields of ``path`` as computed for the last frame (numpy arrays;
        ``.arrays()`` gives them by name)."""
        return self.mesh_resources(path).read_fields()

    @in_own_context
    def read_shading_normals(self, path: str):
        """The shading normals of ``path`` at the last frame: (NormalPlan, (entries, 3)
        float32 local normals) (scene/normals.py)."""
        res = self.mesh_resources(path)
        return res.normal_plan, res.read_shading_normals()

    @in_own_context
    def release(self) -> None:
        self.scene.tracker.revoke()
        self.render_delegate.release()


def image_size(scene, camera: str | None, width: int, height: int | None,
               frame: float | None) -> tuple[int, int]:
    """``--width`` and ``--height``, the height from the camera's aspect ratio when not
    given (16:9 without a camera), rounded down as usdrecord does. Needs only the scene
    delegate, no GL."""
    if height:
        return width, height
    aspect = scene.camera_aspect(camera, frame) or FRAMING_ASPECT
    # usdrecord: static_cast<size_t>(float(width) / aspectRatio), in single precision
    return width, max(1, int(np.float32(width) / np.float32(aspect)))


class EngineDebug:
    """What tests and benchmarks look at inside an engine (``engine.debug``): its counts,
    its kept phase history, its framebuffer, one pass run alone. The doors never need
    it: they use the engine's verbs and queries."""

    def __init__(self, engine: WrinkleEngine):
        self._engine = engine

    @property
    def computed_count(self) -> int:
        """Frames computed (drawn or not) since the engine was made, preroll steps too."""
        return self._engine._computed

    @property
    def preroll_count(self) -> int:
        """Of them, the phase-history preroll steps."""
        return self._engine._prerolled

    def sync_counts(self, path: str) -> dict:
        """How often ``path``'s rprim rebuilt its resources, re-read its parameters, its
        material and its frame (change tracking: what a change costs)."""
        return dict(self._engine.render_delegate.rprims[path].sync_counts)

    @property
    def framebuffer(self):
        """The framebuffer of the last drawn frame (None before the first)."""
        return self._engine.render_delegate.current_framebuffer

    def run_skin(self, path: str) -> None:
        """Run the skin pass again on ``path``'s last synced frame, alone (the bench times
        it against UsdSkel); its output is mesh_resources(path).posed_points."""
        from .render.passes.skin import SkinPass

        engine = self._engine
        mesh = engine.render_delegate.rprims[path]
        with current(engine.ctx):
            engine.render_delegate.wave_pass(SkinPass).skin(mesh.resources, mesh.frame)

    @property
    def history_frame(self) -> float | None:
        """The grid frame whose wave state was recorded last (None: none is kept, the
        next frame restarts the history)."""
        engine = self._engine
        start = engine.history_start()
        if engine.history.last is None or start is None:
            return None
        return start + engine.history.last

    @property
    def kept_history(self) -> list[float]:
        """The grid frames whose wave states the engine keeps (ascending)."""
        start = self._engine.history_start()
        return [] if start is None else [start + i for i in self._engine.history.indices]
