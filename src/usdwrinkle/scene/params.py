"""Wrinkle parameters from WrinkleAPI attributes, with fallbacks and validation."""
from __future__ import annotations

import hashlib
import logging
import math
from collections import OrderedDict

import numpy as np
from pxr import Usd, UsdGeom

from ..method.profiles import default_profile, derive_gradient
from ..usd import schema
from ..usd.validation import parameter_findings, refuse
from ..usd.values import static_flattened, static_value
from .records import WrinkleParams
from .topology import Topology, mean_edge_length, one_way, signed_curvature

_log = logging.getLogger(__name__)

#: signed_curvature per rest shape (digest of its points and triangles), the last few:
#: read_params runs again on every primvar edit (each paint stroke), and the rest shape's
#: curvature, 0.4 s on a 160k-point mesh here, does not change with them
_REST_CURVATURE: OrderedDict[bytes, np.ndarray] = OrderedDict()
_REST_CURVATURE_KEPT = 8


def rest_curvature(rest_points: np.ndarray, topology: Topology) -> np.ndarray:
    """topology.signed_curvature of the rest shape, remembered for the last
    _REST_CURVATURE_KEPT rest shapes (read only: the array is shared)."""
    digest = hashlib.blake2b(digest_size=16)
    for array in (rest_points, topology.triangles):
        array = np.ascontiguousarray(array)
        digest.update(str((array.dtype, array.shape)).encode())
        digest.update(array.tobytes())
    key = digest.digest()
    bent = _REST_CURVATURE.get(key)
    if bent is None:
        bent = signed_curvature(rest_points, topology)
        bent.setflags(write=False)
        _REST_CURVATURE[key] = bent
        while len(_REST_CURVATURE) > _REST_CURVATURE_KEPT:
            _REST_CURVATURE.popitem(last=False)
    else:
        _REST_CURVATURE.move_to_end(key)
    return bent


def stage_meters(stage: Usd.Stage) -> float:
    """The stage's metersPerUnit, which a cloth preset's width and the curvature gain
    divide by: refused in one line unless finite and > 0 (0 divided by zero, NaN and inf
    gave NaN or infinite widths, and -1 negative ones)."""
    from ..process.errors import UsdWrinkleError
    from ..process.limits import METERS_PER_UNIT_RANGE

    meters = UsdGeom.GetStageMetersPerUnit(stage)
    low, high = METERS_PER_UNIT_RANGE
    if not (math.isfinite(meters) and low <= meters <= high):
        raise UsdWrinkleError(f"metersPerUnit {meters:g} must be finite and within "
                              f"{low:g}..{high:g} (the cloth presets' widths are converted "
                              "through it)", stage.GetRootLayer().identifier, "metersPerUnit")
    return meters


def units_notes(stage: Usd.Stage, records: dict) -> list[str]:
    """Warnings about the units a cloth preset's width goes through (issue 42): the root
    layer's metersPerUnit unauthored (USD's fallback 0.01 then makes W 100x what a
    stage in metres wants), or a sublayer authoring other units than the root's (a stage
    reads them from its root layer only, so that sublayer's sizes are taken as the
    root's). ``records``: path -> MeshRecord of the wrinkled meshes."""
    presets = [path for path, record in records.items() if record.wrinkled and
               "metersPerUnit" in record.params.width_note]
    notes = []
    if presets and not UsdGeom.StageHasAuthoredMetersPerUnit(stage):
        notes.append(f"the stage's root layer authors no metersPerUnit, so the cloth "
                     f"preset's width of {len(presets)} mesh(es) assumes USD's fallback of "
                     "0.01 (centimetres); author the stage's units (1 for metres) "
                     f"({presets[0]})")
    meters = UsdGeom.GetStageMetersPerUnit(stage)
    for layer in stage.GetLayerStack(includeSessionLayers=False)[1:]:
        if layer.pseudoRoot.HasInfo("metersPerUnit"):
            theirs = float(layer.pseudoRoot.GetInfo("metersPerUnit"))
            if not math.isclose(theirs, meters, rel_tol=1e-6):
                notes.append(f"sublayer '{layer.identifier}' authors metersPerUnit "
                             f"{theirs:g} but the stage uses its root layer's {meters:g} "
                             "(a stage reads its units from the root layer only): author the "
                             "root layer's units to match")
    return notes


