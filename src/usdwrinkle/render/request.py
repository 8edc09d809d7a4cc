"""FrameRequest: how a computed frame is drawn and read back.

A door builds one from its options (app/options.RenderOptions.frame_request, the paint
session's quality, a test's size) and it reaches the draw and resolve passes unchanged,
through the frame loop (frameloop.render_frames) and the engine's ``render``.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..images.aovs import ImageLayout


@dataclass(frozen=True)
class FrameRequest:
    """One frame's drawing: its size, its multisamples, with or without wrinkles, and what
    is read back (``layout``: float AOVs, or the planes an image file stores)."""

    width: int
    height: int
    #: multisamples per pixel, a power of two (1: no anti-aliasing)
    samples: int = 4
    #: False: the same shading without wrinkles
    wrinkles: bool = True
    #: where folds turn within a pixel, shade each multisample where it lies, not the
    #: pixel once (render --no-shade-samples turns it off)
    shade_samples: bool = True
    #: draw the folds where the view ray meets them (draw.glsl: RELIEF; render --relief),
    #: not where it meets the coarse surface: flanks that face away hide behind crests
    relief: bool = False
    #: what is read back: ImageLayout("aovs", names) returns {name: RenderBuffer}; an
    #: "exr" or "8bit" layout the frame as that file stores it (render/resolve.py)
    layout: ImageLayout = ImageLayout("aovs")
    #: readback buffers: frame f is copied out of the GPU while f + 1 .. f + K - 1
    #: compute (render/resolve.py), and ``render`` returns a PendingImage; 1 reads each
    #: frame as soon as it is drawn; None: the context's choice (readback_ring)
    readback_ring: int | None = 1
    #: a scene/records.CameraRecord to look through instead of the shot's (a viewer's
    #: orbit camera); None: the shot's
    camera: object | None = None

    @property
    def aspect(self) -> float:
        return self.width / self.height

    def ring_on(self, ctx) -> int:
        """The readback buffers this request uses on ``ctx``."""
        if self.layout.kind == "aovs":
            return 1
        if self.readback_ring is not None:
            return self.readback_ring
        return default_readback_ring(ctx)


def default_readback_ring(ctx) -> int:
    """Readback buffers when none are asked for: 3 on a GPU, 1 on llvmpipe, where the CPU
    computes the frame anyway and the copy thread only competes with it (the
    measurements: docs/decisions.md, "Readback buffers")."""
    from .context import is_software_renderer

    return 1 if is_software_renderer(ctx.info.get("GL_RENDERER", "")) else 3
