"""Resolve pass: the drawn (multisampled) attachments -> the pixels a reader needs, at
the precision it keeps them, in one compute dispatch (shaders/resolve.glsl).

Before, each attachment was resolved by a blit into a float texture, read back whole
and finished in numpy (coverage division, normalised normals, depth of empty pixels,
the sRGB encode or the concatenation and half conversion of the encoder). On llvmpipe
that was 25 ms of a 640x360 CesiumMan frame; the pass does it in about 8 ms, and an EXR
frame comes back as the planes its file stores, a PNG frame as its 8-bit codes.
"""
from __future__ import annotations

import threading

import numpy as np

from ..images.aovs import (  # noqa: F401  (re-exported: the pass's own names for its tables)
    AOV_BLOCKS,
    AOVS,
    EXR_CHANNELS,
    HALF_CHANNELS,
    OFFSET_SLOTS,
    ImageLayout,
    ResolvedImage,
)
from . import bindings
from .glcalls import GLCalls, MappedBuffer
from .shaders import Variants, compute_shader


def _plan(layout: ImageLayout, n: int) -> tuple[list[int], int, list]:
    """(the shader's u_offset, total words, [(name, first word, dtype, shape)]). An EXR
    channel the layout leaves out has the offset -1: the shader skips it."""
    offsets, views, word = [], [], 0
    if layout.kind == "aovs":
        for name in AOV_BLOCKS:
            count = len(AOVS[name][2])
            offsets.append(word)
            if name in layout.aovs:
                views.append((name, word, np.float32, count))
            word += n * count if AOVS[name][0] in layout.attachments else 0
    elif layout.kind == "exr":
        chosen = layout.channels
        for name in EXR_CHANNELS:
            if name not in chosen:
                offsets.append(-1)
                continue
            half = layout.half and name in HALF_CHANNELS
            offsets.append(word)
            views.append((name, word, np.float16 if half else np.float32, 1))
            word += (n + 1) // 2 if half else n
    else:
        views.append(("RGBA", 0, np.uint8, 4))
        word = n
    offsets += [0] * (OFFSET_SLOTS - len(offsets))
    return offsets, word, views


def read_rect(layout: ImageLayout | None, width: int, height: int,
              rect=None) -> tuple[int, int, int, int]:
    """The pixels (x0, y0, x1, y1; x1, y1 exclusive) that the resolve reads for ``layout``
    when ``rect`` (None: all) is what was drawn into; Framebuffer.begin clears exactly
    these. An EXR frame's half planes hold two neighbouring pixels per 32-bit word, so
    its rectangle is widened to even columns; an odd-width EXR frame's pairs straddle
    rows, so it is read whole."""
    x0, y0, x1, y1 = (0, 0, width, height) if rect is None else (int(v) for v in rect)
    if x1 <= x0 or y1 <= y0:
        return (0, 0, 0, 0)
    if layout is not None and layout.kind == "exr":
        if width % 2:
            return (0, 0, width, height)
        return (x0 - x0 % 2, y0, x1 + x1 % 2, y1)
    return (x0, y0, x1, y1)


def _grid(layout: ImageLayout, width: int, height: int, rect) -> tuple[tuple, int, int]:
    """(the rectangle of cells the shader resolves, the grid's width, pixels per cell):
    ``rect`` (read_rect's), in pixels, or for EXR in pixel pairs; an odd-width EXR frame
    is one row of all its pixels."""
    if layout.kind != "exr":
        return rect, width, 1
    if width % 2:
        n = width * height
        return (0, 0, n + n % 2, 1), n + n % 2, 2
    return rect, width, 2


def _empty_value(layout: ImageLayout, name: str):
    """What a pixel that nothing covers holds in plane ``name``."""
    if name in ("Z", "depth"):
        return np.inf
    if layout.kind == "8bit" and layout.over_black:
        return np.array([0, 0, 0, 255], np.uint8)  # black, opaque
    return 0


def _fill_outside(plane: np.ndarray, rect, value) -> None:
    """Write ``value`` into the pixels of ``plane`` (height, width[, channels]) outside
    ``rect`` (x0, y0, x1, y1), which the shader did not write."""
    x0, y0, x1, y1 = rect
    height, width = plane.shape[:2]
    if (x0, y0, x1, y1) == (0, 0, width, height):
        return
    plane[:y0] = value
    plane[y1:] = value
    plane[y0:y1, :x0] = value
    plane[y0:y1, x1:] = value


#: the most readback buffers a ring may have (``render --readback-buffers``)
MAX_RING = 8


#: GL_CLIENT_MAPPED_BUFFER_BARRIER_BIT: shader writes reach a persistent mapping
_CLIENT_MAPPED_BARRIER = 0x4000


