"""Render buffers (AOVs) and the offscreen framebuffer they are read from."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..images.aovs import OFFSET_SLOTS
from ..process.memory import require_memory
from .resolve import AOVS, ImageLayout, PendingImage, ResolvedImage, ResolvePass, read_rect


@dataclass
class RenderBuffer:
    """One AOV: (height, width, channels) float32, row 0 at the top of the image.

    ``pixels`` may be a view into a wider array (one attachment holds several AOVs);
    it is never written again by the renderer.
    """

    name: str
    channel_names: tuple
    pixels: np.ndarray


#: bytes per pixel and sample: three RGBA float attachments, and depth
_ATTACHMENT_BYTES = 3 * 16 + 4


def check_samples(samples: int) -> None:
    """Multisample counts are powers of two (moderngl and GL drivers take no others)."""
    from ..process.errors import UsdWrinkleError

    if samples < 1 or samples & (samples - 1):
        raise UsdWrinkleError(f"`samples` {samples} is not a power of two (1, 2, 4, 8, ...)")


def check_frame_size(ctx, width: int, height: int, samples: int) -> None:
    """Refuse a frame the GL implementation or the memory cannot hold, naming the limit,
    before anything is allocated (a driver may crash instead of failing cleanly)."""
    from ..process.errors import UsdWrinkleError

    limits = (("GL_MAX_TEXTURE_SIZE", max(width, height)),
              ("GL_MAX_RENDERBUFFER_SIZE", max(width, height)),
              ("GL_MAX_VIEWPORT_DIMS", max(width, height)))
    for name, value in limits:
        limit = ctx.info.get(name)
        if isinstance(limit, (tuple, list)):
            limit = min(limit)
        if limit and value > int(limit):
            raise UsdWrinkleError(f"image size {width}x{height} exceeds this GL "
                                  f"implementation's {name} of {int(limit)}")
    check_samples(samples)
    max_samples = int(ctx.info.get("GL_MAX_SAMPLES", 1) or 1)
    if samples > max_samples:
        raise UsdWrinkleError(f"`samples` {samples} exceeds this GL implementation's "
                              f"GL_MAX_SAMPLES of {max_samples}")
    # the targets, the resolve pass's output and the read-back copies (the writer may
    # hold a few)
    require_memory(width * height * (_ATTACHMENT_BYTES * samples + OFFSET_SLOTS * 4 * 4),
                   f"a {width}x{height} frame with {samples} samples needs",
                   "lower `width`/`height` or `samples`")


class Framebuffer:
    """Up to three float RGBA attachments (colour; height, amplitude, depth; normal) plus
    depth, at one resolution: ``count`` of them, the first ones (an 8-bit image keeps
    colour alone, and allocating and clearing multisampled float targets it does not keep
    cost start-up and memory).

    With ``samples`` > 1 the meshes are drawn multisampled (edges anti-aliased) into
    multisample textures, which the resolve pass (render/resolve.py) reads directly: it
    averages coverage, so colour stays premultiplied by alpha (the EXR convention) and
    the other AOVs are divided by alpha, so that an edge pixel holds the average over the
    samples that hit the surface.
    """

    def __init__(self, ctx, width: int, height: int, samples: int = 4,
                 resolve: ResolvePass | None = None, count: int = 3, colour: str = "f4"):
        self.ctx = ctx
        self.size = (width, height)
        check_frame_size(ctx, width, height, int(samples))
        self.samples = max(1, int(samples))
        multisample = self.samples if self.samples > 1 else 0  # 0: single-sample
        self.colour = colour
        self.targets = [ctx.texture((width, height), 4, samples=multisample,
                                    dtype=colour if index == 0 else "f4")
                        for index in range(count)]
        self.depth = ctx.depth_renderbuffer((width, height), samples=multisample)
        self.fbo = ctx.framebuffer(color_attachments=self.targets, depth_attachment=self.depth)
        self.rect = (0, 0, width, height)
        self._own_resolve = resolve is None
        self.resolve = resolve or ResolvePass(ctx)

    def begin(self, attachments=None, rect=None, layout: ImageLayout | None = None) -> None:
        """Bind, clear, and write only ``attachments`` (indices; None: all): an 8-bit
        image keeps the colour alone, and the other targets' multisampled writes and
        clears cost the draw about as much as the shading. ``rect`` (x0, y0, x1, y1;
        None: the whole frame): the part of the frame that anything is drawn into
        (render/bounds.py); only the part that the resolve then reads for ``layout``
        (resolve.read_rect; None: AOVs) is cleared, and the rest of the frame is read
        as empty."""
        self.fbo.use()
        self.ctx.viewport = (0, 0, *self.size)
        keep = range(len(self.targets)) if attachments is None else attachments
        self.write_only([index in keep for index in range(len(self.targets))])
        self.ctx.enable(self.ctx.DEPTH_TEST)
        self.rect = read_rect(layout, *self.size, rect)
        x0, y0, x1, y1 = self.rect
        if (x0, y0, x1, y1) == (0, 0, *self.size):
            self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)
        elif x1 > x0 and y1 > y0:
            self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0, viewport=(x0, y0, x1 - x0, y1 - y0))

    def write_only(self, flags) -> list:
        """Write the attachments whose flag is true (moderngl takes one tuple for one
        attachment, a list for several); returns the previous flags."""
        previous = self.fbo.color_mask
        previous = [mask[0] for mask in previous] if isinstance(previous[0], tuple) \
            else [previous[0]]
        masks = [(bool(flag),) * 4 for flag in flags]
        self.fbo.color_mask = masks[0] if len(masks) == 1 else masks
        return previous

    def read_image(self, layout: ImageLayout, ring: int = 1) -> ResolvedImage | PendingImage:
        """The frame as ``layout`` says (an image file's planes or codes): only the
        attachments it needs are read, at the precision it is stored at. ``ring`` > 1:
        a PendingImage, resolved into the next of that many readback buffers and read
        when asked for (render/resolve.py)."""
        if read_rect(layout, *self.size, self.rect) != self.rect:
            raise RuntimeError(f"the frame was cleared for another layout than {layout.kind}")
        return self.resolve.run(self.targets, self.size, self.samples, layout, self.rect,
                                ring)

    def read(self, aovs=tuple(AOVS)) -> dict[str, RenderBuffer]:
        """The requested AOVs as float RenderBuffers, views of one array of their own
        (never released, so no later frame writes into it)."""
        image = self.read_image(ImageLayout("aovs", tuple(aovs)))
        return {name: RenderBuffer(name, AOVS[name][2], image.planes[name]) for name in aovs}

    def release(self) -> None:
        if self._own_resolve:
            self.resolve.release()
        self.fbo.release()
        self.depth.release()
        for target in self.targets:
            target.release()
