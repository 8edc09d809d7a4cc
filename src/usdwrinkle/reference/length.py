"""The length pass (shaders/length.glsl) in numpy: per vertex, the largest scale s <= 1 of
its folds at which the blend of the corner waves over the triangles around it draws no more
than the cloth's rest area there (less the drawn folds' slack, DRAWN_SLACK of
wrinkle:slack, plus LENGTH_TOLERANCE), ramped in with that slack's ramp; 1 where the blend
is one plane wave (docs/method.md, "The cloth's length"). One wave system, regular folds,
no band limit: what tests/test_length.py checks the shader against."""
from __future__ import annotations

import numpy as np

from ..method.contract import (
    DRAWN_SLACK,
    LENGTH_MIN_SLOPE,
    LENGTH_SAMPLES,
    LENGTH_SNAP,
    LENGTH_TOLERANCE,
    SLACK_RAMP,
)
from .blend import blend_at, weight_gradients


def sample_points(m: int) -> np.ndarray:
    """(m^2, 3): the barycentrics of the centroids of a triangle's m x m sub-triangles, in
    the shader's order (cell (a, b) with a + b < m: its upward sub-triangle, then its
    downward one where there is one)."""
    out = []
    for a in range(m):
        for b in range(m - a):
            for down in (0, 1):
                if down and a + b + 1 >= m:
                    continue
                u, v = (np.array([a, b], float) + (2.0 if down else 1.0) / 3.0) / m
                out.append((1.0 - u - v, u, v))
    return np.array(out)


def _solve(gg: np.ndarray, weight: np.ndarray, target: float) -> float:
    """The largest s in [0, 1] with sum w sqrt(1 + s^2 |g|^2 + 2 s g.d + |d|^2) <=
    ``target`` (``gg``: per sample |g|^2, g.d, |d|^2), by bisection; 1 where s = 1 does."""
    def drawn(s):
        return np.sum(weight * np.sqrt(1 + s * s * gg[:, 0] + 2 * s * gg[:, 1] + gg[:, 2]))

    if drawn(1.0) <= target:
        return 1.0
    low, high = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (mid, high) if drawn(mid) <= target else (low, mid)
    return 0.5 * (low + high)


def _area(points: np.ndarray, triangles: np.ndarray) -> float:
    """The summed area of ``triangles`` (rows of corners) over ``points``."""
    e1 = points[triangles[:, 1]] - points[triangles[:, 0]]
    e2 = points[triangles[:, 2]] - points[triangles[:, 0]]
    return float(0.5 * np.linalg.norm(np.cross(e1, e2), axis=1).sum())


def _smoothstep(low: float, high: float, x: float) -> float:
    t = min(max((x - low) / (high - low), 0.0), 1.0)
    return t * t * (3 - 2 * t)


