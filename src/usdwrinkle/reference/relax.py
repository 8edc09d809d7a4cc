"""Numpy reference of relax.glsl (Jacobi with sign alignment) and the misfit metric."""
from __future__ import annotations

import numpy as np

from ..method.contract import (
    COARSENING_MAX,
    COLD_START_FACTOR,
    FIT_CONDITION,
    FIT_ONSET,
    FIT_RANGE,
    FLOOR_ALIGNED,
    FLOOR_ALIGNED_FROM,
    MOBILITY_DEADBAND,
    MOBILITY_PHASE,
    MOBILITY_RING,
    MOBILITY_TURN,
    RELAX_ALIGNED,
    WEIGHT_FLOOR,
)
from ..scene.topology import Topology


def ring_edges(topology: Topology) -> tuple[np.ndarray, np.ndarray]:
    """Every directed ring edge the passes read (Topology.rings: CSR, capped): (i, j)."""
    ring_offsets, dst = topology.rings()[:2]
    return np.repeat(np.arange(len(ring_offsets) - 1), np.diff(ring_offsets)), dst


def aligned(k, src, dst, bare=None) -> np.ndarray:
    """Per ring edge, how much j's wave pulls i's phase beside its amplitude:
    smoothstep(0, RELAX_ALIGNED, |cos|) of the angle between their wave vectors
    (relax.glsl's aligned); where ``bare`` (per point: no wave there) holds for i,
    smoothstep(FLOOR_ALIGNED_FROM, FLOOR_ALIGNED, |cos|) (relax.glsl's floor_aligned)."""
    k = np.asarray(k, np.float64)
    length = np.linalg.norm(k, axis=1)
    cos = np.abs(np.sum(k[src] * k[dst], 1)) / np.maximum(length[src] * length[dst], 1e-30)
    out = _smoothstep(0.0, RELAX_ALIGNED, cos)
    if bare is None:
        return out
    return np.where(np.asarray(bare)[src], _smoothstep(FLOOR_ALIGNED_FROM, FLOOR_ALIGNED, cos),
                    out)


def pairing(points, k, src, dst) -> tuple[np.ndarray, np.ndarray]:
    """Per edge (src, dst): the sign that pairs j's wave with i's ((k, phi) and (-k,
    -phi) are one wave) and the drift kbar_ij . (x_j - x_i)."""
    points = np.asarray(points, np.float64)
    k = np.asarray(k, np.float64)
    sign = np.where(np.sum(k[src] * k[dst], 1) < 0, -1.0, 1.0)
    drift = np.sum(0.5 * (k[src] + sign[:, None] * k[dst]) * (points[dst] - points[src]), 1)
    return sign, drift


