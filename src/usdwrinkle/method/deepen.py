"""Deepened pleats (docs/method.md, "Deepened pleats"): the numpy statement of what
crush.glsl computes per point and its DEEPEN_GRADIENT variant per ring.

Where the room (contract.FOLD_ROOM) lowers a fold, the fold draws less length than the
cloth has. The referee's cloth puts that length into sharper pleats: it reaches past
the low-passed surface away from its centre of curvature (docs/physics.md, "Deepening
the pleats where the room is short"). So each point is offset along its normal by

    o = -sign(kappa) min((D - 1) / |kappa|, DEEPEN_CAP a_full, a_full |kappa| a_full / FOLD_ROOM)

- kappa: the posed surface's normal curvature along the wave (across the crests),
  positive where the surface bends towards its normal: the second fundamental form
  fitted over the ring (least squares of 2 (e.n) / |e|^2 against the edges' directions);
- D: the length the full fold (before the room) draws over the lowered fold's, both of
  the mesh's profile at their slopes a |k| (the inverse of its slope table);
- an offset c away from the centre of curvature lengthens the surface along the wave by
  1 + c |kappa|: (D - 1) / |kappa| gives back the length the room denied (to first
  order: the offset's own slope adds a little more);
- the last bound fades it where the surface turns flat along the wave, so it has no step
  where kappa changes sign.

Its gradient per point (offset_gradient: least squares over the ring, in the tangent
plane) comes from a second step. The blend (include/wave.glsl) carries each corner's
offset to the point along that gradient, o_c + g_c.(p - P_c), blends those by the
barycentric weights as it blends the corner waves' phases, and adds the result to the
wrinkle height, so the offset surface meets every corner's slope and shows no kinks
along the coarse edges.
"""
from __future__ import annotations

import numpy as np

from .contract import DEEPEN_CAP, FOLD_ROOM, SLOPE_SAMPLES, SLOPE_STEP


def length_at(table: np.ndarray, slope) -> np.ndarray:
    """The length per posed length of the profile's wave at slope ``a |k|``: sqrt(1 +
    u^2), u where the slope table (folds.slope_table) reaches ``slope``, linear between
    its samples and along its last segment beyond them (crush.glsl profile_length)."""
    table = np.asarray(table, np.float64)
    slope = np.asarray(slope, np.float64)
    i = np.clip(np.searchsorted(table[1:SLOPE_SAMPLES - 1], slope, side="right"),
                0, SLOPE_SAMPLES - 2)
    low, high = table[i], table[i + 1]
    u = (i + (slope - low) / np.maximum(high - low, 1e-30)) * SLOPE_STEP
    return np.sqrt(1.0 + u * u)


def fit_form(tangent_edges: np.ndarray, normal_parts: np.ndarray, owner: np.ndarray,
             n: int) -> tuple[np.ndarray, np.ndarray]:
    """The second fundamental form per point, (n, 3) = (L, M, N) in the tangent
    coordinates the edges are given in: least squares of kappa_e = 2 (e.n) / |e|^2
    against (x^2, 2xy, y^2) of each edge's unit tangent direction (x, y); and which
    points have at least 3 edges (the others get 0). ``tangent_edges`` (m, 2),
    ``normal_parts`` (m,) = e.n, ``owner`` (m,) the point of each edge; edges of zero
    length or tangent part are skipped (crush.glsl)."""
    e2 = np.sum(tangent_edges ** 2, 1) + normal_parts ** 2
    length = np.linalg.norm(tangent_edges, axis=1)
    keep = (e2 > 0) & (length > 0)
    x = np.where(keep, tangent_edges[:, 0] / np.maximum(length, 1e-30), 0.0)
    y = np.where(keep, tangent_edges[:, 1] / np.maximum(length, 1e-30), 0.0)
    kappa = np.where(keep, 2 * normal_parts / np.maximum(e2, 1e-30), 0.0)
    rows = np.stack([x * x, 2 * x * y, y * y], 1)
    ata = np.zeros((n, 3, 3))
    atb = np.zeros((n, 3))
    np.add.at(ata, owner, rows[:, :, None] * rows[:, None, :])
    np.add.at(atb, owner, rows * kappa[:, None])
    count = np.zeros(n, np.int64)
    np.add.at(count, owner, keep.astype(np.int64))
    det = np.linalg.det(ata)
    scale = np.trace(ata, axis1=1, axis2=2)
    enough = (count >= 3) & (np.abs(det) > 1e-6 * scale ** 3)
    form = np.zeros((n, 3))
    if enough.any():
        form[enough] = np.linalg.solve(ata[enough], atb[enough][..., None])[..., 0]
    return form, enough