def _get(prim: Usd.Prim, name: str):
    """An authored WrinkleAPI value by the static rule (None if unauthored)."""
    attr = prim.GetAttribute(name)
    if not attr or not attr.HasAuthoredValue():
        return None
    return static_value(attr)


def _primvar(prim: Usd.Prim, name: str):
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar(name)
    if not primvar or not primvar.HasAuthoredValue():
        return None
    return static_flattened(primvar)


def _profile(prim, name):
    value = _get(prim, name)
    return None if value is None or len(value) == 0 else np.asarray(value, dtype=np.float32)


def read_params(prim: Usd.Prim, rest_points: np.ndarray, topology: Topology,
                relax_override: int | None = None) -> WrinkleParams:
    """Resolve WrinkleAPI values for one mesh (also for --all-meshes, with fallbacks).

    Every value is checked as ``usdwrinkle check`` checks it, at the default time and at
    every time sample, and the first that breaks a rule is refused with a
    UsdWrinkleError naming the prim and the attribute. WrinkleAPI values do not
    animate: each is read once, at the default time, else at its first time sample; a
    value that changes over time gets a warning (logged).
    """
    n = len(rest_points)
    findings = parameter_findings(prim, n)
    refuse([f for f in findings if f.severity == "error"])
    for finding in findings:
        _log.warning("%s", finding.one_line())

    q = np.zeros((n, 3), np.float32)
    value = _primvar(prim, "wrinkle:q")
    if value is not None:
        q = np.asarray(value, dtype=np.float32).reshape(-1, 3)

    cloth = _get(prim, schema.CLOTH)
    cloth = schema.DEFAULT_CLOTH if cloth is None else str(cloth)
    # the rest surface's largest curvature, signed (1 / scene units): its size for a
    # cloth's width (in 1/m), with its sign for the coarsening's cap
    bent = rest_curvature(rest_points, topology)
    meters = stage_meters(prim.GetStage())
    kappa = None if cloth == schema.MESH_CLOTH else np.abs(bent) / meters
    value = _primvar(prim, "wrinkle:width")
    if value is not None:
        arr = np.atleast_1d(np.asarray(value, dtype=np.float32))
        width = np.broadcast_to(arr, (n,)).astype(np.float32)
        width_note = "wrinkle:width"
    else:
        width, width_note = cloth_width(prim, cloth, kappa, rest_points, topology)

    slack = _get(prim, schema.SLACK)
    slack = schema.DEFAULT_SLACK if slack is None else float(slack)
    damping = _get(prim, schema.CREST_DAMPING)
    damping = schema.DEFAULT_CREST_DAMPING if damping is None else float(damping)
    irregularity = _get(prim, schema.IRREGULARITY)
    irregularity = schema.DEFAULT_IRREGULARITY if irregularity is None \
        else float(irregularity)
    held = _primvar(prim, "wrinkle:held")
    hold = None
    if held is not None:
        held = np.asarray(held, np.float32)
        edges = held_edges(held, topology)
        if np.any(held > 0) and not edges.any():
            _log.warning("%s: wrinkle:held holds points but no edge of the mesh (both its "
                         "ends held): lone held points are pins, at which the cloth "
                         "gathers, and damp no wave (docs/method.md, \"Held edges\")",
                         prim.GetPath())
        hold = held_weights(rest_points, edges, width)

    scale = _get(prim, schema.AMPLITUDE_SCALE)
    scale = 1.0 if scale is None else float(scale)

    height = _profile(prim, schema.HEIGHT_PROFILE)
    gradient = _profile(prim, schema.GRADIENT_PROFILE)
    if height is None:
        height = default_profile()
    if gradient is None:
        gradient = derive_gradient(height)

    iterations = _get(prim, schema.RELAX_ITERATIONS)
    if relax_override is not None:
        iterations = relax_override  # the CLI checked it
    iterations = schema.DEFAULT_RELAX_ITERATIONS if iterations is None else int(iterations)

    controls = []
    for name, fallback in ((schema.BIAXIAL, schema.DEFAULT_BIAXIAL),
                           (schema.TENSION, schema.DEFAULT_TENSION),
                           (schema.TENSION_THRESHOLD, schema.DEFAULT_TENSION_THRESHOLD)):
        value = _get(prim, name)
        controls.append(fallback if value is None else float(value))
    from ..method.contract import ONE_WAY_REACH
    from ..method.folds import coarsening_cap, slope_table

    # how one way the rest surface curves within ONE_WAY_REACH W (the mesh's median W)
    ways = one_way(rest_points, bent, ONE_WAY_REACH * float(np.median(width))) if n else bent

    return WrinkleParams(q, width, scale, height, gradient, iterations, *controls,
                         slack=slack, hold=hold, width_note=width_note,
                         crest_damping=damping, slope=slope_table(height),
                         irregularity=irregularity,
                         coarsening=coarsening_cap(
                             width * meters, tube_width(bent / meters), ways).astype(np.float32))