def pulls(points, k, amplitude, src, dst, floor: float = 0.0
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per ring edge: :func:`pairing`'s sign and drift, and j's pull on i, (a_j +
    ``floor``) :func:`aligned`, along i's own direction only where i has no wave (relax.glsl's
    SEED: its steps read the pulls with WEIGHT_FLOOR, its seed and fit without)."""
    sign, drift = pairing(points, k, src, dst)
    a = np.asarray(amplitude, np.float64)
    pull = (a[dst] + floor) * aligned(k, src, dst, ~(a > 0))
    return sign, drift, pull


def relax(points, wave_vector, amplitude, phase, topology: Topology, iterations: int,
          mean: bool = False):
    """``iterations`` Jacobi steps; returns the new phases (n,). A neighbour pulls by its
    amplitude plus WEIGHT_FLOOR times :func:`aligned`, a vertex itself by its own plus
    WEIGHT_FLOOR. ``mean`` (relax.glsl's cold start): the steps are the weighted mean of
    the phasors, not normalised, z_i <- (w_i z_i + sum_j p_ij z~_j e^{-i d_ij}) / (w_i +
    sum_j p_ij) from z = e^{i phase}, and the phases arg z."""
    points = np.asarray(points, np.float64)
    k = np.asarray(wave_vector, np.float64)
    a = np.asarray(amplitude, np.float64)
    weight = a + WEIGHT_FLOOR
    phi = np.asarray(phase, np.float64).copy()
    src, dst = ring_edges(topology)
    sign, drift, pull = pulls(points, k, a, src, dst, WEIGHT_FLOOR)
    if mean:
        z = np.exp(1j * phi)
        rotation = np.exp(-1j * drift)
        total = weight.copy()
        np.add.at(total, src, pull)
        for _ in range(iterations):
            pulled = weight * z
            np.add.at(pulled, src, pull * np.where(sign < 0, np.conj(z[dst]), z[dst])
                      * rotation)
            z = np.where(np.abs(pulled) > 0, pulled / total, z)
        return np.where(np.abs(z) > 0, np.angle(z), phi)
    for _ in range(iterations):
        predicted = phi[dst] * sign - drift
        re = weight * np.cos(phi)
        im = weight * np.sin(phi)
        np.add.at(re, src, pull * np.cos(predicted))
        np.add.at(im, src, pull * np.sin(predicted))
        phi = np.where(re * re + im * im > 0, np.arctan2(im, re), phi)
    return phi


def fit(points, normals, wave_vector, amplitude, phase, topology: Topology,
        coarsening=None):
    """The wave the phases draw (relax.glsl's FIT): per vertex with a wave, k + c, c the
    least-squares fit in the tangent plane of ``normals`` of c . (x_j - x_i) to each ring
    edge's residual wrap(phi~_j - phi_i - kbar_ij . (x_j - x_i)) (weights a_j times
    :func:`aligned`, neighbours with a wave only, weighted down as k_i advances from pi / 2
    to pi along the edge),
    and the amplitude times |k| / |k + t c|: the same slope. t fades the fit out where the
    ring's directions are too few (FIT_CONDITION) or |k| would grow by more than
    FIT_RANGE, and in from |k + c| = |k| to FIT_ONSET |k|: only shorter waves are fitted
    (method/contract.py); and only where the folds coarsen: times smoothstep(1,
    COARSENING_MAX, cap), ``coarsening`` each point's cap (folds.coarsening_cap; None:
    COARSENING_MAX everywhere).
    Returns (wave_vector (n, 3), amplitude (n,))."""
    points = np.asarray(points, np.float64)
    normals = np.asarray(normals, np.float64)
    k = np.asarray(wave_vector, np.float64)
    a = np.asarray(amplitude, np.float64)
    phi = np.asarray(phase, np.float64)
    n = len(points)
    src, dst = ring_edges(topology)
    sign, drift, pull = pulls(points, k, np.maximum(a, 0.0), src, dst)
    dx = points[dst] - points[src]
    residual = wrap(sign * phi[dst] - phi[src] - drift)
    sampled = 1.0 - _smoothstep(0.5 * np.pi, np.pi, np.abs(np.sum(k[src] * dx, 1)))
    dx = dx - np.sum(dx * normals[src], 1)[:, None] * normals[src]
    weight = pull * sampled
    equations = np.zeros((n, 3, 3))
    np.add.at(equations, src, weight[:, None, None] * dx[:, :, None] * dx[:, None, :])
    rhs = np.zeros((n, 3))
    np.add.at(rhs, src, (weight * residual)[:, None] * dx)
    trace = np.zeros(n)
    np.add.at(trace, src, weight * np.sum(dx * dx, 1))
    # n n^T at the tangent block's scale pins c to the tangent plane
    equations += trace[:, None, None] * normals[:, :, None] * normals[:, None, :]
    spread = np.where(trace > 0, np.linalg.det(equations) /
                      np.maximum(trace ** 3, 1e-300), 0)
    ok = (a > 0) & (spread > FIT_CONDITION)
    correction = np.zeros_like(k)
    if ok.any():
        correction[ok] = np.linalg.solve(equations[ok], rhs[ok][..., None])[..., 0]
    length = np.maximum(np.linalg.norm(k, axis=1), 1e-30)
    change = np.linalg.norm(k + correction, axis=1) / length
    coarsens = 1.0 if coarsening is None else \
        _smoothstep(1.0, COARSENING_MAX, np.asarray(coarsening, np.float64).reshape(-1))
    trust = (_smoothstep(FIT_CONDITION, 2 * FIT_CONDITION, spread) *
             _smoothstep(1.0, FIT_ONSET, change) *
             (1.0 - _smoothstep(0.75 * FIT_RANGE, FIT_RANGE, change)) * coarsens)
    fitted = k + np.where(ok, trust, 0.0)[:, None] * correction
    # never a longer wave than crush's (a partly trusted c that turns k could shorten it)
    fitted *= np.maximum(1.0, length / np.maximum(np.linalg.norm(fitted, axis=1), 1e-30))[:, None]
    scale = length / np.maximum(np.linalg.norm(fitted, axis=1), 1e-30)
    return fitted, np.where(ok, a * scale, a)


def _smoothstep(low: float, high: float, x) -> np.ndarray:
    t = np.clip((np.asarray(x, np.float64) - low) / (high - low), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def wrap(angle):
    return (np.asarray(angle) + np.pi) % (2 * np.pi) - np.pi


def phase_misfit(points, wave_vector, phase, topology: Topology, mask=None) -> float:
    """RMS over edges of wrap(phi~_j - phi_i - kbar_ij . (x_j - x_i)), radians.

    ``mask`` (n,) bool restricts to edges whose both ends are selected.
    """
    points = np.asarray(points, np.float64)
    k = np.asarray(wave_vector, np.float64)
    phi = np.asarray(phase, np.float64)
    edges = topology.edges
    i, j = edges[:, 0], edges[:, 1]
    if mask is not None:
        keep = mask[i] & mask[j]
        i, j = i[keep], j[keep]
    if not len(i):
        return 0.0
    sign, drift = pairing(points, k, i, j)
    residual = wrap(sign * phi[j] - phi[i] - drift)
    return float(np.sqrt(np.mean(residual ** 2)))


def seed(wave_vector, previous_wave_vector, previous_phase, amplitude=None, anchor=None,
         previous_amplitude=None, points=None, topology: Topology | None = None):
    """The warm start of a frame: previous phases, flipped where k flipped; with
    ``amplitude`` and ``anchor`` (crush's material-anchored phase), a point without a wave
    (amplitude 0) starts from its anchor instead (issue 46: the flip test on the
    meaningless k of such a point decided its sign by rounding, and a wrinkle that grew
    there later inherited it, so a 0.01 degree change of a joint moved crests). With
    ``previous_amplitude``, ``points`` and ``topology`` too, a wave that is new (none
    there last frame: its phase then was what the relaxation's floor weights made of its
    neighbours' along its meaningless k, which a 0.01 degree change moved by 1.6-3.1 rad
    at the shirt's elbow) starts from the phase its ring's kept waves ask for (their
    pulls, as a Jacobi step), where it has any; with none beside it, from its previous
    phase (relax.glsl's SEED; docs/method.md, "Sensitivity")."""
    k = np.asarray(wave_vector, np.float64)
    flip = np.sum(k * np.asarray(previous_wave_vector, np.float64), 1) < 0
    start = np.where(flip, -1.0, 1.0) * np.asarray(previous_phase, np.float64)
    if amplitude is None:
        return start
    a = np.asarray(amplitude, np.float64)
    out = np.where(a > 0, start, np.asarray(anchor, np.float64))
    if previous_amplitude is None or points is None or topology is None:
        return out
    kept = (a > 0) & (np.asarray(previous_amplitude) > 0)
    src, dst = ring_edges(topology)
    sign, drift, pull = pulls(points, k, a, src, dst)
    asked = sign * start[dst] - drift
    counts = np.where(kept[dst], pull, 0.0)
    re, im = np.zeros(len(a)), np.zeros(len(a))
    np.add.at(re, src, counts * np.cos(asked))
    np.add.at(im, src, counts * np.sin(asked))
    new = (a > 0) & ~kept & (re * re + im * im > 0)
    return np.where(new, np.arctan2(im, re), out)


def mobility(rest_points, kappa, previous_kappa, amplitude, previous_amplitude,
             topology: Topology) -> np.ndarray:
    """relax.glsl's mobility: the share of the relaxation's move each vertex takes this
    frame, min(max(x - MOBILITY_DEADBAND, 0) / (1 - MOBILITY_DEADBAND), 1) with x = delta /
    MOBILITY_PHASE + turn / MOBILITY_TURN. The change of kappa
    (the previous one sign-matched to the current) is split into the wave number's part,
    (|kappa_now| - |kappa_before|) d_now, and the direction's, |kappa_before| (d_now -
    d_before) (d the unit direction); delta and turn are the largest over the vertex's
    ring edges of each part . (X_j - X_i), averaged over the edge's two ends (j's parts
    sign-matched to i's kappa), each edge times smoothstep(0, MOBILITY_RING, a_j / a_i)
    (a_j: the smaller of j's amplitudes now and before; a neighbour without a wave does
    not count). ``kappa``: the material wave vectors (2 pi / L) d3 in rest
    space, (n, 3). 1 where the vertex has no wave now or had none before (it relaxes
    fully)."""
    rest = np.asarray(rest_points, np.float64)
    now = np.asarray(kappa, np.float64)
    before = np.asarray(previous_kappa, np.float64)
    before = np.where(np.sum(now * before, 1) < 0, -1.0, 1.0)[:, None] * before
    w_now = np.linalg.norm(now, axis=1)
    w_before = np.linalg.norm(before, axis=1)
    d_now = now / np.maximum(w_now, 1e-300)[:, None]
    d_before = before / np.maximum(w_before, 1e-300)[:, None]
    wave_part = (w_now - w_before)[:, None] * d_now
    turn_part = w_before[:, None] * (d_now - d_before)
    src, dst = ring_edges(topology)
    sign = np.where(np.sum(now[src] * now[dst], 1) < 0, -1.0, 1.0)
    a_now = np.asarray(amplitude, np.float64)
    neighbour = np.minimum(a_now[dst], np.asarray(previous_amplitude, np.float64)[dst])
    counts = _smoothstep(0.0, MOBILITY_RING, neighbour / np.maximum(a_now[src], 1e-30)) \
        * aligned(now, src, dst)

    def largest(change: np.ndarray) -> np.ndarray:
        edge = counts * np.abs(np.sum(0.5 * (change[src] + sign[:, None] * change[dst])
                                      * (rest[dst] - rest[src]), 1))
        out = np.zeros(len(rest))
        np.maximum.at(out, src, edge)
        return out

    moved = largest(wave_part) / MOBILITY_PHASE + largest(turn_part) / MOBILITY_TURN
    moving = np.minimum(np.maximum(moved - MOBILITY_DEADBAND, 0.0) / (1.0 - MOBILITY_DEADBAND),
                        1.0)
    waves = (np.asarray(amplitude) > 0) & (np.asarray(previous_amplitude) > 0)
    return np.where(waves, moving, 1.0)


def relax_frame(fields: dict, state: dict | None, topology: Topology, iterations: int,
                cold_start_factor: int = COLD_START_FACTOR) -> tuple[np.ndarray, dict]:
    """One frame of the phase history, as the engine computes it (method/history.py).

    ``fields``: the frame's points, wave_vector, amplitude and phase (crush's anchored
    phase); with ``kappa`` (the material wave vectors, :func:`mobility`) and
    ``rest_points``, and a state that holds its ``kappa``, the relaxed phases move from the
    seed by each vertex's mobility (relax.glsl), else fully. With ``coarsening`` (each
    point's cap), the fit follows it (:func:`fit`). ``state``: the wave state of
    the shot's previous grid frame (its wave_vector, amplitude, relaxed phase and kappa;
    the GPU's also holds crest damping's directions), or None for a cold start (its
    steps the weighted mean, :func:`relax`'s ``mean``). Returns
    the relaxed phases and this frame's state (its wave_vector and amplitude are the
    fitted ones, :func:`fit`, as the GPU's fields are after relax; with no iterations
    there is no fit). ``state`` is read, never changed: the same frame from the same
    state is the same frame.
    """
    if state is None:
        start, count = fields["phase"], iterations * cold_start_factor
    else:
        start = seed(fields["wave_vector"], state["wave_vector"], state["phase"],
                     fields["amplitude"], fields["phase"], state.get("amplitude"),
                     fields["points"], topology)
        count = iterations
    phase = relax(fields["points"], fields["wave_vector"], fields["amplitude"], start,
                  topology, count, mean=state is None)
    if state is not None and count > 0 and "kappa" in fields and "kappa" in state:
        share = mobility(fields["rest_points"], fields["kappa"], state["kappa"],
                         fields["amplitude"], state["amplitude"], topology)
        phase = start + share * wrap(phase - start)
    wave_vector = np.array(fields["wave_vector"], np.float64, copy=True)
    amplitude = np.array(fields["amplitude"], np.float64, copy=True)
    if count > 0:
        wave_vector, amplitude = fit(fields["points"], fields["normals"], wave_vector,
                                     amplitude, phase, topology, fields.get("coarsening"))
    state = {"wave_vector": wave_vector, "amplitude": amplitude, "phase": phase}
    if "kappa" in fields:
        state["kappa"] = np.asarray(fields["kappa"], np.float64)
    return phase, state


def relax_shot(frames: list, topology: Topology, iterations: int,
               cold_start_factor: int = COLD_START_FACTOR):
    """Phase history over a shot's grid frames, as the engine computes it: each frame
    from the state of the one before (:func:`relax_frame`).

    ``frames``: per frame, a dict with points, wave_vector, amplitude and phase (the
    anchored phase from crush). Returns the relaxed phases of every frame.
    """
    out, state = [], None
    for fields in frames:
        phase, state = relax_frame(fields, state, topology, iterations, cold_start_factor)
        out.append(phase)
    return out


def phase_swim(previous: dict, current: dict) -> float:
    """How far crests slide over the cloth between two frames, radians (RMS).

    At a vertex, the crest position relative to the material is its phase, so a crest
    that rides with the cloth keeps it. The RMS change of the phase (sign-aligned
    where k flipped) is weighted by amplitude, since a faint wrinkle that moves is not
    seen. 2 pi is one wavelength.
    """
    amp = np.minimum(previous["amplitude"], current["amplitude"])
    keep = amp > 1e-3 * max(float(amp.max(initial=0.0)), 1e-30)
    if not keep.any():
        return 0.0
    start = seed(current["wave_vector"], previous["wave_vector"], previous["phase"])
    change = wrap(np.asarray(current["phase"], np.float64) - start)[keep]
    weight = amp[keep] ** 2
    return float(np.sqrt(np.sum(weight * change ** 2) / np.sum(weight)))
