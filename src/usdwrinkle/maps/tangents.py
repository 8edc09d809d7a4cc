"""MikkTSpace tangents per triangle corner, vectorised in numpy (no Usd, no GL).

MikkTSpace (Morten Mikkelsen, 2008; the reference ``mikktspace.c`` that Blender, Unreal,
Substance and glTF viewers build on) gives each triangle corner a unit tangent and a
sign. Per triangle it takes dP/ds (``vOs`` in mikktspace.c, eq. 18), with the sign of the
triangle's UV area; per corner it projects that onto the corner's normal, and the tangent
of a corner is the angle-weighted sum over every triangle of its *group*, normalised. A
group is the corners that share a vertex, a normal and a texture coordinate and whose
triangles have the same UV orientation (a mirrored island is its own group). The
bitangent a renderer builds is ``sign * cross(N, T)``, with N and T interpolated and not
renormalised (Cycles' normal-map node; mikktspace.h's recommendation).

Two simplifications against mikktspace.c, both documented in docs/method.md: corners are
grouped by vertex index (the reference welds equal positions), and a group is not split
where its fan crosses an edge whose far ends differ (a UV seam that ends at the vertex).
tests/test_realclients.py holds this module against Blender's ``Mesh.calc_tangents``.
"""
from __future__ import annotations

import numpy as np

from ..method.polygons import face_corners