def width_summary(params: WrinkleParams) -> dict:
    """The effective width of one mesh as ``check`` and the bake summary print it: the
    smallest and largest W (scene units) and where it came from."""
    width = np.asarray(params.width, np.float64)
    low, high = (float(width.min()), float(width.max())) if width.size else (0.0, 0.0)
    text = f"W = {_span(low, high)} scene units ({params.width_note})"
    return {"width": [low, high], "source": params.width_note, "text": text}


def _span(low: float, high: float, digits: int = 4) -> str:
    return f"{low:.{digits}g}" if high <= low * (1 + 1e-6) else \
        f"{low:.{digits}g}..{high:.{digits}g}"


def cloth_width(prim: Usd.Prim, cloth: str, kappa: np.ndarray | None,
                rest_points: np.ndarray, topology: Topology) -> tuple:
    """The fallback width W per point, (n,) float32 in scene units, and how it was found:
    the fold wavelength on flat cloth of ``cloth`` (wrinkle:cloth, cotton unless authored)
    through the stage's metersPerUnit, narrowed where the rest surface curves tighter than
    curved_below(it) (curved_width; ``kappa``: its largest curvature in 1/m); with
    wrinkle:cloth = "mesh", a multiple of the mean rest edge length."""
    n = len(rest_points)
    if cloth == schema.MESH_CLOTH:
        width = schema.WIDTH_EDGE_MULTIPLE * mean_edge_length(rest_points, topology)
        width = width if width > 0 else 1.0
        return np.full(n, width, np.float32), (f"{schema.WIDTH_EDGE_MULTIPLE:g} x the mean "
                                               f"rest edge (wrinkle:cloth = mesh)")
    stage = prim.GetStage()
    meters = stage_meters(stage)
    authored = UsdGeom.StageHasAuthoredMetersPerUnit(stage)
    metres = schema.CLOTH_WIDTHS_M[cloth]
    width = curved_width(metres, kappa) / meters
    units = f"metersPerUnit {meters:g}" + ("" if authored else ", USD's fallback: unauthored")
    note = f"{cloth} {100 * metres:g} cm flat"
    if width.size and width.min() < metres / meters * (1 - 1e-6):
        note += f", narrower where curved under {100 * curved_below(metres):.3g} cm"
    return width.astype(np.float32), f"{note} ({units})"


def tube_width(kappa: np.ndarray) -> np.ndarray:
    """The fold wavelength (m) of a tube whose radius is 1 / ``kappa`` (1/m; at least
    schema.CURVED_RADIUS_MIN_M): W_c (R / R_c) ** p (curved_width without the cloth's
    flat width; inf where nothing curves)."""
    kappa = np.abs(np.asarray(kappa, np.float64))
    radius = np.maximum(1.0 / np.maximum(kappa, 1e-300), schema.CURVED_RADIUS_MIN_M)
    tube = schema.CURVED_WIDTH_M * (radius / schema.CURVED_RADIUS_M) ** schema.CURVED_EXPONENT
    return np.where(kappa > 0, tube, np.inf)


