"""The one code path: scene delegate -> render delegate -> passes.

Rendering a frame and baking a frame both call :meth:`WrinkleEngine.compute_frame`;
rendering then draws, baking reads back what the GPU computed.
"""
from __future__ import annotations

import math

from .render.delegate import DirtyBits, RenderDelegate, RenderPass, RenderPassState
from .scene.stage import StageSceneDelegate, _warn_stderr


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
        Time every pass with GL timer queries (``last_timings``).
    """

    def __init__(self, stage, all_meshes: bool = False, relax_iterations: int | None = None,
                 camera: str | None = None, warn=_warn_stderr, ctx=None, profile: bool = False):
        self.scene = StageSceneDelegate(stage, all_meshes=all_meshes,
                                        relax_iterations=relax_iterations, warn=warn)
        self.camera = camera
        self.render_delegate = RenderDelegate(ctx, profile=profile)
        self.render_pass = RenderPass(self.render_delegate)
        self._dirty = {}
        for path in self.scene.meshes:
            self.render_delegate.create_rprim(path)
            self._dirty[path] = DirtyBits.ALL
        self.last_timings: dict[str, float] = {}
        # fail early on a camera that does not exist
        from .scene.camera import find_camera
        find_camera(self.scene.stage, camera)

    @property
    def wrinkled_paths(self) -> list[str]:
        return [p for p, r in self.scene.meshes.items() if r.wrinkled]

    def resolution(self, width: int, height: int | None, frame: float) -> tuple[int, int]:
        """Fill in ``--height`` from the camera's aspect ratio (or 16:9 without a camera)."""
        if height:
            return width, height
        aspect = self.scene.camera_aspect(self.camera, frame) or 16.0 / 9.0
        return width, max(1, int(round(width / aspect)))

    def compute_frame(self, frame: float, aspect: float = 16.0 / 9.0, wrinkles: bool = True):
        """Sync every rprim to ``frame`` and run skin, crush and relax. Returns the FrameRecord."""
        record = self.scene.sample(frame, aspect, self.camera)
        self.scene.current_frame = record
        for path, mesh in self.render_delegate.rprims.items():
            bits = self._dirty[path] | DirtyBits.DIRTY_POINTS | DirtyBits.DIRTY_TRANSFORM \
                | DirtyBits.DIRTY_VISIBILITY
            self._dirty[path] = mesh.sync(self.scene, bits)
        self.last_timings = {}
        self.render_pass.compute(wrinkles, self.last_timings)
        return record

    def render_frame(self, frame: float, width: int, height: int, wrinkles: bool = True):
        """Compute and draw ``frame``; returns {aov name: RenderBuffer}."""
        record = self.compute_frame(frame, width / height, wrinkles)
        state = RenderPassState(record.camera, record.lights, width, height, wrinkles)
        buffers = self.render_pass.execute(state)
        self.last_timings.update(state.timings)
        return buffers

    def read_fields(self, path: str) -> dict:
        """Per-vertex fields of ``path`` as computed for the last frame (numpy)."""
        return self.render_delegate.rprims[path].resources.read_fields()

    def release(self) -> None:
        self.render_delegate.release()


def format_frame(frame: float) -> str:
    return "default" if math.isnan(frame) else (f"{int(frame)}" if float(frame).is_integer()
                                                else f"{frame:g}")
