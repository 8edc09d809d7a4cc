"""Resolve pass: the drawn (multisampled) attachments -> the pixels a reader needs, at
the precision it keeps them, in one compute dispatch (shaders/resolve.glsl).

Before, each attachment was resolved by a blit into a float texture, read back whole
and finished in numpy (coverage division, normalised normals, depth of empty pixels,
the sRGB encode or the concatenation and half conversion of the encoder). On llvmpipe
that was 25 ms of a 640x360 CesiumMan frame; the pass does it in about 8 ms, and an EXR
frame comes back as the planes its file stores, a PNG frame as its 8-bit codes.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

from . import bindings
from .shaders import Variants, compute_shader

#: AOV name -> (attachment, first channel, channel names in image files)
AOVS = {
    "color": (0, 0, ("R", "G", "B", "A")),
    "wrinkle.height": (1, 0, ("wrinkle.height",)),
    "wrinkle.amplitude": (1, 1, ("wrinkle.amplitude",)),
    "normal": (2, 0, ("N.X", "N.Y", "N.Z")),
    "depth": (1, 2, ("Z",)),
}
#: the order of the AOV blocks of the OUTPUT_AOVS layout (u_offset's order)
AOV_BLOCKS = ("color", "wrinkle.height", "wrinkle.amplitude", "normal", "depth")
#: an EXR frame's channels, one plane each, in the shader's plane order
EXR_CHANNELS = ("R", "G", "B", "A", "wrinkle.height", "wrinkle.amplitude", "N.X", "N.Y", "N.Z",
                "Z")
#: the channels that ``half`` stores as half float: colour and normals
HALF_CHANNELS = ("R", "G", "B", "A", "N.X", "N.Y", "N.Z")


@dataclass(frozen=True)
class ImageLayout:
    """What a frame is read back as.

    ``kind``: "aovs" (float AOVs, for Framebuffer.read), "exr" (one plane per EXR
    channel, colour and normals as half float with ``half``) or "8bit" (RGBA sRGB codes,
    straight alpha; with ``over_black`` the colour over black, for JPEG).
    ``aovs``: the AOVs an "aovs" layout holds.
    """

    kind: str
    aovs: tuple = tuple(AOVS)
    half: bool = False
    over_black: bool = False

    @property
    def attachments(self) -> frozenset:
        if self.kind == "exr":
            return frozenset((0, 1, 2))
        if self.kind == "8bit":
            return frozenset((0,))
        return frozenset(AOVS[name][0] for name in self.aovs) | {0}


@dataclass
class ResolvedImage:
    """One frame as a file stores it: ``planes`` maps an EXR channel name to its
    (height, width) plane (float16 or float32), or "RGBA" to the (height, width, 4) uint8
    codes of an 8-bit image. ``bad``: how many written values are NaN or infinite (depth:
    NaN); the writer refuses such a frame. Row 0 is the top of the image."""

    layout: ImageLayout
    width: int
    height: int
    planes: dict
    bad: int


def _plan(layout: ImageLayout, n: int) -> tuple[list[int], int, list]:
    """(the shader's u_offset, total words, [(name, first word, dtype, shape)])."""
    offsets, views, word = [], [], 0
    if layout.kind == "aovs":
        for name in AOV_BLOCKS:
            count = len(AOVS[name][2])
            offsets.append(word)
            if name in layout.aovs:
                views.append((name, word, np.float32, count))
            word += n * count if AOVS[name][0] in layout.attachments else 0
    elif layout.kind == "exr":
        for name in EXR_CHANNELS:
            half = layout.half and name in HALF_CHANNELS
            offsets.append(word)
            views.append((name, word, np.float16 if half else np.float32, 1))
            word += (n + 1) // 2 if half else n
    else:
        views.append(("RGBA", 0, np.uint8, 4))
        word = n
    offsets += [0] * (10 - len(offsets))
    return offsets, word, views


class ResolvePass:
    """Compiles one shader variant per (samples, layout) on first use."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.defines = {**bindings.COMMON, **bindings.RESOLVE}
        #: sample count -> the shader's variants (SAMPLES is a value, not a switch)
        self.variants: dict[int, Variants] = {}
        self.bad = ctx.buffer(reserve=4)
        self.out = None
        #: readback arrays, reused once nobody holds a view of them any more
        self._arrays: list[np.ndarray] = []
        self._unshared_refs = None

    def _shader(self, layout: ImageLayout, samples: int):
        attachments = layout.attachments
        switches = {"NEED_FIELDS": 1 in attachments, "NEED_NORMAL": 2 in attachments,
                    "OUTPUT_AOVS": layout.kind == "aovs", "OUTPUT_EXR": layout.kind == "exr",
                    "OUTPUT_8BIT": layout.kind == "8bit",
                    "HALF_COLOR_NORMAL": layout.kind == "exr" and layout.half,
                    "OVER_BLACK": layout.kind == "8bit" and layout.over_black}
        samples = max(1, int(samples))
        if samples not in self.variants:
            defines = {**self.defines, "SAMPLES": samples}
            self.variants[samples] = Variants(
                lambda extra: compute_shader(self.ctx, "resolve.glsl", {**defines, **extra}))
        return self.variants[samples](**switches)

    def run(self, targets: list, size: tuple[int, int], samples: int,
            layout: ImageLayout) -> ResolvedImage:
        """Resolve ``targets`` (the three colour attachments, multisampled textures when
        ``samples`` > 1) into ``layout``; returns the frame's arrays."""
        width, height = size
        n = width * height
        offsets, words, views = _plan(layout, n)
        shader = self._shader(layout, samples)
        if self.out is None or self.out.size < words * 4:
            if self.out is not None:
                self.out.release()
            self.out = self.ctx.buffer(reserve=max(words, 1) * 4)
        self.bad.write(np.zeros(1, np.uint32).tobytes())
        for index in layout.attachments:
            targets[index].use(bindings.RESOLVE[("RESOLVE_COLOR", "RESOLVE_WRINKLE",
                                                 "RESOLVE_NORMAL")[index]])
        self.out.bind_to_storage_buffer(bindings.RESOLVE["RESOLVE_OUT"])
        self.bad.bind_to_storage_buffer(bindings.RESOLVE["RESOLVE_BAD"])
        shader["u_size"] = (width, height)
        if "u_offset" in shader:  # the compiler keeps the elements the variant reads
            kept = shader["u_offset"].array_length
            shader["u_offset"] = offsets[:kept] if kept > 1 else offsets[0]
        invocations = (n + 1) // 2 if layout.kind == "exr" else n  # EXR: pixel pairs
        shader.run((invocations + bindings.LOCAL_SIZE - 1) // bindings.LOCAL_SIZE)
        array = self._array(words)
        self.out.read_into(array, size=words * 4)
        bad = int(np.frombuffer(self.bad.read(), np.uint32)[0])
        planes = {}
        for name, first, dtype, channels in views:
            itemsize = np.dtype(dtype).itemsize
            count = n * channels
            flat = array.view(np.uint8)[first * 4:first * 4 + count * itemsize].view(dtype)
            planes[name] = flat.reshape((height, width, channels) if channels > 1 or
                                        layout.kind != "exr" else (height, width))
        return ResolvedImage(layout, width, height, planes, bad)

    def _array(self, words: int) -> np.ndarray:
        """A uint32 array of ``words``: one whose views nobody holds any more (the writer
        may still hold the last frames), else a new one. Reusing saves the page faults of
        fresh memory (2 ms per 330 kpixel float RGBA plane here, ten times the copy)."""
        for array in self._arrays:
            # only this list and the loop hold it when the count is what it was just after
            # allocation (measured with the same expression, so it holds on any Python)
            if array.size == words and sys.getrefcount(array) == self._unshared_refs:
                return array
        array = np.empty(words, np.uint32)
        self._arrays = [a for a in self._arrays if a.size == words][-3:] + [array]
        for candidate in self._arrays:
            if candidate is array:
                self._unshared_refs = sys.getrefcount(candidate)
        return array

    def release(self) -> None:
        self._arrays = []
        for variants in self.variants.values():
            variants.release()
        self.variants = {}
        self.bad.release()
        if self.out is not None:
            self.out.release()
            self.out = None
