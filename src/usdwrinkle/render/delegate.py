"""Hydra-style render delegate: rprims that sync from the scene delegate, and a
render pass that runs skin -> crush -> relax per mesh, then draws.

Vocabulary follows pxr/imaging/hd so that a C++ HdRenderDelegate port is
mechanical: ``RenderDelegate.create_rprim``, ``Mesh.sync(scene_delegate,
dirty_bits) -> remaining bits``, ``RenderPass.execute(request, ...)`` (one FrameRequest,
render/request.py), ``RenderBuffer``.
"""
from __future__ import annotations

import time

from ..method.contract import COLD_START_FACTOR
from ..scene.dirty import DirtyBits
from .bounds import eye_bound, screen_rect
from .buffers import Framebuffer, RenderBuffer
from .context import create_context, is_software_renderer
from .passes.base import Step, wave_passes
from .passes.draw import FLIP_Y, DrawPass
from .request import FrameRequest
from .resolve import PendingImage, ResolvedImage, ResolvePass
from .resources import MeshResources


class Mesh:
    """One wrinkled (or plainly drawn) mesh: its GPU resources and current frame."""

    def __init__(self, delegate: RenderDelegate, path: str):
        self.delegate = delegate
        self.path = path
        self.resources: MeshResources | None = None
        self.frame = None
        self.timings: dict[str, float] = {}
        #: how often each part was synced: "resources" (all GPU resources built),
        #: "params" (wrinkle parameters re-uploaded), "material", "frame" (per frame)
        self.sync_counts = {"resources": 0, "params": 0, "material": 0, "frame": 0}

    def sync(self, scene_delegate, dirty_bits: int, frame=None) -> int:
        """Pull what is dirty from the scene delegate; returns the bits left dirty.

        ``scene_delegate`` provides ``meshes[path]`` (MeshRecord); ``frame`` is this
        mesh's MeshFrame at the time the scene was sampled at (the scene owns time, as
        UsdImagingDelegate::SetTime does; the engine hands the sample down). Topology
        rebuilds every resource; wrinkle parameters and the material re-upload only their
        own tables.
        """
        record = scene_delegate.meshes[self.path]
        if dirty_bits & DirtyBits.DIRTY_TOPOLOGY or self.resources is None:
            if self.resources is not None:
                self.resources.release()
            self.resources = MeshResources(self.delegate.ctx, record)
            self.sync_counts["resources"] += 1
        else:
            if dirty_bits & DirtyBits.DIRTY_PRIMVAR:
                self.resources.update_params(record)
                self.sync_counts["params"] += 1
            if dirty_bits & DirtyBits.DIRTY_MATERIAL:
                self.resources.update_material(record)
                self.sync_counts["material"] += 1
        if dirty_bits & DirtyBits.FRAME and frame is not None:
            self.frame = frame
            if self.frame.normal_map is not None:  # a time-sampled normal map
                self.resources.set_normal_map(self.frame.normal_map)
            if self.frame.corner_colors is not None:  # a time-sampled displayColor
                self.resources.set_frame_colors(self.frame.corner_colors)
            self.sync_counts["frame"] += 1
        return DirtyBits.CLEAN

    def compute(self, wrinkles: bool, timer=None, write: int = 0,
                read: int | None = None, drawn: bool = True) -> None:
        """Run the wave passes (skin, normals, crush, relax: render/passes/base.py) for
        the synced frame, into the wave state in slot ``write``.

        ``read``: the slot of the wave state of the shot's previous grid frame (read,
        never written); relaxation then starts from its phases (``relaxIterations``
        steps). Without one (None) it starts from the material-anchored phase and runs
        COLD_START_FACTOR times longer. A frame drawn from baked wave fields computes its
        normals alone: no fit and no relax (scene/baked.py). ``drawn`` False: a preroll
        step, computed for the history alone (Step.drawn).
        """
        res = self.resources
        history = read is not None
        res.waves.begin(write, read)
        iterations = res.record.params.relax_iterations if wrinkles else 0
        if not history:
            iterations *= COLD_START_FACTOR
        step = Step(self.frame, wrinkles, history and wrinkles, iterations,
                    self.frame.baked if wrinkles else None, drawn)
        for wave_pass in self.delegate.wave_passes:
            with _timed(timer, wave_pass.TIMING, self.timings):
                wave_pass.run(res, step)

    def release(self) -> None:
        if self.resources is not None:
            self.resources.release()
            self.resources = None


