"""Numpy reference of crush.glsl: the same math, vectorised over vertices."""
from __future__ import annotations

import numpy as np

from ..method.anchor import start_phases
from ..method.contract import (
    ANCHOR_ALIGNED,
    COARSENING_MAX,
    DRAWN_SLACK,
    FOLD_ROOM,
    MIN_RATIO,
)
from ..method.deepen import curvature_along, fit_form, offset, offset_gradient
from ..method.folds import (
    area_excess,
    drawn_excess,
    excess_length,
    material_wavelength,
    profile_slope,
)
from ..scene.topology import Topology, rest_tangents, vertex_normals


def minimal_rotation(a, b, v, flip_axis):
    c = np.sum(a * b, axis=1, keepdims=True)
    axis = np.cross(a, b)
    rotated = v * c + np.cross(axis, v) + axis * (np.sum(axis * v, axis=1, keepdims=True)
                                                  / np.maximum(1.0 + c, 1e-30))
    flipped = 2.0 * np.sum(flip_axis * v, axis=1, keepdims=True) * flip_axis - v
    return np.where(c < -0.999999, flipped, rotated)


def _normalize(v, fallback):
    length = np.linalg.norm(v, axis=1, keepdims=True)
    return np.where(length > 1e-30, v / np.maximum(length, 1e-30), fallback)


def wave_vector(M: np.ndarray, d: np.ndarray, wavelength) -> np.ndarray:
    """k = M^-T (2 pi / L) d in the posed tangent coordinates, each singular value of M
    floored at MIN_RATIO (crush.glsl's wave_vector): (n, 2)."""
    U, sigma, Vt = np.linalg.svd(M)
    sigma = np.maximum(sigma, MIN_RATIO)
    inverse_t = U @ (Vt / sigma[:, :, None])  # U S^-1 V^T
    return (2 * np.pi / np.asarray(wavelength, np.float64))[:, None] * \
        np.einsum("nij,nj->ni", inverse_t, d)


