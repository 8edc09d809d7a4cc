"""The wave blend of include/wave.glsl (``blend_corner_waves``) in numpy: the corner waves
of a coarse triangle, weighted by their barycentrics, divided by their coherence
(docs/method.md, "Coherence") and held within the interpolated amplitude. No band limit.
tests/test_blend.py checks the shader against it; benchmarks/physics/blend.py and room.py
draw with it."""
from __future__ import annotations

import numpy as np

from ..method.contract import BLEND_COHERENCE_FLOOR


def profile(table: np.ndarray, theta) -> np.ndarray:
    """A profile table (height or gradient) read as the shaders read it: sample s at
    theta = 2 pi s / N, linear between samples, repeating."""
    table = np.asarray(table, np.float64)
    count = len(table)
    x = np.mod(np.asarray(theta, np.float64) / (2 * np.pi) * count, count)
    i = np.floor(x).astype(np.int64)
    f = x - i
    return table[i % count] * (1 - f) + table[(i + 1) % count] * f


def coherence_keep(total, magnitude) -> np.ndarray:
    """What the blend is multiplied by: total / max(|phasor|, BLEND_COHERENCE_FLOOR
    total), 1 where the weights sum to nothing or the corners agree."""
    total = np.asarray(total, np.float64)
    magnitude = np.asarray(magnitude, np.float64)
    lifted = (total > 0) & (magnitude < total)
    bound = np.maximum(np.maximum(magnitude, BLEND_COHERENCE_FLOOR * total), 1e-300)
    return np.where(lifted, total / bound, 1.0)


def blended_height(weighted: np.ndarray, theta: np.ndarray, height: np.ndarray
                   ) -> np.ndarray:
    """The blend's height over the last axis (the corners): ``weighted`` b_c a_c and
    ``theta`` per corner, ``height`` the profile table."""
    weighted = np.asarray(weighted, np.float64)
    raw = np.sum(weighted * profile(height, theta), axis=-1)
    total = weighted.sum(-1)
    magnitude = np.abs(np.sum(weighted * np.exp(1j * np.asarray(theta)), axis=-1))
    return np.clip(raw * coherence_keep(total, magnitude), -total, total)


def weight_gradients(corners: np.ndarray) -> np.ndarray:
    """(3, 3): the gradient of each barycentric weight over the triangle (wave.glsl's
    weight_gradient)."""
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    opposite = [corners[2] - corners[1], corners[0] - corners[2], corners[1] - corners[0]]
    return np.array([np.cross(normal, e) for e in opposite]) / normal.dot(normal)


def blend_at(waves: np.ndarray, phases: np.ndarray, corners: np.ndarray, bary: np.ndarray,
             p: np.ndarray, height: np.ndarray, gradient: np.ndarray):
    """One point's blend with its exact gradient (``exact_gradient`` in wave.glsl):
    ``waves`` (3, 4) the corners' (k, a), sign-aligned; ``phases`` (3,); ``corners``
    (3, 3) posed; ``bary`` its barycentrics; ``p`` the point. Returns (h, gradient,
    the coherence's factor)."""
    b = np.clip(bary, 0, 1)
    b = b / b.sum()
    k, a = waves[:, :3], waves[:, 3]
    theta = phases + np.einsum("cj,cj->c", k, p - corners)
    H, G = profile(height, theta), profile(gradient, theta)
    db = weight_gradients(corners)
    h = np.sum(b * a * H)
    g = np.einsum("c,cj->j", b * a * G, k) + np.einsum("c,cj->j", a * H, db)
    total = np.sum(b * a)
    phasor = np.array([np.sum(b * a * np.cos(theta)), np.sum(b * a * np.sin(theta))])
    magnitude = float(np.linalg.norm(phasor))
    keep = float(coherence_keep(total, magnitude))
    if keep == 1.0:
        return h, g, keep
    d_total = np.einsum("c,cj->j", a, db)
    if abs(h) * keep >= total:  # the crest held at the interpolated amplitude
        return np.sign(h) * total, np.sign(h) * d_total, keep
    if magnitude > BLEND_COHERENCE_FLOOR * total:
        d_cos = np.einsum("c,cj->j", a * np.cos(theta), db) \
            - np.einsum("c,cj->j", b * a * np.sin(theta), k)
        d_sin = np.einsum("c,cj->j", a * np.sin(theta), db) \
            + np.einsum("c,cj->j", b * a * np.cos(theta), k)
        d_magnitude = (phasor[0] * d_cos + phasor[1] * d_sin) / magnitude
        g = keep * g + h * (d_total - keep * d_magnitude) / magnitude
    else:
        g = keep * g
    return keep * h, g, keep