class _timed:
    """Time a pass when profiling: a GL timer query, or the wall clock around glFinish.

    Mesa's software rasterisers (llvmpipe, softpipe) run the work on the CPU and answer
    GL_TIME_ELAPSED with numbers that do not measure it (1 ns, or the time to queue it),
    so there the finish-bracketed wall clock is used; elsewhere an implausible query
    result falls back to it too. The source is recorded under "<pass>.source".
    """

    def __init__(self, ctx, name, sink):
        self.ctx, self.name, self.sink = ctx, name, sink
        self.query = ctx.query(time=True) if ctx is not None else None
        renderer = ctx.info.get("GL_RENDERER", "") if ctx is not None else ""
        self.software = is_software_renderer(renderer)

    def __enter__(self):
        if self.query is not None:
            self.ctx.finish()
            self.started = time.perf_counter()
            self.query.__enter__()

    def __exit__(self, *exc):
        if self.query is None:
            return
        self.query.__exit__(*exc)
        self.ctx.finish()
        wall_ms = (time.perf_counter() - self.started) * 1e3
        gpu_ms = self.query.elapsed / 1e6
        plausible = not self.software and 0.01 * wall_ms < gpu_ms <= wall_ms * 1.5 + 0.05
        self.sink[self.name] = self.sink.get(self.name, 0.0) + (gpu_ms if plausible else wall_ms)
        self.sink[self.name + ".source"] = "gl-timer-query" if plausible else "wall-clock"


class RenderDelegate:
    """Owns the GL context, the compiled passes and the rprims."""

    def __init__(self, ctx=None, profile: bool = False):
        self.ctx = ctx or create_context()
        self.profile = profile
        #: the per-mesh compute chain, in order (render/passes/base.wave_passes)
        self.wave_passes = [cls(self.ctx) for cls in wave_passes()]
        self.draw = DrawPass(self.ctx)
        self.resolve = ResolvePass(self.ctx)
        self.rprims: dict[str, Mesh] = {}
        self._framebuffer: Framebuffer | None = None

    def wave_pass(self, cls):
        """This delegate's instance of the wave pass class ``cls``."""
        return next(p for p in self.wave_passes if type(p) is cls)

    @property
    def max_texture_size(self) -> int:
        """GL_MAX_TEXTURE_SIZE of this context (the largest map or image side)."""
        return int(self.ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384) or 16384)

    def create_rprim(self, path: str) -> Mesh:
        mesh = Mesh(self, path)
        self.rprims[path] = mesh
        return mesh

    def destroy_rprim(self, path: str) -> None:
        mesh = self.rprims.pop(path, None)
        if mesh is not None:
            mesh.release()

    @property
    def current_framebuffer(self) -> Framebuffer | None:
        """The framebuffer the last frame was drawn into (kept for the next), or None."""
        return self._framebuffer

    def framebuffer(self, width: int, height: int, samples: int = 4,
                    count: int = 3, colour: str = "f4") -> Framebuffer:
        """A framebuffer of at least ``count`` attachments, colour of ``colour`` (kept, and
        reused, until the size, the samples, a larger count or another colour is asked
        for)."""
        fb = self._framebuffer
        if fb is None or fb.size != (width, height) or fb.samples != max(1, samples) or \
                len(fb.targets) < count or fb.colour != colour:
            if fb is not None:
                fb.release()
            fb = self._framebuffer = Framebuffer(self.ctx, width, height, samples,
                                                 self.resolve, count, colour)
        return fb

    def release(self) -> None:
        for path in list(self.rprims):
            self.destroy_rprim(path)
        if self._framebuffer is not None:
            self._framebuffer.release()
            self._framebuffer = None
        self.resolve.release()
        self.draw.release()
        for wave_pass in self.wave_passes:
            wave_pass.release()