class _Slot:
    """One readback buffer of the ring: the resolve's output (a persistently mapped
    buffer in client memory, render/glcalls.py, else a moderngl buffer), its bad-value
    counter, and the frame resolved into it and not yet read (None once read)."""

    def __init__(self, ctx):
        self.out = None
        self.bad = ctx.buffer(reserve=4)
        self.pending: PendingImage | None = None

    def reserve(self, ctx, words: int, calls) -> None:
        if self.out is None or self.out.size < words * 4:
            if self.out is not None:
                self.out.release()
                self.out = None
            size = max(words, 1) * 4
            if calls.mapped:
                try:
                    self.out = MappedBuffer(calls, size)
                except OSError:
                    calls.mapped = False  # the driver refused: moderngl's from now on
            if self.out is None:
                self.out = ctx.buffer(reserve=size)

    def release(self) -> None:
        if self.pending is not None:
            self.pending.discard()
        self.bad.release()
        if self.out is not None:
            self.out.release()
            self.out = None


class PendingImage:
    """A frame whose resolve is queued on the GPU, behind a fence. :meth:`start` waits for
    the fence (in the GL thread) and returns the frame's ResolvedImage, whose planes are
    copied out of the readback buffer on the pass's copy thread when the buffer is a
    mapped one (``background``), else at once; ``image.wait()`` waits for the copy.
    :meth:`result` is both, waited. The render loop starts a frame only after the next
    frame's work is queued, so the GPU computes that frame while the CPU copies this one,
    and the copy overlaps the render loop. ``wait_ms``: the time waited for the fence (the
    GPU still busy); the image's ``read_ms``: the copy."""

    def __init__(self, owner: ResolvePass, slot: _Slot, fence, words: int, views, layout,
                 size, rect):
        self._owner, self._slot, self._fence = owner, slot, fence
        self._words, self._views, self._layout = words, views, layout
        self._size, self._rect = size, rect
        self._image: ResolvedImage | None = None
        self.wait_ms = 0.0

    def start(self, background: bool = False) -> ResolvedImage:
        if self._image is None:
            import time

            started = time.perf_counter()
            if self._fence is not None:
                calls = GLCalls.get()
                calls.wait(self._fence)
                calls.delete(self._fence)
                self._fence = None
            self.wait_ms = (time.perf_counter() - started) * 1e3
            self._image = self._owner._read(self._slot, self._words, self._views,
                                            self._layout, self._size, self._rect, background)
        return self._image

    def result(self) -> ResolvedImage:
        image = self.start()
        self.finish()
        return image

    def finish(self) -> None:
        """Wait until the frame is out of its readback buffer (which may then be reused)."""
        if self._image is None:
            self.start()
        self._image.wait()
        if self._slot.pending is self:
            self._slot.pending = None

    def discard(self) -> None:
        """Drop the frame unread (an interrupted loop): its fence is deleted, a copy under
        way is waited for (the buffer it reads may be released next)."""
        if self._fence is not None:
            GLCalls.get().delete(self._fence)
            self._fence = None
        if self._image is not None:
            try:
                self._image.wait()
            except Exception:  # noqa: BLE001 - dropped anyway; the loop's error goes on
                pass
        if self._slot.pending is self:
            self._slot.pending = None


