"""Test helpers. The stage builders themselves live in usdwrinkle.authoring.builders,
shared with the sample generator and the benchmarks."""
from __future__ import annotations

import numpy as np

from usdwrinkle.authoring.builders import point_cache_stage  # noqa: F401


def rotation_matrix(axis, angle) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                     [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                     [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])


def read_until(stream, pattern, timeout: float) -> bytes:
    """Read a child's pipe (binary) until ``pattern`` (a bytes regex) matches what was
    read, and return it: tests signal a process on an event it reported, never after a
    guessed delay. Fails when the stream ends or ``timeout`` passes first."""
    import os
    import select
    import time

    data = b""
    deadline = time.monotonic() + timeout
    fd = stream.fileno()
    while not pattern.search(data):
        left = deadline - time.monotonic()
        assert left > 0, f"timed out waiting for {pattern.pattern!r}; got {data[-400:]!r}"
        ready, _, _ = select.select([fd], [], [], left)
        if ready:
            chunk = os.read(fd, 65536)
            assert chunk, f"the stream ended before {pattern.pattern!r}; got {data[-400:]!r}"
            data += chunk
    return data