def corner_groups(triangles: np.ndarray, normal_entries: np.ndarray,
                  corner_uv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(group of each corner ([3t + c]), UV orientation of each triangle: True where its
    UV area is positive). The layout does not change over a shot: made once per mesh."""
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    uv = np.asarray(corner_uv, np.float32).reshape(-1, 3, 2)
    orient = _uv_area(uv) > 0.0
    keys = np.empty((3 * len(triangles), 5), np.int64)
    keys[:, 0] = triangles.reshape(-1)
    keys[:, 1] = np.asarray(normal_entries, np.int64).reshape(-1)
    keys[:, 2:4] = uv.reshape(-1, 2).view(np.int32)  # exact texture-coordinate values
    keys[:, 4] = np.repeat(orient, 3)
    _, group = np.unique(keys, axis=0, return_inverse=True)
    return group.reshape(-1).astype(np.int64), orient


def _uv_area(uv: np.ndarray) -> np.ndarray:
    """Twice the signed UV area of each triangle ((t, 3, 2) texture coordinates)."""
    t21 = uv[:, 1] - uv[:, 0]
    t31 = uv[:, 2] - uv[:, 0]
    return t21[:, 0] * t31[:, 1] - t21[:, 1] * t31[:, 0]


def _unit(vectors: np.ndarray) -> np.ndarray:
    length = np.linalg.norm(vectors, axis=-1, keepdims=True)
    return np.divide(vectors, length, out=np.zeros_like(vectors), where=length > 1e-20)


def mikktspace(points: np.ndarray, triangles: np.ndarray, corner_normals: np.ndarray,
               corner_uv: np.ndarray, groups: tuple[np.ndarray, np.ndarray] | None = None,
               mikk_ids: np.ndarray | None = None) -> np.ndarray:
    """(3t, 4) float32: per triangle corner ([3t + c]) the unit MikkTSpace tangent (xyz)
    and its bitangent sign (w: +1 or -1).

    points : (n, 3) positions; triangles : (t, 3) point indices; corner_normals : (3t, 3)
    the unit normal each corner is shaded with; corner_uv : (3t, 2); groups : from
    :func:`corner_groups` (when not given: one normal per point, the corners grouped by
    point and texture coordinate); mikk_ids : the triangles MikkTSpace sums over, as
    corner ids ([3t + c]; :func:`mikktspace_triangles`: a quad split along its other
    diagonal), None: ``triangles`` themselves. A corner whose group has no usable
    triangle (degenerate UVs or positions) gets a zero tangent: the caller falls back.
    """
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    count = len(triangles)
    if groups is None:
        groups = corner_groups(triangles, triangles.reshape(-1), corner_uv)
    group, orient = groups
    ids = np.arange(3 * count).reshape(-1, 3) if mikk_ids is None else \
        np.asarray(mikk_ids, np.int64).reshape(-1, 3)
    p = np.asarray(points, np.float64)[triangles.reshape(-1)[ids]]     # (t, 3, 3)
    uv = np.asarray(corner_uv, np.float64).reshape(-1, 2)[ids]
    n = np.asarray(corner_normals, np.float64).reshape(-1, 3)[ids]
    t21 = uv[:, 1] - uv[:, 0]
    t31 = uv[:, 2] - uv[:, 0]
    d1 = p[:, 1] - p[:, 0]
    d2 = p[:, 2] - p[:, 0]
    area = t21[:, 0] * t31[:, 1] - t21[:, 1] * t31[:, 0]
    # vOs (eq. 18): dP/ds times the UV area; its sign flipped back where the area is
    # negative, so that it points along +s on mirrored islands too
    os_ = t31[:, 1, None] * d1 - t21[:, 1, None] * d2
    os_ = _unit(os_) * np.where(area > 0.0, 1.0, -1.0)[:, None]
    os_[np.abs(area) <= 1e-20] = 0.0
    # per corner: vOs projected onto the corner's normal, weighted by the corner's angle
    # between its two edges (both projected onto the normal too)
    tangent = _unit(os_[:, None, :] - np.sum(n * os_[:, None, :], -1, keepdims=True) * n)
    before = p[:, [2, 0, 1]] - p
    after = p[:, [1, 2, 0]] - p
    before = _unit(before - np.sum(n * before, -1, keepdims=True) * n)
    after = _unit(after - np.sum(n * after, -1, keepdims=True) * n)
    angle = np.arccos(np.clip(np.sum(before * after, -1), -1.0, 1.0))
    contribution = (angle[..., None] * tangent).reshape(-1, 3)
    sums = np.zeros((int(group.max()) + 1 if len(group) else 0, 3))
    np.add.at(sums, group[ids.reshape(-1)], contribution)
    result = np.empty((3 * count, 4), np.float32)
    result[:, :3] = _unit(sums[group])
    result[:, 3] = np.repeat(np.where(orient, 1.0, -1.0), 3)
    return result


def blender_vertex_normals(points: np.ndarray, counts: np.ndarray, indices: np.ndarray,
                           faces: np.ndarray | None = None) -> np.ndarray:
    """(n, 3) float64 unit vertex normals as Blender makes them for a smooth mesh without
    custom normals: per point, the sum over its face corners of the corner's angle times
    the face's unit normal (Newell's, over the whole polygon), normalised. Blender's USD
    importer gives a subdivision mesh these (it authors no normals); Storm and usdwrinkle
    sum corner cross products instead (scene/normals.py). ``faces``: the faces that count
    (a mask; default every face of 3 corners or more: holes are left out by the caller)."""
    points = np.asarray(points, np.float64)
    counts = np.asarray(counts, np.int64)
    keep = counts >= 3
    if faces is not None:
        keep &= np.asarray(faces, bool)
    face_of, point, prev, nxt = face_corners(counts, np.asarray(indices, np.int64), keep)
    here = points[point]
    face_normal = np.zeros((len(counts), 3))
    np.add.at(face_normal, face_of, np.cross(here, points[nxt]))     # Newell
    face_normal = _unit(face_normal)
    angle = np.arccos(np.clip(np.sum(_unit(points[prev] - here) * _unit(points[nxt] - here),
                                     -1), -1.0, 1.0))
    normals = np.zeros_like(points)
    np.add.at(normals, point, angle[:, None] * face_normal[face_of])
    return _unit(normals)


def mikktspace_triangles(points: np.ndarray, triangles: np.ndarray, triangle_face: np.ndarray,
                         corner_uv: np.ndarray) -> np.ndarray:
    """(t, 3) corner ids ([3t + c] of ``triangles``) of the triangles MikkTSpace sums
    over. A quad, which usdwrinkle (and every renderer) splits along 0-2, is split by
    mikktspace.c along its shorter UV diagonal, and where the two are equal along the
    shorter diagonal between the (posed) ``points``; where that is 1-3, its two
    triangles here are (0, 1, 3) and (1, 2, 3) of the quad."""
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    faces = np.asarray(triangle_face, np.int64)
    ids = np.arange(3 * len(triangles)).reshape(-1, 3)
    if len(triangles) < 2:
        return ids
    # quads: exactly two consecutive triangles of a face, a fan (a, b, c), (a, c, d)
    pair = np.flatnonzero((faces[:-1] == faces[1:]) &
                          (triangles[:-1, 0] == triangles[1:, 0]) &
                          (triangles[:-1, 2] == triangles[1:, 1]))
    count = np.bincount(faces, minlength=int(faces.max()) + 1)
    pair = pair[count[faces[pair]] == 2]
    uv = np.asarray(corner_uv, np.float32).reshape(-1, 3, 2)
    t0, t1 = pair, pair + 1
    q = [uv[t0, 0], uv[t0, 1], uv[t0, 2], uv[t1, 2]]          # the quad's corners 0..3
    d02 = np.sum((q[2] - q[0]) ** 2, -1, dtype=np.float32)
    d13 = np.sum((q[3] - q[1]) ** 2, -1, dtype=np.float32)
    p = np.asarray(points, np.float32)
    P = [p[triangles[t0, 0]], p[triangles[t0, 1]], p[triangles[t0, 2]], p[triangles[t1, 2]]]
    p02 = np.sum((P[2] - P[0]) ** 2, -1, dtype=np.float32)
    p13 = np.sum((P[3] - P[1]) ** 2, -1, dtype=np.float32)
    split13 = (d13 < d02) | ((d13 == d02) & (p13 < p02))
    t0, t1 = t0[split13], t1[split13]
    c0, c1, c2, c3 = 3 * t0, 3 * t0 + 1, 3 * t0 + 2, 3 * t1 + 2
    ids[t0] = np.stack([c0, c1, c3], -1)
    ids[t1] = np.stack([c1, c2, c3], -1)
    return ids
