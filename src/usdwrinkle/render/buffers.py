"""Render buffers (AOVs) and the offscreen framebuffer they are read from."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .resolve import AOVS, ImageLayout, ResolvedImage, ResolvePass


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


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux MemAvailable), or None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_samples(samples: int) -> None:
    """Multisample counts are powers of two (moderngl and GL drivers take no others)."""
    from ..errors import UsdWrinkleError

    if samples < 1 or samples & (samples - 1):
        raise UsdWrinkleError(f"--samples {samples} is not a power of two (1, 2, 4, 8, ...)")


def check_frame_size(ctx, width: int, height: int, samples: int) -> None:
    """Refuse a frame the GL implementation or the memory cannot hold, naming the limit,
    before anything is allocated (a driver may crash instead of failing cleanly)."""
    from ..errors import UsdWrinkleError

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
        raise UsdWrinkleError(f"--samples {samples} exceeds this GL implementation's "
                              f"GL_MAX_SAMPLES of {max_samples}")
    # the targets, the resolve pass's output and the read-back copies (the writer may
    # hold a few)
    needed = width * height * (_ATTACHMENT_BYTES * samples + 10 * 4 * 4)
    available = available_memory()
    if available is not None and needed > available:
        raise UsdWrinkleError(f"a {width}x{height} frame with {samples} samples needs about "
                              f"{needed / 2**30:.1f} GiB, but {available / 2**30:.1f} GiB of "
                              "memory are available; lower --width/--height or --samples")


class Framebuffer:
    """Three float RGBA attachments plus depth, at one resolution.

    With ``samples`` > 1 the meshes are drawn multisampled (edges anti-aliased) into
    multisample textures, which the resolve pass (render/resolve.py) reads directly: it
    averages coverage, so colour stays premultiplied by alpha (the EXR convention) and
    the other AOVs are divided by alpha, so that an edge pixel holds the average over the
    samples that hit the surface.
    """

    def __init__(self, ctx, width: int, height: int, samples: int = 4,
                 resolve: ResolvePass | None = None):
        self.ctx = ctx
        self.size = (width, height)
        check_frame_size(ctx, width, height, int(samples))
        self.samples = max(1, int(samples))
        multisample = self.samples if self.samples > 1 else 0  # 0: single-sample
        self.targets = [ctx.texture((width, height), 4, samples=multisample, dtype="f4")
                        for _ in range(3)]
        self.depth = ctx.depth_renderbuffer((width, height), samples=multisample)
        self.fbo = ctx.framebuffer(color_attachments=self.targets, depth_attachment=self.depth)
        self._own_resolve = resolve is None
        self.resolve = resolve or ResolvePass(ctx)

    def begin(self) -> None:
        self.fbo.use()
        self.ctx.viewport = (0, 0, *self.size)
        self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)

    def read_image(self, layout: ImageLayout) -> ResolvedImage:
        """The frame as ``layout`` says (an image file's planes or codes): only the
        attachments it needs are read, at the precision it is stored at."""
        return self.resolve.run(self.targets, self.size, self.samples, layout)

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
