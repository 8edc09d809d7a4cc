"""The wave blend of include/wave.glsl (``blend_corner_waves``) in numpy: the corner waves
of a coarse triangle, weighted by their barycentrics, divided by their coherence
(docs/method.md, "Coherence") and held within the interpolated amplitude. No band limit.
tests/test_blend.py checks the shader against it; benchmarks/physics/blend.py and room.py
draw with it."""
from __future__ import annotations

import numpy as np

from ..method.contract import (
    BLEND_COHERENCE_FLOOR,
    IRREGULARITY_FACTOR_MAX,
    IRREGULARITY_FACTOR_MIN,
    IRREGULARITY_FIELDS,
    IRREGULARITY_TERMS,
    IRREGULARITY_TERMS_PER_FIELD,
)


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


#: each irregularity field's normalisation, sqrt(2 / m) over its m terms
_FIELD_NORM = np.sqrt(2.0 / IRREGULARITY_TERMS_PER_FIELD)


def _field_terms(scale: float) -> tuple[np.ndarray, np.ndarray]:
    """The fields' terms at 1 / Lambda = ``scale``: (omega (m, 3) rest-space radians a
    unit, psi (m,)), field by field (method/contract.py, IRREGULARITY_TERMS)."""
    terms = np.array([(*axis, psi) for axis, psi in IRREGULARITY_TERMS], np.float64)
    return 2 * np.pi * terms[:, :3] * scale, terms[:, 3]


def irregularity_field(points, scale: float):
    """The three irregularity fields over the rest surface (method/contract.py,
    IRREGULARITY_TERMS): N_i = sqrt(2 / m) sum_j sin(omega_ij . X + psi_ij), omega_ij =
    2 pi s_ij u_j ``scale`` (``scale`` = 1 / Lambda), at rest points ``points`` (..., 3);
    returns (N (..., 3), their rest-space gradients (..., 3 fields, 3))."""
    omega, psi = _field_terms(scale)
    phi = np.asarray(points, np.float64) @ omega.T + psi
    shape = (*phi.shape[:-1], IRREGULARITY_FIELDS, IRREGULARITY_TERMS_PER_FIELD)
    field = _FIELD_NORM * np.sin(phi).reshape(shape).sum(-1)
    cosines = np.cos(phi).reshape(shape)
    gradient = _FIELD_NORM * np.einsum("...ij,ijk->...ik", cosines,
                                       omega.reshape(IRREGULARITY_FIELDS, -1, 3))
    return field, gradient


def irregular_field(rest: np.ndarray, db: np.ndarray, b: np.ndarray, scale: float):
    """wave.glsl's ``irregular_field``: the fields N at the point of weights ``b`` of a
    triangle with rest corners ``rest`` (3, 3) and weight gradients ``db`` over its posed
    corners (weight_gradients), at 1 / Lambda = ``scale``; returns (N (3,), their posed
    gradients (3, 3), the terms' posed wave vectors q (m, 3) and sin(phi) (m,))."""
    omega, psi = _field_terms(scale)
    phi = omega @ (b @ rest) + psi
    q = np.outer(omega @ (rest[1] - rest[0]), db[1]) \
        + np.outer(omega @ (rest[2] - rest[0]), db[2])
    fields = (-1, IRREGULARITY_TERMS_PER_FIELD)
    field = _FIELD_NORM * np.sin(phi).reshape(fields).sum(-1)
    gradient = _FIELD_NORM * np.einsum("ij,ijk->ik", np.cos(phi).reshape(fields),
                                q.reshape(IRREGULARITY_FIELDS, -1, 3))
    return field, gradient, q, np.sin(phi)


def system_shift(directions, db, waves, b, field, field_gradient, q, sines, beta):
    """wave.glsl's ``system_shift`` and ``shift_hessian``: the phase shift m = beta u . N
    that every corner of the system takes at the point, u the direction of sum_c b_c a_c
    u_c (``directions`` (3, 3): the corners' unit rest directions u_c, sign-aligned with
    their waves, wave.glsl's CornerWaves.u; ``db`` the weights' gradients over the posed
    corners); returns (m, its posed gradient, its posed Hessian (3, 3)); zeros where no
    corner has a wave."""
    u_c = waves[:, 3:4] * np.asarray(directions, np.float64)
    v = b @ u_c
    V = np.einsum("ci,cj->ij", u_c, db)  # grad v
    rho, total = np.linalg.norm(v), float(b @ waves[:, 3])
    if not (rho > 1e-6 * total) or total <= 0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    u = v / rho
    projector = np.eye(3) - np.outer(u, u)
    grad_u = projector @ V / rho                      # (3 components, 3 directions)
    m = beta * u @ field
    gradient = beta * (u @ field_gradient + grad_u.T @ field)
    weights = np.repeat(u, IRREGULARITY_TERMS_PER_FIELD) * sines
    hessian = -_FIELD_NORM * np.einsum("j,ja,jb->ab", weights, q, q)      # sum_i u_i H_i
    hessian = hessian + field_gradient.T @ grad_u + grad_u.T @ field_gradient
    # N . u(p) with N held: the derivative of V^T (I - u u^T) N / rho along each direction
    uN = u @ field
    for w in range(3):
        du = grad_u[:, w]
        hessian[:, w] += V.T @ (-du * uN - u * (du @ field)) / rho \
            - V.T @ (field - u * uN) * (u @ V[:, w]) / rho ** 2
    return m, gradient, beta * hessian


