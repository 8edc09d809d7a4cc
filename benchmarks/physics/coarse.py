"""The coarse mesh an animator would have: the simulation low-pass filtered (a Gaussian of
``Shot.window``, shots.WINDOW = 5 cm unless the referee widened it, on the rest grid,
twiced) and every ``Shot.stride``-th grid line kept."""
from __future__ import annotations

import numpy as np

from .shots import Shot


def _kernel(sigma_samples: float) -> np.ndarray:
    radius = int(np.ceil(3 * sigma_samples))
    x = np.arange(-radius, radius + 1)
    k = np.exp(-0.5 * (x / sigma_samples) ** 2)
    return k / k.sum()


def _smooth_axis(values: np.ndarray, axis: int, sigma_samples: float, periodic: bool,
                 linear: bool = False):
    """Normalised Gaussian convolution along one axis. At an open border the weights are
    renormalised (``linear`` False), or each sample is the value at its own place of a line
    fitted by Gaussian-weighted least squares (``linear`` True: local-linear smoothing, which
    reproduces a linear ramp up to the border where the renormalised average pulls the
    border towards the inside by about 0.8 sigma times the slope). In the interior of the
    axis the two are the same Gaussian."""
    kernel = _kernel(sigma_samples)
    radius = len(kernel) // 2
    values = np.moveaxis(values, axis, 0)
    n = values.shape[0]
    shape = (n,) + (1,) * (values.ndim - 1)
    t0 = np.zeros_like(values, dtype=np.float64)
    t1 = np.zeros_like(values, dtype=np.float64)
    s0, s1, s2 = np.zeros(shape), np.zeros(shape), np.zeros(shape)
    for offset, w in zip(range(-radius, radius + 1), kernel, strict=True):
        if periodic:
            t0 += w * np.roll(values, -offset, axis=0)
            s0 += w
        else:
            lo, hi = max(0, -offset), min(n, n - offset)
            t0[lo:hi] += w * values[lo + offset:hi + offset]
            s0[lo:hi] += w
            if linear:
                t1[lo:hi] += (w * offset) * values[lo + offset:hi + offset]
                s1[lo:hi] += w * offset
                s2[lo:hi] += w * offset * offset
    if periodic or not linear:
        return np.moveaxis(t0 / s0, 0, axis)
    return np.moveaxis((s2 * t0 - s1 * t1) / (s0 * s2 - s1 * s1), 0, axis)


def lowpass(shot: Shot, points: np.ndarray, sigma: float | None = None) -> np.ndarray:
    """The rest pose plus the Gaussian-filtered displacement from it, on the rest grid:
    (..., n, 3) -> same shape. Filtering the displacement rather than the positions keeps
    a curved rest shape as it is (positions filtered around the sleeve would shrink its
    ring by 18%, a compression that the cloth does not have)."""
    lead = points.shape[:-2]
    moved = (points - shot.rest).reshape(*lead, shot.rows, shot.cols, 3).astype(np.float64)
    s = (shot.window if sigma is None else sigma) / shot.spacing

    def gauss(values):
        values = _smooth_axis(values, values.ndim - 3, s, False, True)
        return _smooth_axis(values, values.ndim - 2, s, shot.periodic, True)

    # twicing (Tukey): G + G(1 - G) = 2G - G^2. Folds (transfer G ~ 0 at 7 cm) are
    # removed as by G, but a bend on the filter's own scale keeps its shape: G alone
    # pulls the surface towards the inside of the elbow by about sigma^2 / (2 radius),
    # 1.2 cm on the sleeve, more than the folds are high
    once = gauss(moved)
    smooth = once + gauss(moved - once)
    return shot.rest + smooth.reshape(points.shape)


def coarse_indices(shot: Shot) -> tuple[np.ndarray, int, int]:
    """Fine indices of the coarse vertices, and the coarse grid's (rows, cols)."""
    rows = np.arange(0, shot.rows, shot.stride)
    cols = np.arange(0, shot.cols, shot.stride)
    if not shot.periodic:
        assert (shot.cols - 1) % shot.stride == 0
    assert (shot.rows - 1) % shot.stride == 0
    index = (rows[:, None] * shot.cols + cols[None, :]).ravel()
    return index, len(rows), len(cols)
