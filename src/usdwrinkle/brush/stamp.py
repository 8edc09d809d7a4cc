"""The brush: what a stamp does to q (and W) on one mesh's rest pose. numpy only: no Qt,
no GL, no USD, so another front end (a DCC, a test) paints with the same code.

q is the method's painted rest-space vector (docs/method.md: the crush biases the fitted
map by ``M (I - q q^T)``). It is a line, not an arrow: q and -q paint the same wrinkles,
so a stamp aligns its direction's sign with the q already there before blending.

A stamp at a rest-space point c with radius R gives each vertex i a weight
``strength * pressure * falloff(d_i / R)``, d_i its rest-space distance from c: geodesic
(shortest paths along the mesh's edges, seeded from the hit triangle's corners) or
Euclidean. Front-facing only: vertices whose posed normal faces away from the eye get
none. Symmetry: a second stamp through a rest-space plane, its direction mirrored.
"""
from __future__ import annotations

import heapq
from dataclasses import dataclass, field

import numpy as np

from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_WORLD_COORDINATE

MODES = ("comb", "smooth", "erase", "width", "attract")
#: the modes that need the stroke's direction (the first move of a drag gives it)
DIRECTED = ("comb", "attract")
#: the stamp profiles, the default first: ``sphere`` combs nearly the brush's whole width
#: (a comb's teeth rake across it), so that a stroke's folds span it (issue 55: with
#: ``smooth`` they covered the middle 62% of it on the shirt's sleeve)
FALLOFFS = ("sphere", "smooth", "linear", "constant")
MIRROR_AXES = (None, "x", "y", "z")
#: how far inside a comb stamp's rim the painted amount tapers to nothing, in the
#: wrinkles' own W at each vertex, less the vertex's edge length (over which the mesh's
#: interpolation already spreads a fold's end), at most half the brush's radius: cloth's
#: folds die out over about their own wavelength, where a stroke that painted its full
#: amount up to the rim stood as a band of folds cut off along two straight lines on a
#: mesh finer than its W (2026-12-06). The ``constant`` profile keeps its hard edge.
COMB_TAPER = 1.0


def falloff(name: str, t: np.ndarray) -> np.ndarray:
    """The stamp's profile over t = distance / radius in [0, 1] (0 beyond)."""
    t = np.clip(np.asarray(t, np.float64), 0.0, 1.0)
    if name == "smooth":
        value = (1.0 - t * t) ** 2
    elif name == "linear":
        value = 1.0 - t
    elif name == "constant":
        value = np.ones_like(t)
    elif name == "sphere":
        value = np.sqrt(np.maximum(1.0 - t * t, 0.0))
    else:
        raise UsdWrinkleError(f"unknown falloff {name!r} (one of {', '.join(FALLOFFS)})")
    return np.where(t < 1.0, value, 0.0)


@dataclass(frozen=True)
class BrushSettings:
    """What the artist sets: mode, size, strength, profile, symmetry."""

    mode: str = "comb"
    #: rest-space radius (scene units of the mesh's local space)
    radius: float = 0.1
    #: how far one stamp moves a vertex towards its target, in [0, 1]
    strength: float = 0.5
    #: |q| that comb paints, in [0, 1]
    amount: float = 1.0
    falloff: str = "sphere"
    #: distances along the surface (True) or straight through space
    geodesic: bool = True
    front_facing_only: bool = True
    #: mirror plane through the rest-space origin: None, "x", "y" or "z" (its normal)
    mirror: str | None = None
    #: stamps per radius along a stroke (Maya's stamp spacing)
    spacing: float = 0.25
    #: the W that the width mode paints
    width: float = 0.05

    def __post_init__(self):
        # every refusal is a UsdWrinkleError naming the field (issue 54): a brush made by a
        # script, a preset file or the window is checked alike
        if self.mode not in MODES:
            raise UsdWrinkleError(f"`mode` {self.mode!r} is not a brush mode (one of "
                                  f"{', '.join(MODES)})")
        if self.falloff not in FALLOFFS:
            raise UsdWrinkleError(f"`falloff` {self.falloff!r} is not a falloff (one of "
                                  f"{', '.join(FALLOFFS)})")
        for name, low, high, open_low in (("radius", 0.0, MAX_WORLD_COORDINATE, True),
                                          ("strength", 0.0, 1.0, False),
                                          ("amount", 0.0, 1.0, False),
                                          ("spacing", 0.0, 100.0, True),
                                          ("width", 0.0, MAX_WORLD_COORDINATE, True)):
            value = _number(getattr(self, name), name)
            if not (low < value if open_low else low <= value) or not value <= high:
                raise UsdWrinkleError(f"brush `{name}` {value:g} must be in "
                                      f"{'(' if open_low else '['}{low:g}, {high:g}]")
            object.__setattr__(self, name, value)
        if not isinstance(self.geodesic, (bool, np.bool_)):
            raise UsdWrinkleError(f"brush `geodesic` must be True or False, not "
                                  f"{self.geodesic!r}")
        if not isinstance(self.front_facing_only, (bool, np.bool_)):
            raise UsdWrinkleError(f"brush `front_facing_only` must be True or False, not "
                                  f"{self.front_facing_only!r}")
        if self.mirror not in MIRROR_AXES:
            raise UsdWrinkleError(f"brush `mirror` must be x, y, z or None, not "
                                  f"{self.mirror!r}")