def blend_at(waves: np.ndarray, phases: np.ndarray, corners: np.ndarray, bary: np.ndarray,
             p: np.ndarray, height: np.ndarray, gradient: np.ndarray,
             irregular: tuple | None = None):
    """The blend with its exact gradient (``exact_gradient`` in wave.glsl) at one point
    or at a batch of points of one triangle: ``waves`` (3, 4) the corners' (k, a),
    sign-aligned; ``phases`` (3,); ``corners`` (3, 3) posed; ``bary`` the barycentrics and
    ``p`` the point, (3,) each, or (s, 3) each for s points. ``irregular``: (the rest
    corners (3, 3), the corners' unit rest directions (3, 3; sign-aligned with their
    waves), beta, 1 / Lambda) for the IRREGULAR variant (wrinkle:irregularity;
    docs/method.md, "Irregular folds"). Returns (h, gradient, the coherence's factor):
    floats and a (3,) for one point, (s,), (s, 3) and (s,) for a batch."""
    single = np.ndim(bary) == 1
    b = np.clip(np.atleast_2d(np.asarray(bary, np.float64)), 0, 1)
    b = b / b.sum(1, keepdims=True)
    p = np.atleast_2d(np.asarray(p, np.float64))
    waves = np.asarray(waves, np.float64)
    count = len(b)
    k = np.repeat(waves[None, :, :3], count, 0)
    a = np.repeat(waves[None, :, 3], count, 0)
    theta = np.asarray(phases, np.float64)[None] \
        + np.einsum("scj,scj->sc", k, p[:, None] - corners[None])
    db = weight_gradients(corners)
    d_a = np.zeros((count, 3, 3))  # each corner amplitude's own gradient
    if irregular is not None:
        rest, directions, beta, scale = irregular
        rest = np.asarray(rest, np.float64)
        length = np.linalg.norm(waves[:, :3], axis=1)
        for n in range(count):
            field, field_gradient, q, sines = irregular_field(rest, db, b[n], scale)
            m, m_gradient, hessian = system_shift(directions, db, waves, b[n], field,
                                                  field_gradient, q, sines, beta)
            theta[n] += m
            k[n] += m_gradient
            local = np.linalg.norm(k[n], axis=1)
            ratio = np.where(length > 0, length / np.maximum(local, 1e-30), 1.0)
            factor = np.where(length > 0, np.clip(ratio, IRREGULARITY_FACTOR_MIN,
                                                  IRREGULARITY_FACTOR_MAX), 1.0)
            for c in range(3):
                if length[c] > 0 and \
                        IRREGULARITY_FACTOR_MIN < factor[c] < IRREGULARITY_FACTOR_MAX:
                    d_a[n, c] = a[n, c] * (-length[c] / local[c] ** 3 * hessian @ k[n, c])
            a[n] *= factor
    H, G = profile(height, theta), profile(gradient, theta)
    h = np.sum(b * a * H, 1)
    g = np.einsum("sc,scj->sj", b * a * G, k) + np.einsum("sc,cj->sj", a * H, db) \
        + np.einsum("sc,scj->sj", b * H, d_a)
    total = np.sum(b * a, 1)
    cos, sin = np.cos(theta), np.sin(theta)
    phasor = np.stack([np.sum(b * a * cos, 1), np.sum(b * a * sin, 1)], 1)
    magnitude = np.linalg.norm(phasor, axis=1)
    keep = coherence_keep(total, magnitude)
    d_total = np.einsum("sc,cj->sj", a, db) + np.einsum("sc,scj->sj", b, d_a)
    # the crest held at the interpolated amplitude; else the blend lifted by the coherence
    # (its gradient too, while the phasor stands above the floor)
    held = (keep != 1.0) & (np.abs(h) * keep >= total)
    lifted = (keep != 1.0) & ~held & (magnitude > BLEND_COHERENCE_FLOOR * total)
    d_cos = np.einsum("sc,cj->sj", a * cos, db) - np.einsum("sc,scj->sj", b * a * sin, k) \
        + np.einsum("sc,scj->sj", b * cos, d_a)
    d_sin = np.einsum("sc,cj->sj", a * sin, db) + np.einsum("sc,scj->sj", b * a * cos, k) \
        + np.einsum("sc,scj->sj", b * sin, d_a)
    safe = np.maximum(magnitude, 1e-300)[:, None]
    d_magnitude = (phasor[:, :1] * d_cos + phasor[:, 1:] * d_sin) / safe
    g = np.where(lifted[:, None],
                 keep[:, None] * g + h[:, None] * (d_total - keep[:, None] * d_magnitude)
                 / safe, keep[:, None] * g)
    g = np.where(held[:, None], np.sign(h)[:, None] * d_total, g)
    h = np.where(held, np.sign(h) * total, keep * h)
    if single:
        return float(h[0]), g[0], float(keep[0])
    return h, g, keep
