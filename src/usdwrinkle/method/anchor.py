"""The waves' start phases: a stripe pattern of the painted q, in rest space; and, for
waves nobody painted on a surface that curves one way (a tube gathered around itself),
one of the direction it curves along (curved_phases; docs/method.md, "Gathered tubes").

Crush starts each wave from its material-anchored phase ``(2pi/L) d.X`` (docs/method.md,
"Stability"): exact where d is constant, but where the painted direction turns, its
gradient is wrong by ``(2pi/L) (grad d)^T X``, and around a loop (q painted around a
sleeve: crests along the arm) ``d.X`` is about constant, so the start has no winding at all.
The relaxation must then make the phase wind around the arm from nothing, and where it
leaves the dislocations that takes is decided by float rounding: a 0.01 degree change of
the shot moved the crests on up to 2.5% of the wrinkled pixels (the stability block's
painted-loop row), against 0.1% unpainted.

Here the painted points get a start phase whose gradient is the paint's own wave, ``2pi /
L`` along q, with L the wavelength the paint alone gives (crush.glsl's fold at r_geo = 1,
``painted_wavelength``):
- integrated breadth first over the painted points' 1-rings from the lowest-numbered
  point of each painted region (which keeps its ``(2pi/L) q.X``), so that around a loop
  the phase winds as often as the loop is long;
- then smoothed as phasors (``SMOOTHING`` Jacobi steps, each point's own phasor and its
  neighbours' carried to it along q), which spreads where the two fronts of the search met
  around the loop.
It depends on the rest pose, q and W alone: the same on every frame, every GPU and every
change of the animation. It is given (else the table holds zeros and crush keeps
``(2pi/L) d.X``, which unpainted neighbours share) only to a painted region
- that winds: some edge closes a loop of the search by more than half a wave (a tree of
  points or a straight stroke does not);
- whose directions are smooth (``SMOOTH``: q painted at random winds everywhere, and a
  stripe pattern of noise is no better a start than any other);
and crush uses it where the wave runs along q (within 45 degrees, ANCHOR_ALIGNED;
elsewhere the mesh's own compression leads). docs/method.md, "Painted loops", has the
measurements.

A phase is measured along the painted vector's own sign; crush flips it where its rest
direction d points the other way. Two painted neighbours whose q point apart carry the
phase across with a sign flip, as the wave's phase does.
"""
from __future__ import annotations

import numpy as np

from .contract import COARSENING_EXPONENT, COARSENING_MAX, MIN_RATIO, PAINT_GATHER_MAX

#: curved_phases: the rest surface curves at least this many times more one way than the
#: other (a tube: without end; a sphere: 1)
CURVED_ONE_WAY = 2.0
#: phasor smoothing steps after the breadth-first integration
SMOOTHING = 32
#: a painted region is smooth where its neighbouring directions agree this well (|cos|,
#: the median): within 30 degrees. The sample stages' paints: 0.92-1.0; q painted at
#: random: 0.6
SMOOTH = 0.866


def painted_wavelength(q_length: np.ndarray, width: np.ndarray,
                       cap=COARSENING_MAX) -> np.ndarray:
    """The material wavelength of a wave that the paint alone makes (crush.glsl's fold at
    r_geo = 1): W min(gather ** COARSENING_EXPONENT, cap), gather = min(1 / r,
    PAINT_GATHER_MAX), r = clamp(1 - |q|^2, MIN_RATIO, 1) the compression along q that
    the paint biases, ``cap`` the point's coarsening cap (folds.coarsening_cap: 1 where
    the rest surface curves one way)."""
    r = np.clip(1.0 - np.asarray(q_length, np.float64) ** 2, MIN_RATIO, 1.0)
    gather = np.minimum(1.0 / r, PAINT_GATHER_MAX)
    return np.asarray(width, np.float64) * np.minimum(gather ** COARSENING_EXPONENT,
                                                      np.asarray(cap, np.float64))