def curvature_along(form: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The normal curvature of ``form`` (fit_form) along ``direction`` (n, 2), in the
    same tangent coordinates (need not be unit; 0 where it is zero)."""
    length = np.linalg.norm(direction, axis=1)
    dx = np.where(length > 0, direction[:, 0] / np.maximum(length, 1e-30), 0.0)
    dy = np.where(length > 0, direction[:, 1] / np.maximum(length, 1e-30), 0.0)
    return form[:, 0] * dx * dx + 2 * form[:, 1] * dx * dy + form[:, 2] * dy * dy


def offset(kappa, drawn, full, wave_number, table: np.ndarray,
           cap: float = DEEPEN_CAP) -> np.ndarray:
    """Each point's offset along its normal (module docstring): ``kappa`` the normal
    curvature along the wave, ``drawn`` the amplitude the surface draws, ``full`` the
    fold's before the room lowered it (scene units), ``wave_number`` |k|."""
    kappa = np.asarray(kappa, np.float64)
    drawn = np.asarray(drawn, np.float64)
    full = np.maximum(np.asarray(full, np.float64), drawn)
    k = np.asarray(wave_number, np.float64)
    gain = length_at(table, full * k) / length_at(table, drawn * k)
    bend = np.maximum(np.abs(kappa), 1e-30)
    c = np.minimum(np.minimum((gain - 1.0) / bend, cap * full), full * bend * full / FOLD_ROOM)
    lowered = (full > drawn) & (drawn > 0) & (np.abs(kappa) > 0)
    return np.where(lowered, -np.sign(kappa) * np.maximum(c, 0.0), 0.0)


def offset_gradient(points: np.ndarray, normals: np.ndarray, owner: np.ndarray,
                    neighbour: np.ndarray, values: np.ndarray) -> np.ndarray:
    """The gradient of a per-point value over the posed surface, per point (n, 3): least
    squares of v_j - v_i against the ring's edges taken into the tangent plane of n_i
    (crush.glsl's DEEPEN_GRADIENT); 0 where the ring spans no plane."""
    n = len(points)
    nrm = np.asarray(normals, np.float64)
    e = np.asarray(points, np.float64)[neighbour] - np.asarray(points, np.float64)[owner]
    e = e - np.sum(e * nrm[owner], 1, keepdims=True) * nrm[owner]
    dv = np.asarray(values, np.float64)[neighbour] - np.asarray(values, np.float64)[owner]
    ete = np.zeros((n, 3, 3))
    etb = np.zeros((n, 3))
    np.add.at(ete, owner, e[:, :, None] * e[:, None, :])
    np.add.at(etb, owner, e * dv[:, None])
    scale = np.trace(ete, axis1=1, axis2=2)
    system = ete + scale[:, None, None] * nrm[:, :, None] * nrm[:, None, :]
    det = np.linalg.det(system)
    ok = (scale > 0) & (np.abs(det) > 1e-6 * scale ** 3)
    gradient = np.zeros((n, 3))
    if ok.any():
        gradient[ok] = np.linalg.solve(system[ok], etb[ok][..., None])[..., 0]
    return gradient