class RenderPass:
    """Computes the wrinkle fields of every rprim, then draws them into the AOVs."""

    def __init__(self, delegate: RenderDelegate):
        self.delegate = delegate

    def compute(self, wrinkles: bool, timings: dict | None = None, write: int = 0,
                read: int | None = None, skip: frozenset = frozenset(),
                drawn: bool = True) -> None:
        """Skin, crush and relax every rprim but those in ``skip`` (a preroll leaves out
        the meshes drawn from baked fields), each into its wave state in slot ``write``,
        from the one in slot ``read`` (None: a cold start). ``drawn`` False: a preroll
        step, never drawn (Step.drawn)."""
        timer = self.delegate.ctx if self.delegate.profile else None
        for path, mesh in self.delegate.rprims.items():
            if path in skip:
                continue
            mesh.timings = {}
            mesh.compute(wrinkles, timer, write, read, drawn)
            if timings is not None:
                for key, value in mesh.timings.items():
                    timings[key] = value if isinstance(value, str) else \
                        timings.get(key, 0.0) + value

    def _draw_translucent(self, meshes: list, fb, camera, bounds: dict) -> None:
        """Translucent meshes after the opaque ones, farthest first, each composited
        "over" what is drawn (its colour is premultiplied by its opacity, as Storm's);
        they write neither depth nor the other AOVs, which keep the surface behind.
        Storm sorts fragments (order-independent transparency); this sorts meshes."""
        import moderngl
        import numpy as np

        ctx = self.delegate.ctx

        def distance(mesh) -> float:
            centre = np.append(mesh.resources.record.rest_points.mean(axis=0), 1.0)
            return float(np.linalg.norm((centre @ mesh.frame.local_to_world)[:3] -
                                        camera.position))

        previous = fb.write_only([True] + [False] * (len(fb.targets) - 1))
        fb.fbo.depth_mask = False
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.ONE, moderngl.ONE_MINUS_SRC_ALPHA
        try:
            for mesh in sorted(meshes, key=distance, reverse=True):
                self.delegate.draw.draw(mesh.resources, mesh.frame, camera, bounds[id(mesh)])
        finally:
            ctx.disable(moderngl.BLEND)
            fb.write_only(previous)
            fb.fbo.depth_mask = True

    def execute(self, request: FrameRequest, camera, lights: tuple,
                timings: dict) -> dict[str, RenderBuffer] | ResolvedImage | PendingImage:
        """Draw every rprim through ``camera`` (``request.camera``, else the shot's) in
        ``lights``; returns what ``request.layout`` reads back: the AOVs, or the frame as
        an image file stores it. ``timings`` gains the pass times (ms)."""
        d = self.delegate
        ctx = d.ctx
        layout = request.layout
        if request.camera is not None:
            camera = request.camera
        attachments = layout.attachments if layout.kind != "aovs" else None
        # an 8-bit image is as exact from half-float colour samples (11 bits), which
        # halve the multisampled colour's clears, writes and reads
        eight_bit = layout.kind == "8bit"
        fb = d.framebuffer(request.width, request.height, request.samples,
                           3 if attachments is None else max(attachments) + 1,
                           "f2" if eight_bit else "f4")
        image = layout if attachments is not None else None
        timer = ctx if d.profile else None
        # a host's GL state is not ours (Qt enters paintGL with blending on): reset what
        # the draw relies on
        ctx.disable(ctx.BLEND)
        ctx.scissor = None
        with _timed(timer, "draw", timings):
            drawn = [mesh for mesh in d.rprims.values() if mesh.resources is not None and
                     mesh.frame is not None and mesh.frame.visible and
                     mesh.resources.num_triangles]
            # where each mesh can be this frame: its culling, and the part of the frame
            # that is cleared and read back (render/bounds.py)
            bounds = {id(mesh): eye_bound(mesh.resources.record, mesh.frame,
                                          camera.view) for mesh in drawn}
            fb.begin(attachments, screen_rect(bounds.values(), camera.projection @ FLIP_Y,
                                              request.width, request.height), image)
            ctx.enable(ctx.DEPTH_TEST)
            ctx.disable(ctx.CULL_FACE)
            d.draw.shade_samples = request.shade_samples and request.samples > 1
            d.draw.relief = request.relief
            d.draw.begin(camera, lights, request.wrinkles)
            translucent = [mesh for mesh in drawn if mesh.resources.record.material.translucent]
            for mesh in drawn:
                if mesh not in translucent:
                    d.draw.draw(mesh.resources, mesh.frame, camera, bounds[id(mesh)])
            if translucent:
                self._draw_translucent(translucent, fb, camera, bounds)
        started = time.perf_counter()
        buffers = fb.read_image(image, request.ring_on(ctx)) if image is not None \
            else fb.read(layout.aovs)
        if d.profile:  # a pending image's copy is timed when it is read (its read_ms)
            timings["readback"] = (time.perf_counter() - started) * 1e3
        return buffers
