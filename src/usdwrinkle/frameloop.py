"""A shot's frames to files: the render loop and the bake loop.

The serial ``render`` and ``bake`` commands, the farm's worker tasks and the farm's
client (which bakes before it distributes) all run these, so a frame rendered on a
farm is made by exactly the code that renders it serially.
"""
from __future__ import annotations

import contextlib
import logging
from collections.abc import Callable
from dataclasses import dataclass, replace

from .process.errors import UsdWrinkleError
from .process.timecode import format_frame
from .render.context import in_own_context
from .usd import schema

_log = logging.getLogger(__name__)

#: the warning of a render that finds no wrinkled mesh (serial and farm)
NO_WRINKLED_MESH = ("no mesh has WrinkleAPI applied; rendering without wrinkles "
                    "(use `all_meshes` to wrinkle every mesh)")


def unapplied_note(stage) -> str | None:
    """A warning naming meshes that author wrinkle controls without WrinkleAPI (None if
    there are none): render, bake, the farm and paint say it; check reports it."""
    paths = schema.unapplied_controls(stage)
    return schema.unapplied_message(paths) if paths else None


@contextlib.contextmanager
def at_frame(frame: float | None):
    """Name the frame in a per-frame error that did not name one."""
    try:
        yield
    except UsdWrinkleError as exc:
        if exc.frame is None and frame is not None:
            exc.frame = frame
            exc.args = (exc.one_line(),)
        raise


@in_own_context  # the engine's GL calls and its outputs' (maps, geometry, readbacks)
def render_frames(engine, request, writing, frames: list[float | None], paths: list[str],
                  skip: Callable[[str], bool] = lambda path: False,
                  progress: Callable = lambda items: items,
                  stats: dict | None = None) -> list[float | None]:
    """Render each frame to its path (atomically); returns the frames written.

    ``request`` (render/request.FrameRequest): how each frame is drawn and read back, in
    the layout of the paths' format (outputs/images.layout_for); ``writing``
    (outputs/writer.WriteOptions): how the files are written.

    ``skip(path)``: leave that frame alone (``--skip-existing``, a farm retry).
    ``progress``: wraps the list of (frame, path) pairs (a progress bar).
    ``stats``: filled with per-frame timings in ms (the engine's ``last_timings``, with
    ``profile`` on for the per-pass split, ``fence_wait`` and ``readback`` when the frame
    was copied out, and ``encode`` on the writer), the seconds the loop waited for the
    writer and for the GPU, and the loop's wall time and the process's CPU time over it
    (``render --stats``).

    With ``request.readback_ring`` K > 1, frame f is queued (computed, drawn and resolved
    into one of K readback buffers, behind a fence) and copied out only once frame
    f + K - 1 is queued too, on the resolve's copy thread, so the GPU works on the next
    frames while the CPU copies and encodes; the files are the same
    (tests/test_whole_frames.py).
    """
    import time
    from collections import deque

    from .outputs.images import write_image
    from .outputs.writer import FrameWriter

    engine.check_relax_work(frames, request.wrinkles)
    rows: dict[str, dict] = {}

    def write(path: str, frame_image) -> None:
        try:
            frame_image.wait()  # copied out of the GPU's readback buffer
            started = time.perf_counter()
            write_image(path, frame_image, writing.exr_compression,
                        exr_threads=writing.exr_threads)
        finally:
            frame_image.release()  # its memory may now hold a later frame, not before
        if stats is not None:
            rows[path]["encode"] = (time.perf_counter() - started) * 1e3
            if ring > 1 or "readback" not in rows[path]:  # the copy out (ms)
                rows[path]["readback"] = frame_image.read_ms

    ring = request.ring_on(engine.ctx)
    queued: deque = deque()  # (frame, path, PendingImage) not copied out yet
    gpu_waited = 0.0

    def copy_out(writer: FrameWriter) -> None:
        nonlocal gpu_waited
        frame, path, pending = queued.popleft()
        with at_frame(frame):  # the copy out runs on the resolve's copy thread
            frame_image = pending.start(background=True) if ring > 1 else pending
        if ring > 1:
            gpu_waited += pending.wait_ms / 1e3
            if stats is not None:
                rows[path]["fence_wait"] = pending.wait_ms
        writer.submit(frame, path, frame_image)

    loop_started = time.perf_counter()
    loop_cpu = time.process_time()  # every thread's: the writer's and OpenEXR's too
    with FrameWriter(write, writing.threads, writing.in_flight) as writer:
        try:
            for frame, path in progress(list(zip(frames, paths, strict=True))):
                if skip(path):
                    continue
                started = time.perf_counter()
                with at_frame(frame):
                    pending = engine.render(frame, request)
                if stats is not None:
                    rows[path] = {"frame": frame, **engine.last_timings,
                                  "render": (time.perf_counter() - started) * 1e3}
                queued.append((frame, path, pending))
                while len(queued) >= ring:
                    copy_out(writer)
            while queued:
                copy_out(writer)
        finally:
            for _frame, _path, pending in queued:  # an error or a stop: never read
                if ring > 1:
                    pending.discard()
    if stats is not None:
        stats.update({"frames": list(rows.values()), "waited_s": writer.waited,
                      "gpu_waited_s": gpu_waited,
                      "loop_s": time.perf_counter() - loop_started,
                      "loop_cpu_s": time.process_time() - loop_cpu,
                      "write_threads": writing.threads, "exr_threads": writing.exr_threads,
                      "readback_buffers": ring})
    return writer.written


