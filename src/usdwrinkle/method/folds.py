"""The fold law beyond the paper, in numpy (docs/method.md, "Folds that read as cloth"):
what the crush pass computes per vertex from the compression, written once for the CPU
side (the numpy reference, the tests, the benchmarks). numpy only: the render layer reads
the profile's slope table from here.

- **Inextensible.** Along the compression a posed length of cloth holds ``rho`` times as
  much material (its excess length): the mesh's compression beyond the slack, times what
  a painted gather adds. The wave restores exactly that length for the mesh's profile H:
  its slope ``a |k|`` solves ``mean sqrt(1 + (a |k| H')^2) = rho`` (slope_table). Where
  the mesh is compressed across the wave too, the slope restores the area instead
  (``area_excess``: the compression across joins, down to ACROSS_MIN); the surface
  draws it lowered where the mesh is stretched across beyond STRETCH_ONSET, up to
  ACROSS_MAX (``drawn_excess``).
- **Two slacks.** The drawn fold takes the slack contract.DRAWN_SLACK x wrinkle:slack;
  the wave (its coarsening) and the fold the relaxation weighs the phases by take
  wrinkle:slack itself (reference/crush.py; docs/method.md, "folds drawn before the crests
  settle"). The functions here take the slack they are given.
- **Coarsening.** ``L = W min(rho^COARSENING_EXPONENT, COARSENING_MAX)``: the cloth
  referee's folds widen under compression while their posed wavelength stays about
  constant (docs/physics.md); exponent 1 keeps the posed wavelength at W up to rho =
  COARSENING_MAX. A steeper law (exponent 2, the best fit to the curtain alone) moved
  crests on 20% of the shirt's pixels for a 0.01 degree joint change (bar 2%).
- **Room.** A fold rises at most FOLD_ROOM of the distance over which the posed normals
  turn by a radian (and of the surface's radius of curvature): a fold displaced along
  converging normals that rises more passes through its neighbour.
"""
from __future__ import annotations

import numpy as np

from .contract import (
    ACROSS_MAX,
    ACROSS_MIN,
    COARSENING_EXPONENT,
    COARSENING_MAX,
    CURVED_COARSENING,
    MIN_RATIO,
    ONE_WAY,
    PAINT_GATHER_MAX,
    SLACK_RAMP,
    SLOPE_SAMPLES,
    SLOPE_STEP,
    STRETCH_ONSET,
)


def gradient_of(height: np.ndarray) -> np.ndarray:
    """dH/dtheta of a periodic profile sampled uniformly over [0, 2pi) (float64)."""
    height = np.asarray(height, dtype=np.float64)
    step = 2 * np.pi / len(height)
    return (np.roll(height, -1) - np.roll(height, 1)) / (2 * step)


def length_of(gradient: np.ndarray, slope) -> np.ndarray:
    """The arc length of ``a H(k x)`` per unit of its posed length, for slopes ``a |k|``
    (any shape): mean_theta sqrt(1 + (a |k| H'(theta))^2)."""
    g2 = np.asarray(gradient, np.float64) ** 2
    slope = np.asarray(slope, np.float64)
    return np.sqrt(1.0 + slope[..., None] ** 2 * g2).mean(axis=-1)


def slope_table(height: np.ndarray, samples: int = SLOPE_SAMPLES,
                step: float = SLOPE_STEP) -> np.ndarray:
    """The inextensible wave of a profile: for u_i = i * step (i < samples), the slope
    ``a |k|`` whose wave is sqrt(1 + u_i^2) times as long as its posed length,
    (samples,) float32. The crush pass reads it at u = sqrt(rho^2 - 1) and extrapolates
    linearly beyond the last sample (the slope grows as u / mean |H'| there). For the
    triangle it is (pi / 2) u: the paper's zigzag law. H' is derived from the height."""
    gradient = gradient_of(height)
    target = np.sqrt(1.0 + (np.arange(samples) * step) ** 2)
    mean_abs = max(float(np.abs(gradient).mean()), 1e-12)
    low = np.zeros(samples)
    high = target / mean_abs * 2.0 + 1.0
    for _ in range(80):  # bisection: the length grows monotonically with the slope
        middle = 0.5 * (low + high)
        longer = length_of(gradient, middle) > target
        high = np.where(longer, middle, high)
        low = np.where(longer, low, middle)
    return (0.5 * (low + high)).astype(np.float32)


def profile_slope(table: np.ndarray, rho) -> np.ndarray:
    """The table's slope at excess length ``rho`` (linear, as the crush pass reads it)."""
    table = np.asarray(table, np.float64)
    u = np.sqrt(np.maximum(np.asarray(rho, np.float64) ** 2 - 1.0, 0.0)) / SLOPE_STEP
    i = np.minimum(np.floor(u).astype(np.int64), len(table) - 2)
    return table[i] + (u - i) * (table[i + 1] - table[i])


def excess_length(r, r_geo, slack: float) -> np.ndarray:
    """rho: the material a posed length of the wave holds. ``r``: the compression along
    the wave with the painted q, ``r_geo``: the mesh's alone (both in [MIN_RATIO, 1]).
    The mesh's share restores ``restored(r_geo, slack)`` of the rest length; the painted
    gather (r_geo / r, at most PAINT_GATHER_MAX) adds its own."""
    r = np.asarray(r, np.float64)
    r_geo = np.asarray(r_geo, np.float64)
    # r = 0 (a paint of amount 1 in numpy's hands; the shaders clamp r to MIN_RATIO):
    # the gather's cap, without a division by zero
    gather = np.divide(r_geo, r, out=np.full(np.broadcast(r_geo, r).shape, np.inf),
                       where=r > 0)
    return np.maximum(1.0, restored(r_geo, slack) / r_geo) * \
        np.minimum(gather, PAINT_GATHER_MAX)