def painted_phases(rest: np.ndarray, rest_normals: np.ndarray, neighbor_offsets: np.ndarray,
                   neighbor_indices: np.ndarray, q: np.ndarray,
                   width: np.ndarray, coarsening: np.ndarray | None = None) -> np.ndarray:
    """(n, 4) float32: xyz the unit painted direction (q in the rest tangent plane; zero
    where nothing is painted), w the start phase (radians) along it (module docstring).
    ``neighbor_offsets``/``neighbor_indices``: each point's 1-ring (Topology);
    ``coarsening``: each point's coarsening cap (COARSENING_MAX everywhere: None)."""
    rest = np.asarray(rest, np.float64)
    normals = np.asarray(rest_normals, np.float64)
    n = len(rest)
    out = np.zeros((n, 4), np.float32)
    q = np.asarray(q, np.float64)
    tangent = q - np.sum(q * normals, axis=1, keepdims=True) * normals
    length = np.linalg.norm(tangent, axis=1)
    painted = length > 0.0
    if not painted.any():
        return out
    direction = np.zeros_like(tangent)
    direction[painted] = tangent[painted] / length[painted, None]
    wavenumber = np.zeros(n)
    cap = np.broadcast_to(np.asarray(COARSENING_MAX if coarsening is None else coarsening,
                                     np.float64), (n,))
    wavenumber[painted] = 2.0 * np.pi / painted_wavelength(np.minimum(length[painted], 1.0),
                                                          np.asarray(width)[painted],
                                                          cap[painted])
    return integrated_phases(rest, direction, wavenumber, neighbor_offsets, neighbor_indices)


def integrated_phases(rest: np.ndarray, direction: np.ndarray, wavenumber: np.ndarray,
                      neighbor_offsets: np.ndarray, neighbor_indices: np.ndarray) -> np.ndarray:
    """(n, 4) float32: the start phases of a direction field (xyz: ``direction``, unit in
    the rest tangent plane, zero where there is none; w: the phase along it, at
    ``wavenumber`` radians per unit), integrated breadth first over each region of the
    field and smoothed, where the region winds and its directions are smooth (module
    docstring); zero elsewhere."""
    rest = np.asarray(rest, np.float64)
    direction = np.asarray(direction, np.float64)
    wavenumber = np.asarray(wavenumber, np.float64)
    n = len(rest)
    out = np.zeros((n, 4), np.float32)
    painted = np.linalg.norm(direction, axis=1) > 0.0
    if not painted.any():
        return out

    # the painted points' ring edges (i -> j, both painted)
    offsets = np.asarray(neighbor_offsets, np.int64)
    indices = np.asarray(neighbor_indices, np.int64)
    source = np.repeat(np.arange(n), np.diff(offsets))
    keep = painted[source] & painted[indices] & (source != indices)
    source, target = source[keep], indices[keep]
    # j's phase in i's terms: the sign between their directions, and the advance from i to
    # j along their mean direction (in i's sign) at their mean wave number
    sign = np.where(np.sum(direction[source] * direction[target], axis=1) < 0.0, -1.0, 1.0)
    mean = direction[source] + sign[:, None] * direction[target]
    mean /= np.maximum(np.linalg.norm(mean, axis=1, keepdims=True), 1e-300)
    advance = 0.5 * (wavenumber[source] + wavenumber[target]) * np.sum(
        mean * (rest[target] - rest[source]), axis=1)
    order = np.argsort(source, kind="stable")
    source, target, sign, advance = source[order], target[order], sign[order], advance[order]

    phase = np.full(n, np.nan)
    region = np.full(n, -1)
    for root in np.flatnonzero(painted):
        if region[root] >= 0:
            continue
        region[root] = root
        phase[root] = wavenumber[root] * float(direction[root] @ rest[root])
        front = np.array([root])
        while front.size:
            starts = np.searchsorted(source, front, side="left")
            counts = np.searchsorted(source, front, side="right") - starts
            edges = np.repeat(starts - np.concatenate([[0], np.cumsum(counts)[:-1]]),
                              counts) + np.arange(counts.sum())
            edges = edges[region[target[edges]] < 0]
            if not edges.size:
                break
            # each new point from its lowest-numbered parent in the front
            chosen = edges[np.lexsort((source[edges], target[edges]))]
            first = np.concatenate([[True], target[chosen][1:] != target[chosen][:-1]])
            chosen = chosen[first]
            new = target[chosen]
            phase[new] = sign[chosen] * (phase[source[chosen]] + advance[chosen])
            region[new] = root
            front = new

    # a region winds where some edge closes a loop of the search by more than half a wave;
    # its stripe pattern means something where its painted directions are smooth (their
    # neighbours' within 30 degrees at the median: noise painted at random would wind too)
    closing = np.abs(sign * (phase[source] + advance) - phase[target])
    agreement = np.abs(np.sum(direction[source] * direction[target], axis=1))
    winding = [r for r in np.unique(region[source[closing > np.pi]])
               if np.median(agreement[region[source] == r]) >= SMOOTH]
    used = np.isin(region, winding) & painted
    if not used.any():
        return out

    # Jacobi on the phasors: each point's own and its neighbours' carried to it
    inside = used[source]
    source, target, sign, advance = source[inside], target[inside], sign[inside], \
        advance[inside]
    z = np.exp(1j * phase)
    z[~used] = 0.0
    turn = np.exp(-1j * advance)
    for _ in range(SMOOTHING):
        carried = np.where(sign < 0.0, np.conj(z[target]), z[target])  # j's phase in i's sign
        carried = carried * turn
        total = z + np.bincount(source, carried.real, minlength=n) \
            + 1j * np.bincount(source, carried.imag, minlength=n)
        size = np.abs(total)
        z = np.where(size > 1e-12, total / np.maximum(size, 1e-300), z)
    out[used, :3] = direction[used]
    out[used, 3] = np.angle(z[used])
    return out