def crush(rest: np.ndarray, posed: np.ndarray, topology: Topology, q: np.ndarray,
          width: np.ndarray, amplitude_scale: float = 1.0, slack: float = 0.0,
          hold: np.ndarray | None = None, coarsening: np.ndarray | None = None,
          slope: np.ndarray | None = None) -> dict:
    """Per-vertex wave fields, as crush.glsl computes them (``slack``: wrinkle:slack;
    ``hold``: what held edges leave each point, scene.params.held_weights; ``coarsening``:
    each point's cap on the mesh's coarsening, folds.coarsening_cap (COARSENING_MAX
    everywhere by default); ``slope``: the profile's slope table, folds.slope_table,
    the default profile's by default).

    Returns a dict of arrays: normals (n,3), wave_vector (n,3), amplitude (n,),
    direction (n,3), compression (n,), phase (n,), usable (n,) bool, offset (n,) and
    offset_gradient (n,3) (method/deepen.py).
    """
    rest = np.asarray(rest, np.float64)
    posed = np.asarray(posed, np.float64)
    n = len(rest)
    N0 = vertex_normals(rest, topology).astype(np.float64)
    T1 = rest_tangents(N0).astype(np.float64)
    T2 = np.cross(N0, T1)
    n_posed_sum = np.zeros((n, 3))
    tri = topology.triangles
    ring_offsets, ring_indices, triangle_offsets, triangle_indices = topology.rings()
    if len(tri):
        face = np.cross(posed[tri[:, 1]] - posed[tri[:, 0]], posed[tri[:, 2]] - posed[tri[:, 0]])
        owner = np.repeat(np.arange(n), np.diff(triangle_offsets))
        np.add.at(n_posed_sum, owner, face[triangle_indices])
    has_normal = np.linalg.norm(n_posed_sum, axis=1) > 0
    usable = (np.linalg.norm(N0, axis=1) > 0.5) & has_normal
    nrm = _normalize(n_posed_sum, N0)
    t1 = _normalize(minimal_rotation(N0, nrm, T1, T1), T1)
    t2 = np.cross(nrm, t1)

    src = np.repeat(np.arange(n), np.diff(ring_offsets))
    dst = ring_indices
    rest_edge = rest[dst] - rest[src]
    posed_edge = posed[dst] - posed[src]
    a = np.stack([np.sum(rest_edge * T1[src], 1), np.sum(rest_edge * T2[src], 1)], 1)
    b = np.stack([np.sum(posed_edge * t1[src], 1), np.sum(posed_edge * t2[src], 1)], 1)
    AA = np.zeros((n, 2, 2))
    BA = np.zeros((n, 2, 2))
    np.add.at(AA, src, a[:, :, None] * a[:, None, :])
    np.add.at(BA, src, b[:, :, None] * a[:, None, :])
    count = np.diff(ring_offsets)
    det_a = np.linalg.det(AA)
    trace_a = AA[:, 0, 0] + AA[:, 1, 1]
    usable &= (count >= 2) & (trace_a > 0) & (det_a > 1e-6 * trace_a ** 2)
    M = np.tile(np.eye(2), (n, 1, 1))
    ok = usable
    M[ok] = BA[ok] @ np.linalg.inv(AA[ok])
    M_geo = M.copy()

    q = np.asarray(q, np.float64)
    q2 = np.stack([np.sum(q * T1, 1), np.sum(q * T2, 1)], 1)
    q_len = np.linalg.norm(q2, axis=1)
    q2 = np.where(q_len[:, None] > 1.0, q2 / np.maximum(q_len, 1e-30)[:, None], q2)
    M = M @ (np.eye(2) - q2[:, :, None] * q2[:, None, :])

    S = np.transpose(M, (0, 2, 1)) @ M
    lam_all, vec_all = np.linalg.eigh(S)
    d = vec_all[:, :, 0]
    d3 = d[:, :1] * T1 + d[:, 1:] * T2
    lead = d3[np.arange(n), np.argmax(np.abs(d3), axis=1)]
    flip = np.where(lead < 0, -1.0, 1.0)
    d, d3 = d * flip[:, None], d3 * flip[:, None]
    any_wave = usable | (q_len > 0)
    r = np.where(any_wave, np.clip(np.linalg.norm(np.einsum("nij,nj->ni", M, d), axis=1),
                                   MIN_RATIO, 1.0), 1.0)
    r_geo = np.where(any_wave, np.clip(np.linalg.norm(np.einsum("nij,nj->ni", M_geo, d),
                                                      axis=1), MIN_RATIO, 1.0), 1.0)
    width = np.asarray(width, np.float64)
    # the posed surface's room for a fold (crush.glsl: 2 |e.n| / |e|^2 over the ring)
    e2 = np.sum(posed_edge * posed_edge, 1)
    turn = np.linalg.norm(nrm[dst] - nrm[src], axis=1) * np.sqrt(e2)
    bend_edge = np.where(e2 > 0, np.maximum(2 * np.abs(np.sum(posed_edge * nrm[src], 1)),
                                            turn) / np.maximum(e2, 1e-300), 0.0)
    bend = np.zeros(n)
    np.maximum.at(bend, src, bend_edge)
    room = np.where(bend > 0, FOLD_ROOM / np.maximum(bend, 1e-300), np.inf)
    table = default_slope() if slope is None else np.asarray(slope, np.float64)
    # the crests' excess (wrinkle:slack: the wave's coarsening and the relaxation's
    # weight) and the drawn folds' (DRAWN_SLACK of it: the amplitude)
    fold_slack = DRAWN_SLACK * slack
    rho = excess_length(r, r_geo, slack)
    rho_fold = excess_length(r, r_geo, fold_slack)
    # the compression across d (crush.glsl: one wave restores the area; wrinkle:biaxial,
    # which the reference does not draw, would restore it with a second system)
    e = np.stack([-d[:, 1], d[:, 0]], 1)
    across = np.where(usable, np.linalg.norm(np.einsum("nij,nj->ni", M_geo, e), axis=1), 1.0)
    rho_area = area_excess(r, r_geo, across, fold_slack)
    folding = rho_fold > 1.0
    most = COARSENING_MAX if coarsening is None else np.asarray(coarsening, np.float64)
    wavelength = np.where(rho > 1.0, material_wavelength(width, rho, most), width)
    k2 = wave_vector(M_geo, d, wavelength)
    kl = np.linalg.norm(k2, axis=1)
    amplitude = np.where(folding, profile_slope(table, rho_area) / np.maximum(kl, 1e-30),
                         0.0)
    # the share of it the surface draws: lowered where the mesh is stretched across d
    # (crush.glsl: FIELD_NORMAL's w), within the same room
    cap = room / max(amplitude_scale, 1e-30)
    lowered = np.where(folding, profile_slope(table, drawn_excess(r, r_geo, across,
                                                                  fold_slack))
                       / np.maximum(kl, 1e-30), 0.0)
    # the fold the relaxation weighs the phases by: the law with the crests' slack
    weight = np.where(rho > 1.0, np.minimum(profile_slope(table, area_excess(
        r, r_geo, across, slack)) / np.maximum(kl, 1e-30), cap), 0.0) * amplitude_scale
    drawn = np.where(amplitude > 0, np.minimum(np.minimum(lowered, cap)
                                               / np.maximum(np.minimum(amplitude, cap), 1e-300),
                                               1.0), 1.0)
    capped = amplitude * amplitude_scale > room
    # how many times its room the law's fold would rise (benchmarks.physics.room)
    over_room = np.where(folding, amplitude * amplitude_scale / room, 0.0)
    amplitude = np.minimum(amplitude, room / max(amplitude_scale, 1e-30)) * amplitude_scale
    if hold is not None:
        hold = np.asarray(hold, np.float64)
        along = np.sum(d3 / np.linalg.norm(d3, axis=1, keepdims=True) * hold[:, 1:], 1)
        amplitude = amplitude * (1.0 - hold[:, 0] * (1.0 - along ** 2))
        weight = weight * (1.0 - hold[:, 0] * (1.0 - along ** 2))
    k = k2[:, :1] * t1 + k2[:, 1:] * t2
    # the deepened pleats (method/deepen.py): the offset where the room lowered the fold,
    # from the form fitted over the ring in the posed tangent coordinates b
    form, fitted = fit_form(b, np.sum(posed_edge * nrm[src], 1), src, n)
    drawn_amplitude = amplitude * drawn
    deepen = offset(curvature_along(form, k2), drawn_amplitude,
                    drawn_amplitude * np.maximum(over_room, 1.0), kl, table)
    deepen = np.where(usable & fitted, deepen, 0.0)
    phase = (2 * np.pi / wavelength) * np.sum(d3 * rest, 1)
    # where the wave runs along the paint, the paint's own start phase (method/anchor.py)
    painted = start_phases(rest, N0, T1, topology.neighbor_offsets,
                           topology.neighbor_indices, q, width, coarsening).astype(np.float64)
    along_paint = np.sum(d3 / np.maximum(np.linalg.norm(d3, axis=1, keepdims=True), 1e-300)
                         * painted[:, :3], 1)
    phase = np.where(np.abs(along_paint) >= ANCHOR_ALIGNED,
                     np.where(along_paint < 0, -painted[:, 3], painted[:, 3]), phase)
    stretch = np.sqrt(np.linalg.eigvalsh(np.transpose(M_geo, (0, 2, 1)) @ M_geo)[:, 1])
    return {"normals": nrm, "wave_vector": k, "amplitude": amplitude, "drawn": drawn,
            "weight": weight,
            "direction": d3,
            "compression": r, "phase": phase, "usable": usable,
            # the material wave vector (2 pi / L) d3 that relax's mobility compares
            "kappa": (2 * np.pi / wavelength)[:, None] * d3,
            # beyond crush.glsl's outputs: the mesh's own compression along d and largest
            # stretch, and where the room limited the fold (the area tests read them)
            "geometric": r_geo, "stretch": stretch, "capped": capped & folding,
            "over_room": over_room,
            # the deepening's offset along the normal and its gradient (FIELD_DEEPEN)
            "offset": deepen,
            "offset_gradient": offset_gradient(posed, nrm, src, dst, deepen)}


def default_slope() -> np.ndarray:
    """The default profile's slope table (folds.slope_table of profiles.default_profile)."""
    from ..method.folds import slope_table
    from ..method.profiles import default_profile

    return slope_table(default_profile()).astype(np.float64)
