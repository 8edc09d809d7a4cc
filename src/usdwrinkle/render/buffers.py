"""Render buffers (AOVs) and the offscreen framebuffer they are read from."""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

#: AOV name -> (attachment, first channel, channel names in image files)
AOVS = {
    "color": (0, 0, ("R", "G", "B", "A")),
    "wrinkle.height": (1, 0, ("wrinkle.height",)),
    "wrinkle.amplitude": (1, 1, ("wrinkle.amplitude",)),
    "normal": (2, 0, ("N.X", "N.Y", "N.Z")),
    "depth": (1, 2, ("Z",)),
}


@dataclass
class RenderBuffer:
    """One AOV: (height, width, channels) float32, row 0 at the top of the image.

    ``pixels`` may be a view into a wider array (one attachment holds several AOVs);
    it is never written again by the renderer.
    """

    name: str
    channel_names: tuple
    pixels: np.ndarray


#: bytes per pixel: three RGBA float attachments, and depth
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
    max_samples = int(ctx.info.get("GL_MAX_SAMPLES", 1) or 1)
    if samples > max_samples:
        raise UsdWrinkleError(f"--samples {samples} exceeds this GL implementation's "
                              f"GL_MAX_SAMPLES of {max_samples}")
    # multisampled targets, the resolved textures, and the read-back copies
    needed = width * height * (_ATTACHMENT_BYTES * (samples + 1) + 3 * 16 * 2)
    available = available_memory()
    if available is not None and needed > available:
        raise UsdWrinkleError(f"a {width}x{height} frame with {samples} samples needs about "
                              f"{needed / 2**30:.1f} GiB, but {available / 2**30:.1f} GiB of "
                              "memory are available; lower --width/--height or --samples")


class Framebuffer:
    """Three float RGBA attachments plus depth, at one resolution.

    With ``samples`` > 1 the meshes are drawn multisampled (edges anti-aliased) and
    resolved into single-sample textures. The resolve averages coverage: colour stays
    premultiplied by alpha (the EXR convention), the other AOVs are divided by alpha so
    that an edge pixel holds the average over the samples that hit the surface.
    """

    def __init__(self, ctx, width: int, height: int, samples: int = 4):
        self.ctx = ctx
        self.size = (width, height)
        check_frame_size(ctx, width, height, int(samples))
        self.samples = max(1, int(samples))
        self.textures = [ctx.texture((width, height), 4, dtype="f4") for _ in range(3)]
        multisample = self.samples if self.samples > 1 else 0  # 0: a plain renderbuffer
        self.depth = ctx.depth_renderbuffer((width, height), samples=multisample)
        if self.samples > 1:
            self.targets = [ctx.renderbuffer((width, height), 4, samples=self.samples, dtype="f4")
                            for _ in range(3)]
        else:
            self.targets = self.textures
        self.fbo = ctx.framebuffer(color_attachments=self.targets, depth_attachment=self.depth)
        # one (resolved, multisampled) framebuffer pair per attachment: a frame resolves
        # only the attachments its file stores (a PNG: colour alone)
        self.resolve_pairs = [(ctx.framebuffer(color_attachments=[texture]),
                               ctx.framebuffer(color_attachments=[target]))
                              for texture, target in zip(self.textures, self.targets,
                                                         strict=True)] \
            if self.samples > 1 else []
        self._planes: list[np.ndarray | None] = [None] * 3
        self._unshared_refs = 0

    def begin(self) -> None:
        self.fbo.use()
        self.ctx.viewport = (0, 0, *self.size)
        self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)

    def read(self, aovs=tuple(AOVS)) -> dict[str, RenderBuffer]:
        """Read back the requested AOVs: only the attachments they need, each straight into
        a new array (the draw pass flips y in clip space, so GL's bottom-up rows already
        come out top-down). AOVs that need no arithmetic are views of those arrays."""
        width, height = self.size
        needed = {AOVS[name][0] for name in aovs} | {0}  # colour's alpha is the coverage
        for index in sorted(needed):
            if self.resolve_pairs:
                resolved, multisampled = self.resolve_pairs[index]
                self.ctx.copy_framebuffer(resolved, multisampled)
        planes = {}
        for index in sorted(needed):
            planes[index] = self._plane(index)
            self.textures[index].read_into(planes[index])
        alpha = planes[0][..., 3:4]
        covered = alpha > 0.0
        inverse = None
        if self.samples > 1 and any(AOVS[name][0] != 0 for name in aovs):
            # resolved AOVs are coverage-weighted sums: divide by the coverage
            inverse = np.zeros((height, width, 1), np.float32)
            np.divide(1.0, alpha, out=inverse, where=covered)
        out = {}
        for name in aovs:
            attachment, first, channels = AOVS[name]
            pixels = planes[attachment][..., first:first + len(channels)]
            if inverse is not None and attachment != 0:
                pixels = pixels * inverse
            if name == "depth":
                pixels = np.where(covered, pixels, np.float32(np.inf))  # nothing hit: far
            if name == "normal" and self.samples > 1:
                length = np.sqrt(np.einsum("...i,...i->...", pixels, pixels))[..., None]
                np.divide(pixels, length, out=pixels, where=length > 0)
            out[name] = RenderBuffer(name, channels, pixels)
        return out

    def _plane(self, index: int) -> np.ndarray:
        """The array attachment ``index`` is read into: last frame's when nobody holds it
        (or a view of it) any more, else a new one, so buffers handed out are never
        overwritten. Reusing it saves the page faults of fresh memory (2 ms per 330 kpixel
        plane here, ten times the copy itself)."""
        # Only the list holds it when the count is what it was right after allocation
        # (measured with the same expression, so it holds on any Python version).
        if self._planes[index] is None or \
                sys.getrefcount(self._planes[index]) != self._unshared_refs:
            self._planes[index] = np.empty((self.size[1], self.size[0], 4), np.float32)
            self._unshared_refs = sys.getrefcount(self._planes[index])
        return self._planes[index]

    def release(self) -> None:
        self._planes = [None] * 3
        for pair in self.resolve_pairs:
            for fbo in pair:
                fbo.release()
        self.resolve_pairs = []
        self.fbo.release()
        self.depth.release()
        for tex in self.textures:
            tex.release()
        if self.samples > 1:
            for rb in self.targets:
                rb.release()