def length_scales(rest: np.ndarray, posed: np.ndarray, triangles: np.ndarray,
                  waves: np.ndarray, phases: np.ndarray, height: np.ndarray,
                  gradient: np.ndarray, slack: float, deepen: np.ndarray | None = None
                  ) -> np.ndarray:
    """(n,): each vertex's scale. ``rest`` and ``posed`` (n, 3); ``triangles`` (m, 3)
    corners; ``waves`` (n, 4) each vertex's drawn wave (k, a); ``phases`` (n,) its relaxed
    phase; ``height`` and ``gradient`` the profile tables; ``slack`` wrinkle:slack (the
    allowance takes the drawn folds' share of it, DRAWN_SLACK);
    ``deepen`` (n, 4) the pleats' offset and its gradient (None: none), which the blend
    carries unscaled."""
    slack = DRAWN_SLACK * slack
    rest = np.asarray(rest, np.float64)
    posed = np.asarray(posed, np.float64)
    waves = np.asarray(waves, np.float64)
    phases = np.asarray(phases, np.float64)
    triangles = np.asarray(triangles)
    n = len(posed)
    incident = [[] for _ in range(n)]
    for t, tri in enumerate(triangles):
        for c in tri:
            incident[int(c)].append(t)
    out = np.ones(n)
    for i in range(n):
        a_i = waves[i, 3]
        ring = incident[i]
        if not a_i * np.linalg.norm(waves[i, :3]) >= LENGTH_MIN_SLOPE or not ring:
            continue
        rest_area = _area(rest, triangles[ring])
        posed_area = _area(posed, triangles[ring])
        ratio = posed_area / max(rest_area, 1e-30)
        onset = (_smoothstep(1 - SLACK_RAMP * slack, 1 - slack, ratio) if slack > 0
                 else float(ratio >= 1))
        if not onset < 1:
            continue
        target = max((1 - slack * onset) * rest_area, posed_area)
        cap = max(int(np.floor(np.sqrt(LENGTH_SAMPLES / len(ring)))), 1)
        gg, weight = [], []
        apart, reference = 0.0, 0.0
        for t in ring:
            tri = triangles[t]
            corners = posed[tri]
            face = np.cross(corners[1] - corners[0], corners[2] - corners[0])
            area = 0.5 * np.linalg.norm(face)
            if not area > 0:
                continue
            normal = face / (2 * area)
            w = waves[tri].copy()
            ph = phases[tri].copy()
            for c in (1, 2):  # sign-aligned to corner 0 (wave.glsl's corner_waves)
                if w[c, :3] @ w[0, :3] < 0:
                    w[c, :3] *= -1
                    ph[c] *= -1
            reach = max(np.linalg.norm(corners[1] - corners[0]),
                        np.linalg.norm(corners[2] - corners[1]),
                        np.linalg.norm(corners[0] - corners[2]))
            lengths = np.linalg.norm(w[:, :3], axis=1)
            k_max = lengths[w[:, 3] > 0].max(initial=0.0)
            m = min(max(int(np.ceil(4 * k_max * reach / (2 * np.pi))), 2), cap)
            bary = sample_points(m)
            points = bary @ corners
            g = blend_at(w, ph, corners, bary, points, height, gradient)[1]
            g -= np.outer(g @ normal, normal)
            d = np.zeros_like(g)
            if deepen is not None:
                o = np.asarray(deepen, np.float64)[tri]
                carried = o[:, 0][None] + np.einsum("cj,scj->sc", o[:, 1:],
                                                    points[:, None] - corners[None])
                d = bary @ o[:, 1:] + carried @ weight_gradients(corners)
                d -= np.outer(d @ normal, normal)
            mine = int(np.flatnonzero(tri == i)[0])
            # the reference: corners that agree, each carrying vertex i's wave (its k, its
            # phase carried to the corner) at the corner's own slope
            k_i = w[mine, :3]
            agree = np.column_stack([np.tile(k_i, (3, 1)),
                                     w[:, 3] * lengths / np.linalg.norm(k_i)])
            agree_phases = ph[mine] + (corners - corners[mine]) @ k_i
            g_ref = blend_at(agree, agree_phases, corners, bary, points, height,
                             gradient)[1]
            g_ref -= np.outer(g_ref @ normal, normal)
            apart += np.sum((g - g_ref) ** 2)
            reference += np.sum(g_ref ** 2)
            gg.append(np.stack([np.sum(g * g, 1), np.sum(g * d, 1), np.sum(d * d, 1)], 1))
            weight.append(np.full(len(bary), area / m ** 2))
        if not gg:
            continue
        gg, weight = np.concatenate(gg), np.concatenate(weight)
        if apart <= LENGTH_SNAP ** 2 * reference:
            continue  # one plane wave over the ring: the law's own
        target *= 1 + LENGTH_TOLERANCE  # the samples' own error is no reason to scale
        out[i] = 1 + (1 - onset) * (_solve(gg, weight, target) - 1)
    return out
