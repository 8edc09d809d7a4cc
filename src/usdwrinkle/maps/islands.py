"""The wrinkle maps' own texture layout: one UV island per face (``--map-layout islands``).

Why (docs/method.md, "Map layout"): a tangent-space normal map is decoded per triangle,
and across a deforming quad's diagonal the posed triangles' frames turn apart (29 degrees
at the shirt's elbow). Storm shades its multisamples at the pixel's centre, so a pixel on
a triangle's edge reads its neighbour's texels and decodes them in the wrong frame: a
one-pixel line along every coarse edge. This layout removes both causes:

- every face is its own island, surrounded by a gutter that only its own padding fills,
  so no sample ever reads another face's texels;
- a face is unfolded from the rest pose about its fan's first diagonal (corners 0 and 2,
  the diagonal every renderer splits a quad along) with that diagonal along s. On a line
  of constant t, dP/ds is that diagonal's direction in *both* triangles of a quad, so
  the per-triangle frame (Storm's, usdwrinkle's) is one continuous frame over the face,
  whatever the pose; and MikkTSpace's per-corner tangents all start from that one
  direction, so Blender's frame is nearly the same;
- the diagonal 0-2 is made the shorter one in UV (t stretched where a skewed quad needs
  it), because MikkTSpace splits a quad along its shorter UV diagonal.

Faces of more than four corners are unfolded as a fan about corner 0 (each triangle
hinged on the one before), so only the first diagonal is along s. The islands are packed
in rows into [0, 1]^2 with ``2 * padding`` texels between them at ``size``. Numpy only:
no Usd, no GL; the layout depends on the rest pose alone, so it is made once per mesh.
"""
from __future__ import annotations

import numpy as np

from ..method.polygons import face_starts
from .tangents import _unit

#: the MikkTSpace split: |uv2 - uv0|^2 must stay below this share of |uv3 - uv1|^2
DIAGONAL_MARGIN = 0.9
#: the most a quad's t is stretched to make its 0-2 diagonal the shorter one
MAX_STRETCH = 4.0
#: islands of fewer texels on their longer side get a warning (a wave needs 2 texels)
MIN_ISLAND = 16
#: the smallest island side (texels) a layout is made with, whatever the padding
SMALLEST_ISLAND = 6


def _place(origin_3d, edge_end_3d, new_3d, origin_2d, edge_end_2d, side: float):
    """2D position of ``new_3d`` unfolded isometrically beside the edge origin -> end,
    on its left (``side`` +1) or right (-1)."""
    axis3 = _unit(edge_end_3d - origin_3d)
    rel = new_3d - origin_3d
    along = np.sum(rel * axis3, axis=-1, keepdims=True)
    across = np.linalg.norm(rel - along * axis3, axis=-1, keepdims=True)
    axis2 = _unit(edge_end_2d - origin_2d)
    left2 = np.stack([-axis2[..., 1], axis2[..., 0]], axis=-1)
    return origin_2d + along * axis2 + side * across * left2


def unfold_faces(points: np.ndarray, triangles: np.ndarray, triangle_face: np.ndarray,
                 corner_face_vertex: np.ndarray, face_vertices: int) -> np.ndarray:
    """(face_vertices, 2) float64: each face corner's position in its face's own plane
    (rest units), corner 0 at the origin and the diagonal 0 -> 2 along +s. Corners of no
    triangle (holes, faces of fewer than 3 corners) stay at the origin."""
    points = np.asarray(points, np.float64)
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    faces = np.asarray(triangle_face, np.int64)
    corners = np.asarray(corner_face_vertex, np.int64).reshape(-1, 3)
    uv = np.zeros((int(face_vertices), 2))
    if not len(triangles):
        return uv
    # the first triangle of each face, and each triangle's index within its face
    first = np.ones(len(faces), bool)
    first[1:] = faces[1:] != faces[:-1]
    starts = np.flatnonzero(first)
    rank = np.arange(len(faces)) - np.repeat(starts, np.diff(np.append(starts, len(faces))))
    p = points[triangles]
    # first triangles: corner a at the origin, c along +s, b on the right of a -> c
    # (the triangle then winds counter-clockwise in UV, as it does about its normal)
    lead = starts
    a2 = np.zeros((len(lead), 2))
    c2 = np.stack([np.linalg.norm(p[lead, 2] - p[lead, 0], axis=-1), np.zeros(len(lead))], -1)
    b2 = _place(p[lead, 0], p[lead, 2], p[lead, 1], a2, c2, -1.0)
    uv[corners[lead, 0]] = a2
    uv[corners[lead, 1]] = b2
    uv[corners[lead, 2]] = c2
    # later triangles of a fan, hinged on the edge they share with the one before
    # (corner 0 -> corner 1 of this triangle), in order of their rank
    later = np.flatnonzero(rank > 0)
    fan = (corners[later, 0] == corners[later - 1, 0]) & \
        (corners[later, 1] == corners[later - 1, 2])
    odd = np.unique(faces[later[~fan]])   # ear-clipped concave faces
    for r in range(1, int(rank.max(initial=0)) + 1):
        rows = np.flatnonzero(rank == r)
        uv[corners[rows, 2]] = _place(p[rows, 0], p[rows, 1], p[rows, 2],
                                      uv[corners[rows, 0]], uv[corners[rows, 1]], 1.0)
    for face in odd:
        _project(points, triangles[faces == face], corners[faces == face], uv)
    return uv


def _project(points, triangles, corners, uv) -> None:
    """A face whose triangles are not a fan (an ear-clipped concave face): projected onto
    the plane of its first triangle, s along that triangle's 0 -> 2 edge."""
    p = points[triangles[0]]
    s = _unit(p[2] - p[0])
    t = np.cross(_unit(np.cross(p[1] - p[0], p[2] - p[0])), s)
    rel = points[triangles] - p[0]                           # (k, 3, 3)
    uv[corners] = np.stack([rel @ s, rel @ t], axis=-1)