class ResolvePass:
    """Compiles one shader variant per (samples, layout) on first use. Resolves into a
    ring of readback buffers (``run``'s ``ring``): a frame resolved into one is read
    from it while the next frames are computed into the others."""

    def __init__(self, ctx):
        self.ctx = ctx
        self.defines = {**bindings.COMMON, **bindings.RESOLVE, **bindings.RESOLVE_SHAPE}
        #: sample count -> the shader's variants (SAMPLES is a value, not a switch)
        self.variants: dict[int, Variants] = {}
        #: the readback buffers; the ring grows to the largest ``ring`` asked for
        self.slots: list[_Slot] = []
        self._next = 0
        #: the thread that copies frames out of mapped readback buffers (made on first use)
        self._copier = None
        #: readback arrays handed back by ResolvedImage.release, ready for a later
        #: frame (the writer thread releases, the render loop takes: hence the lock)
        self._free: list[np.ndarray] = []
        self._free_lock = threading.Lock()

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

    def _slot(self, ring: int) -> _Slot:
        """The next buffer of a ring of ``ring``; a frame still unread in it is read
        first (its caller gets it from its PendingImage as usual)."""
        ring = max(1, int(ring))
        while len(self.slots) < ring:
            self.slots.append(_Slot(self.ctx))
        slot = self.slots[self._next % ring]
        self._next = (self._next + 1) % ring
        if slot.pending is not None:  # read (or still being copied) before it is reused
            slot.pending.finish()
        return slot

    def run(self, targets: list, size: tuple[int, int], samples: int,
            layout: ImageLayout, rect=None, ring: int = 1) -> ResolvedImage | PendingImage:
        """Resolve ``targets`` (the three colour attachments, multisampled textures when
        ``samples`` > 1) into ``layout``; returns the frame's arrays. ``rect`` (x0, y0,
        x1, y1; None: all): the part of the targets drawn into and cleared, which must
        hold read_rect(layout, ..., rect); the pixels outside it are written empty,
        without reading the targets. ``ring`` > 1: resolve into the next of that many
        readback buffers and return a PendingImage, read when asked for."""
        width, height = size
        n = width * height
        offsets, words, views = _plan(layout, n)
        shader = self._shader(layout, samples)
        slot = self._slot(ring)
        calls = GLCalls.get(self.ctx)
        slot.reserve(self.ctx, words, calls)
        slot.bad.write(np.zeros(1, np.uint32).tobytes())
        for index in layout.attachments:
            targets[index].use(bindings.RESOLVE[("RESOLVE_COLOR", "RESOLVE_WRINKLE",
                                                 "RESOLVE_NORMAL")[index]])
        slot.out.bind_to_storage_buffer(bindings.RESOLVE["RESOLVE_OUT"])
        slot.bad.bind_to_storage_buffer(bindings.RESOLVE["RESOLVE_BAD"])
        shader["u_size"] = (width, height)
        rect = read_rect(layout, width, height, rect)
        grid, grid_width, step = _grid(layout, width, height, rect)
        shader["u_rect"] = grid
        if "u_grid_width" in shader:  # EXR's pairs only
            shader["u_grid_width"] = grid_width
        if "u_offset" in shader:  # the compiler keeps the elements the variant reads
            kept = shader["u_offset"].array_length
            shader["u_offset"] = offsets[:kept] if kept > 1 else offsets[0]
        invocations = (grid[2] - grid[0]) // step * (grid[3] - grid[1])
        if invocations:
            shader.run((invocations + bindings.LOCAL_SIZE - 1) // bindings.LOCAL_SIZE)
        if ring <= 1 and not calls.mapped:
            return self._read(slot, words, views, layout, size, rect)  # moderngl waits
        # the buffer is read by the CPU after the fence: make the shader's writes visible
        # to that read (glMemoryBarrier), then fence and flush
        self.ctx.memory_barrier(self.ctx.BUFFER_UPDATE_BARRIER_BIT | _CLIENT_MAPPED_BARRIER)
        slot.pending = PendingImage(self, slot, calls.fence(), words, views, layout, size,
                                    rect)
        return slot.pending if ring > 1 else slot.pending.result()

    def _read(self, slot: _Slot, words: int, views, layout: ImageLayout, size, rect,
              background: bool = False) -> ResolvedImage:
        """A resolved frame out of ``slot``, in arrays of its own: copied at once, or with
        ``background`` (and a mapped buffer, which needs no GL call to read) on the copy
        thread, the image's ``wait()`` waiting for it. numpy releases the GIL while it
        copies, so the render loop goes on meanwhile (a 1080p EXR frame's 54 MB took
        about 20 ms to copy on an H200 node)."""
        import time

        width, height = size
        n = width * height
        array = self._take_array(words)
        bad = int(np.frombuffer(slot.bad.read(), np.uint32)[0])
        planes = {}
        for name, first, dtype, channels in views:
            itemsize = np.dtype(dtype).itemsize
            count = n * channels
            flat = array.view(np.uint8)[first * 4:first * 4 + count * itemsize].view(dtype)
            planes[name] = flat.reshape((height, width, channels) if channels > 1 or
                                        layout.kind != "exr" else (height, width))
        image = ResolvedImage(layout, width, height, planes, bad,
                              _recycle=lambda: self._give_back(array))

        def copy() -> None:
            started = time.perf_counter()
            slot.out.read_into(array, size=words * 4)
            for name, plane in planes.items():
                _fill_outside(plane, rect, _empty_value(layout, name))
            image.read_ms = (time.perf_counter() - started) * 1e3

        if background and isinstance(slot.out, MappedBuffer):
            if self._copier is None:
                from concurrent.futures import ThreadPoolExecutor

                self._copier = ThreadPoolExecutor(1, thread_name_prefix="usdwrinkle-readback")
            image._ready = self._copier.submit(copy)
        else:
            copy()
        return image

    def _take_array(self, words: int) -> np.ndarray:
        """A uint32 array of ``words``: one that a released image handed back, else a new
        one. Reusing saves the page faults of fresh memory (2 ms per 330 kpixel float
        RGBA plane here, ten times the copy). An array is reused only after its image's
        explicit release (the writer's, once the file is written), never on a guess of
        who still holds it: an 8-bit frame still being encoded keeps its own pixels."""
        with self._free_lock:
            for index, array in enumerate(self._free):
                if array.size == words:
                    return self._free.pop(index)
        return np.empty(words, np.uint32)

    def _give_back(self, array: np.ndarray) -> None:
        with self._free_lock:
            # a few frames in flight at most; arrays of another size are of an old layout
            self._free = [a for a in self._free if a.size == array.size][-3:] + [array]

    def release(self) -> None:
        with self._free_lock:
            self._free = []
        for variants in self.variants.values():
            variants.release()
        self.variants = {}
        for slot in self.slots:
            slot.release()
        self.slots = []
        self._next = 0
        if self._copier is not None:
            self._copier.shutdown(wait=True)
            self._copier = None
