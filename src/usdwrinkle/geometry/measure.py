"""Measures of displaced geometry: the plane wave along a line, and length restoration.

Wrinkles exist because cloth keeps its length while its support shrinks; a displaced
mesh makes that measurable. Used by the tests (against the derivation in
``profiles.length_ratio``) and by ``python -m benchmarks.lengths`` (the table in
docs/method.md).
"""
from __future__ import annotations

import numpy as np


def polyline_length(points: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(points, axis=0), axis=1).sum())


def clipped_length(x: np.ndarray, z: np.ndarray, start: float, end: float) -> float:
    """Arc length of the graph (x, z(x)) between x = start and x = end (x increasing),
    the ends interpolated."""
    inside = (x > start) & (x < end)
    xs = np.concatenate([[start], x[inside], [end]])
    zs = np.concatenate([[np.interp(start, x, z)], z[inside], [np.interp(end, x, z)]])
    return polyline_length(np.stack([xs, zs], 1))


def plane_wave(x: np.ndarray, h: np.ndarray) -> tuple[float, float]:
    """(amplitude, wavelength) of a sampled wave h(x): the largest |h|, and the mean
    spacing of its upward zero crossings (interpolated)."""
    order = np.argsort(x)
    x, h = x[order], h[order]
    up = np.flatnonzero((h[:-1] < 0) & (h[1:] >= 0))
    crossings = x[up] - h[up] * (x[up + 1] - x[up]) / (h[up + 1] - h[up])
    wavelength = float(np.diff(crossings).mean()) if len(crossings) > 1 else float("nan")
    return float(np.abs(h).max(initial=0.0)), wavelength


def length_ratio_along(x: np.ndarray, z: np.ndarray, ratio: float, width: float,
                       start: float, periods: int) -> float:
    """Displaced length over rest length of ``periods`` whole wavelengths (r W each, rest
    length W each) of the graph (x, z) from ``start``."""
    order = np.argsort(x)
    end = start + periods * ratio * width
    return clipped_length(x[order], z[order], start, end) / (periods * width)