def area_excess(r, r_geo, across, slack: float) -> np.ndarray:
    """The excess length the fold's slope restores: ``excess_length`` with the mesh's
    compression ``r_geo * across`` in place of ``r_geo`` (``across``: the mesh's
    compression across the wave, clipped to [ACROSS_MIN, 1]), so that where the cloth is
    compressed both ways one wave restores its area. Never less than excess_length."""
    r = np.asarray(r, np.float64)
    r_geo = np.asarray(r_geo, np.float64)
    across = np.clip(np.asarray(across, np.float64), ACROSS_MIN, 1.0)
    # scaling r and r_geo alike keeps the painted gather r_geo / r as it is
    return np.maximum(excess_length(r, r_geo, slack),
                      excess_length(r * across, r_geo * across, slack))


def drawn_excess(r, r_geo, across, slack: float) -> np.ndarray:
    """The excess length of the fold the surface draws: ``area_excess`` with a stretch
    across the wave beyond STRETCH_ONSET counted too (``across`` below 1 clipped to
    [ACROSS_MIN, 1], above it divided by STRETCH_ONSET and clipped to [1, ACROSS_MAX]):
    where the mesh is stretched across by more than a wrinkling cloth stretches itself,
    the posed surface holds that share of the cloth's area already. The relaxation
    weighs the phases by ``area_excess``'s fold."""
    r = np.asarray(r, np.float64)
    r_geo = np.asarray(r_geo, np.float64)
    across = np.asarray(across, np.float64)
    across = np.where(across < 1.0, np.clip(across, ACROSS_MIN, 1.0),
                      np.clip(across / STRETCH_ONSET, 1.0, ACROSS_MAX))
    return excess_length(r * across, r_geo * across, slack)


def restored(r_geo, slack: float) -> np.ndarray:
    """The share of the rest length that folds restore where the mesh is compressed to
    ``r_geo``: the cloth takes the first ``slack`` in-plane, so folds begin at r = 1 -
    slack (restoring 1 - slack); from r = 1 - SLACK_RAMP slack on they restore all of
    it, a smoothstep between. The wrinkled surface keeps at least 1 - slack of its rest
    area, all of it where the cloth is clearly compressed."""
    r_geo = np.asarray(r_geo, np.float64)
    if slack <= 0.0:
        return np.ones_like(r_geo)
    t = np.clip((r_geo - (1.0 - SLACK_RAMP * slack)) / ((SLACK_RAMP - 1.0) * slack), 0.0, 1.0)
    return 1.0 - slack * t * t * (3.0 - 2.0 * t)


def _smoothstep(low: float, high: float, x) -> np.ndarray:
    t = np.clip((np.asarray(x, np.float64) - low) / (high - low), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def coarsening_cap(width, tube, one_way=1.0) -> np.ndarray:
    """The most the mesh's compression coarsens a point's folds: COARSENING_MAX on flat
    cloth, falling to 1 (none) by (smoothstep(CURVED_COARSENING[:2], ``width`` / ``tube``)
    - smoothstep(CURVED_COARSENING[2:], ``width`` / ``tube``)) times smoothstep(ONE_WAY,
    ``one_way``): ``tube`` the fold wavelength of a tube of the point's rest radius of
    curvature (scene/params.tube_width, in width's units; inf on flat cloth), ``one_way``
    how one way the surface curves around it (scene/topology.one_way). Where W is about
    the tube's own wavelength, the curvature sets the folds and they do not coarsen; pleats,
    and W far from the tube's, coarsen as flat cloth does (contract.CURVED_COARSENING)."""
    ratio = np.asarray(width, np.float64) / np.maximum(np.asarray(tube, np.float64), 1e-300)
    low, high, fading, gone = CURVED_COARSENING
    held = (_smoothstep(low, high, ratio) - _smoothstep(fading, gone, ratio)) \
        * _smoothstep(*ONE_WAY, one_way)
    return COARSENING_MAX - (COARSENING_MAX - 1.0) * held


def material_wavelength(width, rho, cap=COARSENING_MAX) -> np.ndarray:
    """L = W min(rho^COARSENING_EXPONENT, cap) (W where nothing folds): the folds coarsen
    with the length they restore, the mesh's and the paint's, up to ``cap``
    (coarsening_cap: COARSENING_MAX on flat cloth, 1 where it curves one way)."""
    rho = np.maximum(np.asarray(rho, np.float64), 1.0)
    return np.asarray(width, np.float64) * np.minimum(rho ** COARSENING_EXPONENT,
                                                      np.asarray(cap, np.float64))


def height_bound(table: np.ndarray, slack: float = 0.0) -> float:
    """The tallest fold the law draws, over W (on flat cloth, before the amplitude scale):
    the largest slope(rho_area) r_geo L / (2 pi W) over every compression r_geo in
    [MIN_RATIO, 1], painted gather up to PAINT_GATHER_MAX and compression across in
    [ACROSS_MIN, 1]."""
    r_geo = np.linspace(MIN_RATIO, 1.0, 2001)[:, None, None]
    gather = np.linspace(1.0, PAINT_GATHER_MAX, 41)[None, :, None]
    across = np.linspace(ACROSS_MIN, 1.0, 7)[None, None, :]
    rho = excess_length(r_geo / gather, r_geo, slack)
    slope = profile_slope(table, area_excess(r_geo / gather, r_geo, across, slack))
    height = slope * r_geo * material_wavelength(1.0, rho) / (2 * np.pi)
    return float(np.where(rho > 1.0, height, 0.0).max())