def split_on_first_diagonal(uv: np.ndarray, counts: np.ndarray) -> None:
    """Stretch t of each quad whose diagonal 0 -> 2 is not the shorter one in UV (in
    place): MikkTSpace splits a quad along its shorter UV diagonal, every renderer's
    triangulation along 0 -> 2."""
    counts = np.asarray(counts, np.int64)
    starts = face_starts(counts)
    quads = np.flatnonzero(counts == 4)
    if not len(quads):
        return
    base = starts[quads]
    q = uv[base[:, None] + np.arange(4)]                      # (k, 4, 2)
    d02 = np.sum((q[:, 2] - q[:, 0]) ** 2, -1)
    ds = q[:, 3, 0] - q[:, 1, 0]
    dt = np.abs(q[:, 3, 1] - q[:, 1, 1])
    need = d02 / DIAGONAL_MARGIN - ds ** 2                    # what dt^2 k^2 must exceed
    k = np.sqrt(np.maximum(need, 0.0)) / np.maximum(dt, 1e-30)
    k = np.clip(np.where(need > dt ** 2, k * 1.01, 1.0), 1.0, MAX_STRETCH)
    uv[base[:, None] + np.arange(4), 1] *= k[:, None]


def _face_boxes(uv: np.ndarray, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) corner of each face's box in ``uv`` ((faces, 2) each; a face of no
    corners gets the origin)."""
    face_of = np.repeat(np.arange(len(counts)), counts)
    lo = np.full((len(counts), 2), np.inf)
    hi = np.full((len(counts), 2), -np.inf)
    np.minimum.at(lo, face_of, uv)
    np.maximum.at(hi, face_of, uv)
    empty = ~np.isfinite(lo[:, 0])
    lo[empty] = hi[empty] = 0.0
    return lo, hi


def pack_islands(uv: np.ndarray, counts: np.ndarray, size: int, padding: int) -> np.ndarray:
    """Scale and place each face's island (rows of ``uv``, grouped by ``counts``) into
    [0, 1]^2, in shelves, ``2 * padding + 1`` texels apart at a ``size`` map and as large
    as fits; returns the packed (face_vertices, 2) float32 layout."""
    counts = np.asarray(counts, np.int64)
    face_of = np.repeat(np.arange(len(counts)), counts)
    lo, hi = _face_boxes(uv, counts)
    extent = hi - lo
    gap = (2.0 * padding + 1.0) / size                        # between islands, in UV
    order = np.argsort(-extent[:, 1], kind="stable")          # tallest first

    def shelves(scale: float):
        """Lower-left corner of each island, or None when they do not fit."""
        corner = np.zeros((len(counts), 2))
        x = y = gap / 2
        row_height = 0.0
        for face in order:
            w, h = extent[face] * scale
            if x + w + gap / 2 > 1.0 and x > gap / 2 + 1e-12:
                x, y = gap / 2, y + row_height + gap
                row_height = 0.0
            corner[face] = (x, y)
            x += w + gap
            row_height = max(row_height, h)
        return corner if y + row_height + gap / 2 <= 1.0 and x - gap / 2 <= 1.0 else None

    # the largest scale that fits, by bisection from the area bound
    area = float(np.sum((extent[:, 0] + 1e-12) * (extent[:, 1] + 1e-12)))
    high = 1.0 / np.sqrt(max(area, 1e-30))
    low = 0.0
    for _ in range(40):
        middle = 0.5 * (low + high)
        if shelves(middle) is not None:
            low = middle
        else:
            high = middle
    corner = shelves(low)
    if corner is None or low <= 0.0:
        raise ValueError(f"{len(counts)} islands do not fit a {size}-texel map with "
                         f"{padding} texels of padding")
    return ((uv - lo[face_of]) * low + corner[face_of]).astype(np.float32)


def island_layout(points, triangles, triangle_face, corner_face_vertex,
                  counts: np.ndarray, size: int, padding: int) -> tuple[np.ndarray, int, float]:
    """(the islands layout of a mesh, one texture coordinate per face corner (faceVarying,
    (len(faceVertexIndices), 2) float32), the padding it keeps between islands, the
    median island's longer side in texels) from its rest ``points``, its triangulation and
    its ``counts`` (faceVertexCounts). The padding is ``padding``, halved while the
    gutters would take more than a quarter of a typical island's side (a dense mesh on
    a small map); ValueError where the islands would be under SMALLEST_ISLAND texels."""
    counts = np.asarray(counts, np.int64)
    uv = unfold_faces(points, triangles, triangle_face, corner_face_vertex, int(counts.sum()))
    split_on_first_diagonal(uv, counts)
    kept = int(padding)
    while True:
        try:
            packed = pack_islands(uv, counts, size, kept)
            typical = _typical_island(packed, counts, size)
        except ValueError:
            packed, typical = None, 0.0
        if packed is not None and typical >= 4 * (2 * kept + 1):
            return packed, kept, typical
        if kept == 0:
            if packed is None or typical < SMALLEST_ISLAND:
                raise ValueError(f"{len(counts)} faces on a {size}-texel map leave islands "
                                 f"of {typical:.1f} texels, too small to hold wrinkles")
            return packed, kept, typical
        kept //= 2


def _typical_island(uv: np.ndarray, counts: np.ndarray, size: int) -> float:
    """The median longer side of the faces' islands, in texels."""
    lo, hi = _face_boxes(uv, counts)
    return float(np.median((hi - lo).max(axis=1)) * size) if len(counts) else 0.0