def _number(value, name: str) -> float:
    """A real number (numpy's too), never a bool or a string."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                      np.floating)):
        raise UsdWrinkleError(f"brush `{name}` must be a number, not {value!r}")
    value = float(value)
    if not np.isfinite(value):
        raise UsdWrinkleError(f"brush `{name}` must be finite, not {value:g}")
    return value


@dataclass
class Hit:
    """Where a ray met a mesh: the triangle, its barycentrics, the rest-space point."""

    path: str
    triangle: int
    barycentric: np.ndarray
    rest_point: np.ndarray
    distance: float


@dataclass
class PaintMesh:
    """One mesh's rest pose as the brush needs it (local space), and its paint."""

    path: str
    rest_points: np.ndarray      # (n, 3) float64
    rest_normals: np.ndarray     # (n, 3) float64, unit
    triangles: np.ndarray        # (m, 3) int
    q: np.ndarray                # (n, 3) float32, |q| <= 1
    width: np.ndarray            # (n,) float32
    _neighbours: list = field(default_factory=list, repr=False)

    def __post_init__(self):
        self.rest_points = np.asarray(self.rest_points, np.float64)
        self.rest_normals = np.asarray(self.rest_normals, np.float64)
        self.triangles = np.asarray(self.triangles, np.int64).reshape(-1, 3)
        self.q = np.array(self.q, np.float32).reshape(-1, 3)
        self.width = np.array(self.width, np.float32).reshape(-1)
        n = len(self.rest_points)
        edges = np.concatenate([self.triangles[:, [0, 1]], self.triangles[:, [1, 2]],
                                self.triangles[:, [2, 0]]])
        edges = np.unique(np.sort(edges, axis=1), axis=0)
        lengths = np.linalg.norm(self.rest_points[edges[:, 0]] - self.rest_points[edges[:, 1]],
                                 axis=1)
        self._neighbours = [[] for _ in range(n)]
        for (a, b), length in zip(edges.tolist(), lengths.tolist(), strict=True):
            self._neighbours[a].append((b, length))
            self._neighbours[b].append((a, length))
        self._mirror_maps: dict[str, np.ndarray] = {}
        self._spacing: np.ndarray | None = None

    @property
    def count(self) -> int:
        return len(self.rest_points)

    def neighbours(self, i: int) -> list[int]:
        return [j for j, _ in self._neighbours[i]]

    def distances(self, hit_point: np.ndarray, triangle: int | None, radius: float,
                  geodesic: bool) -> np.ndarray:
        """Rest-space distance of every vertex from ``hit_point`` (inf beyond
        ``radius``): along the edges from the hit triangle's corners, or straight."""
        straight = np.linalg.norm(self.rest_points - hit_point, axis=1)
        if not geodesic or triangle is None:
            return np.where(straight <= radius, straight, np.inf)
        out = np.full(self.count, np.inf)
        heap = []
        for corner in self.triangles[triangle]:
            d = float(straight[corner])
            if d < out[corner]:
                out[corner] = d
                heapq.heappush(heap, (d, int(corner)))
        while heap:
            d, i = heapq.heappop(heap)
            if d > out[i] or d > radius:
                continue
            for j, length in self._neighbours[i]:
                nd = d + length
                if nd < out[j] and nd <= radius:
                    out[j] = nd
                    heapq.heappush(heap, (nd, j))
        # a path along edges is never shorter than the straight line
        return np.where(out <= radius, np.maximum(out, straight), np.inf)

    def mirror_map(self, axis: str) -> np.ndarray:
        """Each vertex's mirror partner through the plane ``axis`` = 0 (the nearest
        vertex to its mirror image; -1 where none lies within a hundredth of the mean
        edge length). The candidates come from a hash grid of cells as large as that
        tolerance (the 27 cells around each image), so the time is linear in the points:
        comparing all pairs took 98-113 s at 62,500 points."""
        if axis in self._mirror_maps:
            return self._mirror_maps[axis]
        k = "xyz".index(axis)
        mirrored = self.rest_points.copy()
        mirrored[:, k] *= -1.0
        tolerance = 1e-2 * self.mean_edge()
        partner = np.full(self.count, -1, np.int64)
        best = np.full(self.count, np.inf)
        if self.count and tolerance > 0.0:
            origin = np.minimum(self.rest_points.min(axis=0), mirrored.min(axis=0))
            cells = np.floor((self.rest_points - origin) / tolerance).astype(np.int64)
            images = np.floor((mirrored - origin) / tolerance).astype(np.int64)
            keys = _cell_keys(cells)
            order = np.argsort(keys, kind="stable")
            sorted_keys = keys[order]
            for offset in np.stack(np.meshgrid(*[[-1, 0, 1]] * 3, indexing="ij"),
                                   -1).reshape(-1, 3):
                wanted = _cell_keys(images + offset)
                lo = np.searchsorted(sorted_keys, wanted, "left")
                hi = np.searchsorted(sorted_keys, wanted, "right")
                for step in range(int((hi - lo).max(initial=0))):
                    rows = np.nonzero(lo + step < hi)[0]
                    candidates = order[lo[rows] + step]
                    d2 = ((mirrored[rows] - self.rest_points[candidates]) ** 2).sum(-1)
                    closer = d2 < best[rows]
                    best[rows[closer]] = d2[closer]
                    partner[rows[closer]] = candidates[closer]
        partner[best > tolerance ** 2] = -1
        self._mirror_maps[axis] = partner
        return partner

    def mean_edge(self) -> float:
        lengths = [length for row in self._neighbours for _, length in row]
        return float(np.mean(lengths)) if lengths else 1.0

    def spacing(self) -> np.ndarray:
        """Per vertex, the mean rest length of its edges (0 for a lone vertex)."""
        if self._spacing is None:
            self._spacing = np.array([np.mean([length for _, length in row]) if row else 0.0
                                      for row in self._neighbours])
        return self._spacing