def curved_width(flat: float, kappa: np.ndarray) -> np.ndarray:
    """The fold wavelength (m) of a cloth whose flat wavelength is ``flat`` (m) at points
    whose largest rest curvature is ``kappa`` (1/m): min(flat, W_c (R / R_c) ** p), R = 1 /
    kappa (at least schema.CURVED_RADIUS_MIN_M), W_c = schema.CURVED_WIDTH_M at R_c =
    schema.CURVED_RADIUS_M, p = schema.CURVED_EXPONENT: on a tube the folds are the
    tube's, whatever the cloth (docs/method.md: the cloth's width)."""
    return np.minimum(flat, tube_width(kappa))


def curved_below(flat: float) -> float:
    """The rest radius of curvature (m) under which ``flat``'s width narrows (curved_width):
    where the tube's width meets the flat one."""
    return schema.CURVED_RADIUS_M * (flat / schema.CURVED_WIDTH_M) ** (
        1.0 / schema.CURVED_EXPONENT)


def held_edges(held: np.ndarray, topology: Topology) -> np.ndarray:
    """(n,) float32: the held weight with which each point damps the waves around it, the
    firmest held edge through it, an edge of the mesh held as firmly as its weaker end
    (wrinkle:held, one value per point or one for all). A held point on no held edge is a
    pin, as a curtain's ring: it holds its point, not the cloth around it, which gathers
    at it, and damps nothing. Measured against the converged referee, whose curtains hang
    from rings 6 cm apart and gather there (the coarse mesh holds every third of its top
    points): its rings damping the waves over 2 W as a held edge does, the leather
    curtain's folds stood evenly down it and correlated 0.826 with the cloth's (bar 0.85);
    as pins 0.875 (docs/physics.md, "Pins and held edges"). Blender's curtain, whose whole
    rail is pinned, is a held edge either way."""
    n = topology.num_points
    weights = np.broadcast_to(np.atleast_1d(np.asarray(held, np.float32)), (n,))
    offsets = np.asarray(topology.neighbor_offsets, np.int64)
    neighbours = np.asarray(topology.neighbor_indices, np.int64)
    point = np.repeat(np.arange(n), np.diff(offsets))
    out = np.zeros(n, np.float32)
    np.maximum.at(out, point, np.minimum(weights[point], weights[neighbours]))
    return out


def held_weights(rest_points: np.ndarray, held: np.ndarray, width: np.ndarray) -> np.ndarray:
    """What held points leave each point: (n, 4) float32, x the damping strength
    max_j w_j f(d_ij / (HELD_REACH W_i)) with f(t) = 1 - smoothstep(0, 1, t), d the
    rest-space distance and w_j the held weight of point j (wrinkle:held, in [0, 1]; one
    constant value holds every point); yzw the rest-space unit vector from that strongest
    holder to the point (0 on a held point, and where nothing reaches). The crush pass damps
    a wave by x (1 - (d . u)^2) for its rest direction d: a wave whose crests run into the
    held edge fades towards it, one whose crests run along it does not (docs/method.md:
    held edges).

    Only holders within a point's reach count, so the pairs come from a uniform grid of
    cells as large as the largest reach: linear in the points for a mesh of even density
    (all-pairs was quadratic: 22,500 points, all held, took 49 s). Ties go to the holder
    of the lower index, as numpy's argmax over all pairs would."""
    n = len(rest_points)
    weights = np.broadcast_to(np.atleast_1d(held).astype(np.float64), (n,))
    holders = np.flatnonzero(weights > 0)
    out = np.zeros((n, 4), np.float32)
    if len(holders) == 0:
        return out
    rest = np.asarray(rest_points, np.float64)
    reach = np.maximum(schema.HELD_REACH * np.broadcast_to(
        np.asarray(width, np.float64), (n,)), 1e-30)
    if not (np.all(np.isfinite(rest)) and np.all(np.isfinite(reach))):
        return _held_all_pairs(rest, weights, holders, reach, out)
    cell = float(reach.max())
    origin = rest.min(axis=0)
    cells = np.floor((rest - origin) / cell).astype(np.int64)
    span = cells.max(axis=0) + 3  # room for the -1 .. +1 neighbours of every cell
    if float(np.prod(span.astype(np.float64))) >= 2.0 ** 62:
        return _held_all_pairs(rest, weights, holders, reach, out)

    def key(c):
        return ((c[:, 0] + 1) * span[1] + (c[:, 1] + 1)) * span[2] + (c[:, 2] + 1)

    holder_keys = key(cells[holders])
    order = np.argsort(holder_keys, kind="stable")
    sorted_keys, sorted_holders = holder_keys[order], holders[order]
    best = np.zeros(n, np.float64)
    best_holder = np.full(n, -1, np.int64)
    # a point held with the largest weight is its own strongest holder (t = 0; any tie is
    # at distance 0, whose direction is 0 too): no search (all held: no pairs at all)
    top = weights == weights[holders].max()
    best[top] = weights[top]
    best_holder[top] = np.flatnonzero(top)
    searched = np.flatnonzero(~top)
    offsets = np.array([(a, b, c) for a in (-1, 0, 1) for b in (-1, 0, 1) for c in (-1, 0, 1)])
    block = 65536
    for start in range(0, len(searched), block):
        points = searched[start:start + block]
        for offset in offsets:
            k = key(cells[points] + offset)
            lo = np.searchsorted(sorted_keys, k, "left")
            hi = np.searchsorted(sorted_keys, k, "right")
            _held_pairs(rest, weights, reach, points, lo, hi, sorted_holders, best,
                        best_holder)
    reached = best > 0
    out[reached, 0] = best[reached]
    away = rest[reached] - rest[best_holder[reached]]
    length = np.linalg.norm(away, axis=1)[:, None]
    out[reached, 1:] = np.where(length > 1e-12, away / np.maximum(length, 1e-30), 0.0)
    return out


