"""The image contract: the AOVs a frame holds, the channels an EXR frame stores, which of
them ``half`` stores as half float, and the two records of a read-back frame. Defined
once here, below render/ (which resolves them; shaders/resolve.glsl gets OFFSET_SLOTS
injected) and outputs/ (which writes them): neither imports the other for them.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

#: AOV name -> (attachment, first channel, channel names in image files)
AOVS = {
    "color": (0, 0, ("R", "G", "B", "A")),
    "wrinkle.height": (1, 0, ("wrinkle.height",)),
    "wrinkle.amplitude": (1, 1, ("wrinkle.amplitude",)),
    "normal": (2, 0, ("N.X", "N.Y", "N.Z")),
    "depth": (1, 2, ("Z",)),
}
#: the order of the AOV blocks of the OUTPUT_AOVS layout (u_offset's order), of a frame's
#: AOVs and of an EXR's channel blocks
AOV_BLOCKS = tuple(AOVS)
#: an EXR frame's channels, one plane each, in the shader's plane order
EXR_CHANNELS = tuple(channel for aov in AOV_BLOCKS for channel in AOVS[aov][2])
#: the channels that ``half`` stores as half float: colour and normals
HALF_CHANNELS = ("R", "G", "B", "A", "N.X", "N.Y", "N.Z")
#: what render's ``--aovs`` lists: each AOV with the channels it stores
AOVS_TEXT = ", ".join(
    name if AOVS[name][2] == (name,) else f"{name} ({','.join(AOVS[name][2])})"
    for name in AOV_BLOCKS)


def parse_aovs(value: str | Iterable[str]) -> tuple[str, ...]:
    """``"color,depth"`` (or a list of names, each may hold commas) -> the AOV names in
    AOV_BLOCKS order; refuses an unknown name or none."""
    from ..process.errors import UsdWrinkleError

    texts = [value] if isinstance(value, str) else list(value)
    names = [part.strip() for text in texts for part in str(text).split(",") if part.strip()]
    unknown = [name for name in names if name not in AOVS]
    if unknown or not names:
        got = ", ".join(unknown) if unknown else "nothing"
        raise UsdWrinkleError(f"`aovs` takes a comma-separated list of {AOVS_TEXT} "
                              f"(got {got})")
    return tuple(name for name in AOV_BLOCKS if name in names)


def exr_channels(aovs: Iterable[str]) -> tuple[str, ...]:
    """The EXR channels that hold ``aovs``, in EXR_CHANNELS order."""
    chosen = set(aovs)
    return tuple(channel for aov in AOV_BLOCKS if aov in chosen for channel in AOVS[aov][2])


#: u_offset's length in resolve.glsl: one first word per EXR plane (the most blocks any
#: layout has)
OFFSET_SLOTS = max(len(EXR_CHANNELS), len(AOV_BLOCKS))


@dataclass(frozen=True)
class ImageLayout:
    """What a frame is read back as.

    ``kind``: "aovs" (float AOVs, for Framebuffer.read), "exr" (one plane per EXR
    channel, colour and normals as half float with ``half``) or "8bit" (RGBA sRGB codes,
    straight alpha; with ``over_black`` the colour over black, for JPEG).
    ``aovs``: the AOVs an "aovs" layout holds, or whose channels an "exr" layout holds
    (render ``--aovs``; every AOV by default).
    """

    kind: str
    aovs: tuple = tuple(AOVS)
    half: bool = False
    over_black: bool = False

    @property
    def attachments(self) -> frozenset:
        """The draw's attachments the resolve reads: colour always (its alpha is the
        coverage that the other AOVs are divided by)."""
        if self.kind == "8bit":
            return frozenset((0,))
        return frozenset(AOVS[name][0] for name in self.aovs) | {0}

    @property
    def channels(self) -> tuple[str, ...]:
        """The planes of an "exr" layout, in EXR_CHANNELS order."""
        return exr_channels(self.aovs) if self.kind == "exr" else ()


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
    #: hands the planes' memory back to the pass that made them (see :meth:`release`)
    _recycle: object = field(default=None, repr=False, compare=False)
    #: the copy of the planes out of the GPU's readback buffer, when it runs on another
    #: thread (render/resolve.py): a concurrent.futures.Future, or None when done
    _ready: object = field(default=None, repr=False, compare=False)
    #: ms the copy took
    read_ms: float = field(default=0.0, repr=False, compare=False)

    def wait(self) -> None:
        """Wait until the planes hold the frame (raises the copy's error)."""
        if self._ready is not None:
            self._ready.result()
            self._ready = None

    def release(self) -> None:
        """Say that nobody reads these planes any more: their memory may then hold a
        later frame. Only the writer calls it, after the file is written; an image that
        is never released keeps its own memory (nothing else ever writes into it)."""
        ready, self._ready = self._ready, None
        if ready is not None:  # a copy into these planes still running must end first
            ready.exception()
        recycle, self._recycle = self._recycle, None
        self.planes = {}
        if recycle is not None:
            recycle()
