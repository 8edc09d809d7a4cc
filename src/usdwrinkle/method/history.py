"""The wave history as data: which grid frames' wave states an engine keeps, and where.

A frame's relaxation starts from the wave state of the shot's previous grid frame
(docs/method.md, "The wave state"). The GPU holds the states in numbered slots
(render/fields.py); this bookkeeping, free of GL and USD, says which slot holds which grid
frame. A frame reads one slot and writes another, so computing a frame twice from one
state gives the same frame twice; recording a computed grid frame as a state
(:meth:`WaveHistory.commit`) is a separate step. The states kept are the most recently
used ones, at most ``capacity``: stepping back a frame, or redrawing one, replays nothing.
"""
from __future__ import annotations

import math
from collections import OrderedDict

#: grid states an engine keeps by default (a viewer scrubbing near its frame replays
#: nothing; a straight run needs one)
HISTORY_CACHE_FRAMES = 8
#: the GPU memory the kept states may take, all meshes together (bytes)
HISTORY_CACHE_BYTES = 256 << 20


def cache_capacity(bytes_per_state: int, frames: int = HISTORY_CACHE_FRAMES,
                   budget: int = HISTORY_CACHE_BYTES) -> int:
    """How many states to keep: ``frames``, fewer where they would take more than
    ``budget`` bytes, and never less than one (the frame a straight run reads)."""
    if bytes_per_state <= 0:
        return max(1, frames)
    return max(1, min(frames, budget // bytes_per_state))


class WaveHistory:
    """Grid frame (as its index on the grid: frame - start) -> slot, least recently
    used first. Slots run from 0 to ``capacity``: ``capacity`` kept states and one that
    a frame writes."""

    def __init__(self, capacity: int = HISTORY_CACHE_FRAMES):
        if capacity < 1:
            raise ValueError(f"a wave history keeps at least one state, not {capacity}")
        self.capacity = capacity
        self._states: OrderedDict[int, int] = OrderedDict()
        #: the grid index last recorded (None: nothing since the last clear)
        self.last: int | None = None

    def __len__(self) -> int:
        return len(self._states)

    def __contains__(self, index: int) -> bool:
        return index in self._states

    @property
    def indices(self) -> list[int]:
        """The grid indices held, in ascending order."""
        return sorted(self._states)

    @property
    def slots(self) -> int:
        """The slots a mesh needs: one per kept state and one to write."""
        return self.capacity + 1

    def clear(self) -> None:
        """Forget every state (an edit that changes what every frame computes)."""
        self._states.clear()
        self.last = None

    def slot(self, index: int) -> int | None:
        """The slot of grid frame ``index`` (marked as used), or None."""
        if index not in self._states:
            return None
        self._states.move_to_end(index)
        return self._states[index]

    def nearest_below(self, index: int) -> int | None:
        """The largest grid index held that is at most ``index``, or None."""
        held = [i for i in self._states if i <= index]
        return max(held) if held else None

    def work_slot(self, keep: int | None = None) -> int:
        """A slot holding no kept state and not ``keep`` (the slot being read): where a
        frame writes. One always exists among ``slots``."""
        used = set(self._states.values())
        if keep is not None:
            used.add(keep)
        for slot in range(self.slots + 1):
            if slot not in used:
                return slot
        raise AssertionError("no free wave-state slot")  # capacity + 1 slots, <= capacity used

    def commit(self, index: int, slot: int) -> None:
        """Record that ``slot`` holds grid frame ``index``'s state (the chain advanced to
        it); the least recently used state beyond the capacity is dropped."""
        self._states.pop(index, None)
        for held, held_slot in list(self._states.items()):
            if held_slot == slot:
                del self._states[held]
        self._states[index] = slot
        self.last = index
        while len(self._states) > self.capacity:
            self._states.popitem(last=False)


def on_grid(frame: float | None, start: float | None) -> bool:
    """Whether ``frame`` is a frame of the history's grid start, start + 1, ..."""
    return start is not None and frame is not None and frame >= start and \
        float(frame - start).is_integer()


def reads_index(frame: float | None, start: float) -> int | None:
    """The grid index whose state ``frame`` starts from: the grid frame before it (f - 1
    on the grid, the grid frame below a sub-frame), or None for the shot's first frame
    and frames before it (a cold start)."""
    if frame is None:
        return None
    offset = frame - start
    if offset <= 0:
        return None
    return math.ceil(offset) - 1