def bakeable_meshes(engine) -> dict:
    """Path -> MeshRecord of the wrinkled meshes a layer can override."""
    wrinkled = {}
    for path in engine.wrinkled_paths:
        if engine.stage.GetPrimAtPath(path).IsInstanceProxy():
            _log.warning(f"mesh is inside an instance and cannot be overridden; skipped ({path})")
            continue
        wrinkled[path] = engine.meshes[path]
    return wrinkled


@dataclass(frozen=True)
class BakeRequest:
    """What a bake writes (``usdwrinkle bake`` builds it from its options).

    ``frame_spec``: the frames as the user wrote them, recorded in the layer (None:
    first:last). ``maps`` (maps.options.MapOptions): also render each frame's wrinkle
    maps and bind them in a material per mesh; the maps are moved into their folder just
    before the layer is renamed into place, so an error leaves neither. ``geometry``
    (geometry.options.GeometryOptions): also write a displaced render mesh per wrinkled
    mesh, with the coarse mesh as its proxy; without ``levels``, every frame's waves are
    surveyed first."""

    stage_path: str
    output: str
    frames: tuple
    frame_spec: str | None = None
    with_points: bool = False
    display_color: str | None = None
    sparse: bool = False
    maps: object | None = None
    geometry: object | None = None


@in_own_context  # the engine's GL calls and its outputs' (maps, geometry, readbacks)
def bake_layer(engine, request: BakeRequest, progress: Callable = lambda items: items,
               survey_progress: Callable | None = None) -> int:
    """Compute every frame of ``request`` in order (the phase history is sequential in
    time) and write the wrinkle fields to its output atomically; returns the number of
    meshes baked. ``progress`` wraps the frames, ``survey_progress`` the geometry's
    survey of them."""
    from .outputs.layers import LayerBaker, LayerOptions, new_layer, save_layer
    from .outputs.sink import BakeScene
    from .scene.overrides import read_overrides

    stage_path, output, frames = request.stage_path, request.output, list(request.frames)
    maps, geometry = request.maps, request.geometry
    frame_spec = request.frame_spec or frame_spec_text(frames)

    engine.check_relax_work(frames)
    wrinkled = bakeable_meshes(engine)
    if not wrinkled:  # a layer without wrinkle data is never what a bake is run for
        if engine.wrinkled_paths:
            raise UsdWrinkleError("every wrinkled mesh is inside an instance and cannot be "
                                  "overridden, so the layer would hold no wrinkle data (make "
                                  "those prims not instanceable)")
        if any(schema.has_wrinkle_api(prim) for prim in engine.stage.Traverse()):
            raise UsdWrinkleError("no mesh with WrinkleAPI can be wrinkled (each was skipped: "
                                  "see the warnings), so the layer would hold no wrinkle data")
        if note := unapplied_note(engine.stage):
            raise UsdWrinkleError(f"{note}; the layer would hold no wrinkle data")
        raise UsdWrinkleError("no mesh has WrinkleAPI applied, so the layer would hold no "
                              "wrinkle data: pass `all_meshes` to wrinkle every mesh, or apply "
                              "WrinkleAPI to the cloth (usdwrinkle apply)")
    # the maps are relative to the posed shading normals, which renderers must shade with:
    # Storm drops the authored normals of a skinned mesh, so the posed points and normals
    # are baked (README: maps)
    facts = read_overrides(engine.stage, stage_path, wrinkled, frames,
                           carry_primvars=geometry is not None)
    scene = BakeScene(facts, output, tuple(frames), wrinkled, engine.meshes, engine.ctx,
                      engine.corner_primvar, engine.local_to_world)
    sinks = [LayerBaker(scene, LayerOptions(
        with_points=request.with_points or maps is not None,
        display_color=request.display_color, sparse=request.sparse, frame_spec=frame_spec))]
    geometry_bake = None
    try:
        if maps is not None:
            from .maps.bake import MapBake

            if request.display_color:
                # the preview purpose shows the display-colour ramp (LayerBaker), so no
                # map set is made for it
                maps = replace(maps, preview=False)
            sinks.append(MapBake(scene, maps))
        if geometry is not None:
            from .geometry.bake import GeometryBake

            geometry_bake = GeometryBake(scene, geometry)
            sinks.append(geometry_bake)
        if geometry_bake is not None and geometry_bake.needs_survey:
            for frame in (survey_progress or progress)(frames):
                with at_frame(frame):
                    engine.compute_frame(frame)
                    geometry_bake.survey({p: engine.read_fields(p) for p in wrinkled})
        layer = new_layer()
        for sink in sinks:
            sink.begin(layer)
        for frame in progress(frames):
            with at_frame(frame):
                engine.compute_frame(frame)
                fields = {path: engine.read_fields(path) for path in wrinkled}
                resources = {path: engine.mesh_resources(path) for path in engine.rprim_paths}
                for sink in sinks:
                    sink.add_frame(frame, fields, resources)
        metadata = {}
        for sink in sinks:
            metadata.update(sink.finish())

        def commit():
            for sink in sinks:
                sink.commit()

        save_layer(layer, output, metadata, before_rename=commit)
    finally:
        for sink in sinks:
            sink.release()
    return len(wrinkled)


def frame_spec_text(frames: list[float]) -> str:
    """The frames of a bake for its layer's metadata, when no --frames named them:
    ``first:last``, or ``default``."""
    if not frames or frames[0] is None:
        return format_frame(None)
    return f"{format_frame(frames[0])}:{format_frame(frames[-1])}"