def _held_pairs(rest, weights, reach, points, lo, hi, sorted_holders, best, best_holder):
    """Fold the pairs (points[i], sorted_holders[lo[i]:hi[i]]) into best/best_holder, in
    chunks of at most a few million pairs."""
    lengths = hi - lo
    limit = 4_000_000
    first = 0
    while first < len(points):
        total = np.cumsum(lengths[first:])
        last = first + max(1, int(np.searchsorted(total, limit, "right")))
        count = lengths[first:last]
        if count.sum():
            which = np.repeat(np.arange(first, last), count)
            starts = np.repeat(np.cumsum(count) - count, count)
            holder = sorted_holders[lo[which] + np.arange(len(which)) - starts]
            point = points[which]
            d = np.linalg.norm(rest[point] - rest[holder], axis=1)
            t = np.clip(d / reach[point], 0.0, 1.0)
            strength = weights[holder] * (1.0 - t * t * (3.0 - 2.0 * t))
            better = (strength > best[point]) | ((strength == best[point]) & (strength > 0) & (
                (best_holder[point] < 0) | (holder < best_holder[point])))
            # the best pair of each point among this chunk's better ones
            point, holder, strength = point[better], holder[better], strength[better]
            pick = np.lexsort((holder, -strength, point))
            point, holder, strength = point[pick], holder[pick], strength[pick]
            head = np.ones(len(point), bool)
            head[1:] = point[1:] != point[:-1]
            best[point[head]] = strength[head]
            best_holder[point[head]] = holder[head]
        first = last


def _held_all_pairs(rest, weights, holders, reach, out):
    """held_weights over every (point, holder) pair: for points no grid can hold."""
    n = len(rest)
    anchor, anchor_weight = rest[holders], weights[holders]
    block = max(1, 4_000_000 // len(holders))
    for start in range(0, n, block):
        offset = rest[start:start + block, None, :] - anchor[None]
        d = np.linalg.norm(offset, axis=2)
        t = np.clip(d / reach[start:start + block, None], 0.0, 1.0)
        strength = anchor_weight[None] * (1.0 - t * t * (3.0 - 2.0 * t))
        best = strength.argmax(axis=1)
        rows = np.arange(len(best))
        out[start:start + block, 0] = strength[rows, best]
        away = offset[rows, best]
        length = d[rows, best][:, None]
        out[start:start + block, 1:] = np.where(
            (length > 1e-12) & (strength[rows, best][:, None] > 0),
            away / np.maximum(length, 1e-30), 0.0)
    return out