def curved_phases(rest: np.ndarray, rest_normals: np.ndarray, rest_tangents: np.ndarray,
                  neighbor_offsets: np.ndarray, neighbor_indices: np.ndarray,
                  width: np.ndarray, use: np.ndarray | None = None) -> np.ndarray:
    """(n, 4) float32, as painted_phases: the start phases around the rest surface's
    curvature, for waves that nobody painted (``use``: the points that may have one; all
    by default). Where the rest surface curves at least CURVED_ONE_WAY times more one way
    than the other (a tube), the stripe pattern of W (the folds' wavelength at their
    onset) along the curvature's direction, integrated as the paint's is, winds around a
    tube as often as W goes into its circumference. The material-anchored phase (2pi/L)
    d.X does not: around a tube d.X is about constant (exactly 0 about an axis through the
    mesh's origin), and the relaxation cannot make a winding from nothing (docs/method.md,
    "Gathered tubes"). The direction is the fitted second fundamental form's (deepen.
    fit_form) of larger magnitude; zero where the region does not wind or its directions
    are not smooth (integrated_phases). ``rest_tangents``: a unit tangent per point
    (scene/topology.rest_tangents), the form's first axis."""
    from .deepen import fit_form

    rest = np.asarray(rest, np.float64)
    normals = np.asarray(rest_normals, np.float64)
    n = len(rest)
    out = np.zeros((n, 4), np.float32)
    allowed = np.ones(n, bool) if use is None else np.asarray(use, bool)
    if not allowed.any():
        return out
    first = np.asarray(rest_tangents, np.float64)
    second = np.cross(normals, first)
    offsets = np.asarray(neighbor_offsets, np.int64)
    target = np.asarray(neighbor_indices, np.int64)
    source = np.repeat(np.arange(n), np.diff(offsets))
    edge = rest[target] - rest[source]
    tangent = np.stack([np.sum(edge * first[source], 1), np.sum(edge * second[source], 1)], 1)
    form, fitted = fit_form(tangent, np.sum(edge * normals[source], 1), source, n)
    ll, mm, nn = form[:, 0], form[:, 1], form[:, 2]
    mean, spread = 0.5 * (ll + nn), np.hypot(0.5 * (ll - nn), mm)
    angle = 0.5 * np.arctan2(2.0 * mm, ll - nn)  # the direction of eigenvalue mean + spread
    larger, smaller = mean + spread, mean - spread
    swap = np.abs(smaller) > np.abs(larger)
    angle = np.where(swap, angle + 0.5 * np.pi, angle)
    most, least = np.where(swap, smaller, larger), np.where(swap, larger, smaller)
    one_way = (np.abs(most) > 0.0) & (np.abs(most) >= CURVED_ONE_WAY * np.abs(least))
    usable = allowed & fitted & one_way & np.all(np.isfinite(normals), axis=1)
    direction = np.zeros((n, 3))
    direction[usable] = (np.cos(angle)[:, None] * first + np.sin(angle)[:, None] * second)[usable]
    wavenumber = np.where(usable, 2.0 * np.pi / np.maximum(np.asarray(width, np.float64),
                                                           1e-300), 0.0)
    return integrated_phases(rest, direction, wavenumber, offsets, target)


def start_phases(rest: np.ndarray, rest_normals: np.ndarray, rest_tangents: np.ndarray,
                 neighbor_offsets: np.ndarray, neighbor_indices: np.ndarray, q: np.ndarray,
                 width: np.ndarray, coarsening: np.ndarray | None = None) -> np.ndarray:
    """The table crush starts waves from (n, 4): the paint's (painted_phases) where q is
    painted, else the curvature's (curved_phases) on the unpainted points."""
    painted = painted_phases(rest, rest_normals, neighbor_offsets, neighbor_indices, q, width,
                             coarsening)
    q = np.asarray(q, np.float64)
    normals = np.asarray(rest_normals, np.float64)
    unpainted = np.linalg.norm(q - np.sum(q * normals, axis=1, keepdims=True) * normals,
                               axis=1) == 0.0
    if not unpainted.any():
        return painted
    curved = curved_phases(rest, normals, rest_tangents, neighbor_offsets, neighbor_indices,
                           width, unpainted)
    return np.where(np.any(painted[:, :3] != 0, axis=1, keepdims=True), painted, curved)