def _cell_keys(cells: np.ndarray) -> np.ndarray:
    """One int64 per grid cell (a hash: a collision only adds a candidate, which the
    distance test then drops)."""
    c = cells.astype(np.int64)
    return (c[:, 0] * np.int64(73856093)) ^ (c[:, 1] * np.int64(19349663)) ^ \
        (c[:, 2] * np.int64(83492791))


def mirror_vector(v: np.ndarray, axis: str | None) -> np.ndarray:
    """``v`` reflected through the plane whose normal is ``axis``."""
    out = np.array(v, np.float64, copy=True)
    if axis is not None:
        out[..., "xyz".index(axis)] *= -1.0
    return out


def tangent_directions(mesh: PaintMesh, direction: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``direction`` projected onto the rest tangent plane of each vertex in ``index``,
    unit length (zero where it is along the normal)."""
    n = mesh.rest_normals[index]
    d = np.asarray(direction, np.float64)[None, :] - \
        (n @ np.asarray(direction, np.float64))[:, None] * n
    length = np.linalg.norm(d, axis=1, keepdims=True)
    return np.where(length > 1e-12, d / np.maximum(length, 1e-300), 0.0)


def stamp(mesh: PaintMesh, brush: BrushSettings, centre: np.ndarray, triangle: int | None,
          direction: np.ndarray | None, facing: np.ndarray | None = None,
          pressure: float = 1.0) -> np.ndarray:
    """Apply one stamp (and its mirror) to ``mesh`` in place; returns the indices of the
    vertices it touched (weight > 0). ``direction``: the stroke's rest-space tangent
    (comb); ``facing``: per vertex, whether it faces the eye (front-facing only).

    With a mirror plane, the stamp and its mirror act at once, from the values before
    them: where both reach (a stroke across the plane) a vertex's weight is
    ``1 - (1 - w)(1 - w')`` and its target the weighted mean of both targets, so the
    result is the mirror image of its partner's, whichever stamp came first."""
    weight, reach = _weights(mesh, brush, np.asarray(centre, np.float64), triangle, facing,
                             pressure)
    if brush.mirror is None:
        index = np.nonzero(weight > 0.0)[0]
        if len(index):
            _apply(mesh, brush, index, weight[index], None, direction, None,
                   reach[index])
        return index
    # the mirror stamp: each vertex takes its mirror partner's weight (exactly symmetric on
    # a mesh whose rest pose is), the direction mirrored; a vertex with no partner is
    # weighed from the mirrored centre
    partner = mesh.mirror_map(brush.mirror)
    mirrored = np.where(partner >= 0, weight[np.maximum(partner, 0)], 0.0)
    mirrored_reach = np.where(partner >= 0, reach[np.maximum(partner, 0)], np.inf)
    lone = partner < 0
    if lone.any():
        centre_m = mirror_vector(centre, brush.mirror)
        lone_weight, lone_reach = _weights(mesh, brush, centre_m,
                                           _nearest_triangle(mesh, centre_m), None, pressure)
        mirrored[lone], mirrored_reach[lone] = lone_weight[lone], lone_reach[lone]
    index = np.nonzero((weight > 0.0) | (mirrored > 0.0))[0]
    if len(index):
        _apply(mesh, brush, index, weight[index], mirrored[index], direction,
               None if direction is None else mirror_vector(direction, brush.mirror),
               np.minimum(reach[index], mirrored_reach[index]))
    return index


def _weights(mesh: PaintMesh, brush: BrushSettings, centre: np.ndarray, triangle: int | None,
             facing, pressure: float) -> tuple[np.ndarray, np.ndarray]:
    """Each vertex's weight under a stamp at ``centre``, and its distance from it."""
    if triangle is None and brush.geodesic:
        triangle = _nearest_triangle(mesh, centre)
    distance = mesh.distances(centre, triangle, brush.radius, brush.geodesic)
    weight = brush.strength * float(np.clip(pressure, 0.0, 1.0)) * \
        falloff(brush.falloff, distance / brush.radius)
    if facing is not None and brush.front_facing_only:
        weight = np.where(facing, weight, 0.0)
    return weight, distance


def _nearest_triangle(mesh: PaintMesh, point: np.ndarray) -> int | None:
    if not len(mesh.triangles):
        return None
    centres = mesh.rest_points[mesh.triangles].mean(axis=1)
    return int(np.argmin(np.linalg.norm(centres - point, axis=1)))


def _apply(mesh: PaintMesh, brush: BrushSettings, index: np.ndarray, weight: np.ndarray,
           mirrored: np.ndarray | None, direction: np.ndarray | None,
           mirrored_direction: np.ndarray | None, reach: np.ndarray | None = None) -> None:
    """One stamp at ``index`` with ``weight`` (and its mirror's ``mirrored`` weight and
    direction, applied at once: see stamp); ``reach``: each vertex's distance from the
    nearer of the two stamps' centres (comb's taper)."""
    w1 = weight
    w2 = np.zeros_like(w1) if mirrored is None else mirrored
    combined = 1.0 - (1.0 - w1) * (1.0 - w2)
    if brush.mode == "width":
        mesh.width[index] = (mesh.width[index] + combined * (brush.width - mesh.width[index])
                             ).astype(np.float32)
        return
    q = mesh.q[index].astype(np.float64)
    w = combined[:, None]
    if brush.mode in DIRECTED:
        if direction is None or not np.any(direction):
            return
        amount = _comb_amount(mesh, brush, index, q, reach)
        target = _comb_target(mesh, index, q, direction, amount)
        if mirrored is not None:
            other = _comb_target(mesh, index, q, mirrored_direction, amount)
            empty = np.linalg.norm(q, axis=1) <= 1e-9
            # where q is empty the two lines' signs are set by each other, then the mean by
            # a sign the mirror keeps (the largest component off the mirror axis)
            other[empty & (np.sum(other * target, axis=1) < 0.0)] *= -1.0
            total = np.maximum(w1 + w2, 1e-300)[:, None]
            target = (w1[:, None] * target + w2[:, None] * other) / total
            axis = "xyz".index(brush.mirror)
            kept = np.delete(target, axis, axis=1)
            lead = kept[np.arange(len(kept)), np.argmax(np.abs(kept), axis=1)]
            target[empty & (lead < 0.0)] *= -1.0
        if brush.mode == "attract":
            # Comb's attract: q turns towards the stroke, its amount kept
            amount = np.linalg.norm(q, axis=1, keepdims=True)
            length = np.linalg.norm(target, axis=1, keepdims=True)
            target = np.where(length > 1e-12, target / np.maximum(length, 1e-300), 0.0) * amount
            turned = q + w * (target - q)
            size = np.linalg.norm(turned, axis=1, keepdims=True)
            q = np.where(size > 1e-12, turned / np.maximum(size, 1e-300) * amount, q)
        else:
            q = q + w * (target - q)
    elif brush.mode == "erase":
        q = q * (1.0 - w)
    elif brush.mode == "smooth":
        q = q + w * (_neighbour_mean(mesh, index) - q)
    mesh.q[index] = clamp_unit(q).astype(np.float32)


def _comb_amount(mesh: PaintMesh, brush: BrushSettings, index: np.ndarray, q: np.ndarray,
                 reach: np.ndarray | None) -> np.ndarray:
    """Per vertex, the |q| that a comb stamp moves q towards: the brush's ``amount``,
    tapering linearly to 0 over the last ``COMB_TAPER`` W (less the vertex's edge length,
    over which the mesh spreads the fold's end itself; at most half the radius) inside
    the rim, so that a stroke's folds die out at its edges as cloth's do. Where q already
    holds more (up to ``amount``), the taper leaves it: overlapping strokes do not carve
    valleys into each other, and a stroke of a lower amount still lowers q to it."""
    amount = np.full(len(index), brush.amount)
    if reach is None or brush.falloff == "constant":
        return amount
    # the mesh's own interpolation between its points already spreads a step over an
    # edge: only the rest of the W is tapered (none on a mesh as coarse as its folds)
    taper = np.clip(COMB_TAPER * mesh.width[index].astype(np.float64) -
                    mesh.spacing()[index], 0.0, 0.5 * brush.radius)
    if not np.any(taper > 0.0):
        return amount
    inside = np.clip((brush.radius - reach) / np.maximum(taper, 1e-300), 0.0, 1.0)
    held = np.minimum(np.linalg.norm(q, axis=1), brush.amount)
    return np.maximum(brush.amount * inside, held)


def _comb_target(mesh: PaintMesh, index: np.ndarray, q: np.ndarray, direction: np.ndarray,
                 amount: np.ndarray) -> np.ndarray:
    """What comb moves q towards: the stroke's direction in each tangent plane, of length
    ``amount`` (per vertex), its sign nearer the q already there (a line, not an arrow)."""
    target = amount[:, None] * tangent_directions(mesh, direction, index)
    flip = np.sum(target * q, axis=1) < 0.0
    target[flip] *= -1.0
    return target


def _neighbour_mean(mesh: PaintMesh, index: np.ndarray) -> np.ndarray:
    """The mean of each vertex's neighbours' q (and its own), each sign-aligned to the
    vertex's own q first (q is a line)."""
    out = np.zeros((len(index), 3))
    for row, i in enumerate(index.tolist()):
        own = mesh.q[i].astype(np.float64)
        total = own.copy()
        for j in mesh.neighbours(i):
            other = mesh.q[j].astype(np.float64)
            total += -other if other @ own < 0.0 else other
        out[row] = total / (1 + len(mesh.neighbours(i)))
    return out


def flood(mesh: PaintMesh, brush: BrushSettings, direction: np.ndarray | None) -> np.ndarray:
    """The brush's mode over every vertex at its strength (comb: along ``direction``,
    projected per vertex); returns the indices changed."""
    index = np.arange(mesh.count)
    _apply(mesh, brush, index, np.full(mesh.count, brush.strength), None, direction, None)
    return index


def clamp_unit(q: np.ndarray) -> np.ndarray:
    """Shorten vectors longer than 1 to length 1 (the schema's |q| <= 1); float32 safe."""
    q = np.asarray(q, np.float64)
    length = np.linalg.norm(q, axis=1, keepdims=True)
    return np.where(length > 1.0, q / np.maximum(length, 1e-300) * (1.0 - 1e-7), q)


def spread(q: np.ndarray, index: np.ndarray) -> float:
    """How much q's direction varies over ``index``: 1 - the largest eigenvalue share of
    the (sign-free) direction tensor sum q q^T / |q|^2 (0: all parallel)."""
    v = np.asarray(q, np.float64)[index]
    length = np.linalg.norm(v, axis=1)
    v = v[length > 1e-9] / length[length > 1e-9, None]
    if not len(v):
        return 0.0
    tensor = v.T @ v / len(v)
    return float(1.0 - np.linalg.eigvalsh(tensor)[-1])


class Stroke:
    """Stamps spaced along a drag: each new sample places stamps every
    ``spacing * radius`` of rest-space travel since the last one (or closer: ``min_step``,
    the rest-space length of a few pixels, so that a short drag with a huge brush paints
    too), each combing along the travel's direction. A mode without a direction stamps on
    the press; comb stamps at the press point as soon as the first step gives it one."""

    def __init__(self, mesh: PaintMesh, brush: BrushSettings):
        self.mesh, self.brush = mesh, brush
        self.last: np.ndarray | None = None
        self.direction: np.ndarray | None = None
        self.touched: set[int] = set()
        #: the rest-space centre of every stamp placed
        self.centres: list[np.ndarray] = []
        #: the press's triangle and pressure (comb stamps there once it has a direction)
        self._first: tuple = (None, 1.0)

    def add(self, hit: Hit, facing: np.ndarray | None, pressure: float = 1.0,
            min_step: float | None = None) -> int:
        """A new sample of the drag; returns the stamps placed. ``min_step``: the
        rest-space spacing that stamps never exceed (PaintSession passes the length of
        SCREEN_SPACING pixels there)."""
        point = np.asarray(hit.rest_point, np.float64)
        if self.last is None:
            self.last = point
            self._first = (hit.triangle, pressure)
            if self.brush.mode not in DIRECTED:  # the first move gives comb a direction
                self._stamp(point, hit.triangle, None, facing, pressure)
                return 1
            return 0
        travel = point - self.last
        length = float(np.linalg.norm(travel))
        step = self.brush.spacing * self.brush.radius
        if min_step is not None and min_step > 0.0:
            step = min(step, min_step)
        if length < step or not step > 0.0:
            return 0
        self.direction = travel / length
        count = int(length / step + 1e-9)  # 0.5 / 0.05 is 10 stamps, not 9
        first = 1
        if self.brush.mode in DIRECTED and not self.centres:
            first = 0  # the press point, now that the stroke has a direction
        for k in range(first, count + 1):
            centre = self.last + travel * (k * step / length)
            tri = hit.triangle if k == count else (self._first[0] if k == 0 else None)
            self._stamp(centre, tri, self.direction, facing,
                        self._first[1] if k == 0 else pressure)
        self.last = self.last + travel * (count * step / length)
        return count + 1 - first

    def _stamp(self, centre, triangle, direction, facing, pressure) -> None:
        touched = stamp(self.mesh, self.brush, centre, triangle, direction, facing, pressure)
        self.touched.update(touched.tolist())
        self.centres.append(np.array(centre, np.float64))
