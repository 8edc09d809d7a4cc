"""Numpy reference of relax.glsl (Jacobi with sign alignment) and the misfit metric."""
from __future__ import annotations

import numpy as np

from ..contract import COLD_START_FACTOR, WEIGHT_FLOOR
from ..scene.topology import Topology


def relax(points, wave_vector, amplitude, phase, topology: Topology, iterations: int):
    """``iterations`` Jacobi steps; returns the new phases (n,)."""
    points = np.asarray(points, np.float64)
    k = np.asarray(wave_vector, np.float64)
    weight = np.asarray(amplitude, np.float64) + WEIGHT_FLOOR
    phi = np.asarray(phase, np.float64).copy()
    n = len(points)
    ring_offsets, dst = topology.rings()[:2]
    src = np.repeat(np.arange(n), np.diff(ring_offsets))
    sign = np.where(np.sum(k[src] * k[dst], 1) < 0, -1.0, 1.0)
    k_j = k[dst] * sign[:, None]
    k_bar = 0.5 * (k[src] + k_j)
    drift = np.sum(k_bar * (points[dst] - points[src]), 1)
    for _ in range(iterations):
        predicted = phi[dst] * sign - drift
        re = weight * np.cos(phi)
        im = weight * np.sin(phi)
        np.add.at(re, src, weight[dst] * np.cos(predicted))
        np.add.at(im, src, weight[dst] * np.sin(predicted))
        phi = np.where(re * re + im * im > 0, np.arctan2(im, re), phi)
    return phi


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
    sign = np.where(np.sum(k[i] * k[j], 1) < 0, -1.0, 1.0)
    k_bar = 0.5 * (k[i] + sign[:, None] * k[j])
    residual = wrap(sign * phi[j] - phi[i] - np.sum(k_bar * (points[j] - points[i]), 1))
    return float(np.sqrt(np.mean(residual ** 2)))


def seed(wave_vector, previous_wave_vector, previous_phase, amplitude=None, anchor=None):
    """The warm start of a frame: previous phases, flipped where k flipped; with
    ``amplitude`` and ``anchor`` (crush's material-anchored phase), a point without a wave
    (amplitude 0) starts from its anchor instead (issue 46: the flip test on the
    meaningless k of such a point decided its sign by rounding, and a wrinkle that grew
    there later inherited it, so a 0.01 degree change of a joint moved crests)."""
    flip = np.sum(np.asarray(wave_vector, np.float64)
                  * np.asarray(previous_wave_vector, np.float64), 1) < 0
    start = np.where(flip, -1.0, 1.0) * np.asarray(previous_phase, np.float64)
    if amplitude is not None:
        start = np.where(np.asarray(amplitude) > 0, start, np.asarray(anchor, np.float64))
    return start


def relax_frame(fields: dict, state: dict | None, topology: Topology, iterations: int,
                cold_start_factor: int = COLD_START_FACTOR) -> tuple[np.ndarray, dict]:
    """One frame of the phase history, as the engine computes it (history.py).

    ``fields``: the frame's points, wave_vector, amplitude and phase (crush's anchored
    phase). ``state``: the wave state of the shot's previous grid frame (its wave_vector
    and relaxed phase; the GPU's also holds crest damping's directions), or None for a
    cold start. Returns the relaxed phases and this frame's state. ``state`` is read,
    never changed: the same frame from the same state is the same frame.
    """
    if state is None:
        start, count = fields["phase"], iterations * cold_start_factor
    else:
        start = seed(fields["wave_vector"], state["wave_vector"], state["phase"],
                     fields["amplitude"], fields["phase"])
        count = iterations
    phase = relax(fields["points"], fields["wave_vector"], fields["amplitude"], start,
                  topology, count)
    return phase, {"wave_vector": np.array(fields["wave_vector"], copy=True), "phase": phase}


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
