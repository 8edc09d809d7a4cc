"""Render buffers (AOVs) and the offscreen framebuffer they are read from."""
from __future__ import annotations

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
    """One AOV: (height, width, channels) float32, row 0 at the top of the image."""

    name: str
    channel_names: tuple
    pixels: np.ndarray


class Framebuffer:
    """Three float RGBA attachments plus depth, at one resolution."""

    def __init__(self, ctx, width: int, height: int):
        self.ctx = ctx
        self.size = (width, height)
        self.textures = [ctx.texture((width, height), 4, dtype="f4") for _ in range(3)]
        self.depth = ctx.depth_renderbuffer((width, height))
        self.fbo = ctx.framebuffer(color_attachments=self.textures, depth_attachment=self.depth)

    def begin(self) -> None:
        self.fbo.use()
        self.ctx.viewport = (0, 0, *self.size)
        self.fbo.clear(0.0, 0.0, 0.0, 0.0, depth=1.0)

    def read(self) -> dict[str, RenderBuffer]:
        width, height = self.size
        planes = []
        for tex in self.textures:
            data = np.frombuffer(tex.read(), np.float32).reshape(height, width, 4)
            planes.append(data[::-1])  # GL rows start at the bottom, images at the top
        covered = planes[0][..., 3] > 0.0
        out = {}
        for name, (attachment, first, channels) in AOVS.items():
            pixels = planes[attachment][..., first:first + len(channels)].copy()
            if name == "depth":
                pixels[~covered] = np.inf  # nothing hit: infinitely far
            out[name] = RenderBuffer(name, channels, pixels)
        return out

    def release(self) -> None:
        self.fbo.release()
        self.depth.release()
        for tex in self.textures:
            tex.release()
