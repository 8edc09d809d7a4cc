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
