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
               corner_uv: np.ndarray, groups: tuple[np.ndarray, np.ndarray] | None = None
               ) -> np.ndarray:
    """(3t, 4) float32: per triangle corner ([3t + c]) the unit MikkTSpace tangent (xyz)
    and its bitangent sign (w: +1 or -1).

    points : (n, 3) positions; triangles : (t, 3) point indices; corner_normals : (3t, 3)
    the unit normal each corner is shaded with; corner_uv : (3t, 2); groups : from
    :func:`corner_groups` (when not given: one normal per point, the corners grouped by
    point and texture coordinate). A corner whose group has no usable
    triangle (degenerate UVs or positions) gets a zero tangent: the caller falls back.
    """
    triangles = np.asarray(triangles, np.int64).reshape(-1, 3)
    count = len(triangles)
    if groups is None:
        groups = corner_groups(triangles, triangles.reshape(-1), corner_uv)
    group, orient = groups
    p = np.asarray(points, np.float64)[triangles]                      # (t, 3, 3)
    uv = np.asarray(corner_uv, np.float64).reshape(-1, 3, 2)
    n = np.asarray(corner_normals, np.float64).reshape(-1, 3, 3)
    t21 = uv[:, 1] - uv[:, 0]
    t31 = uv[:, 2] - uv[:, 0]
    d1 = p[:, 1] - p[:, 0]
    d2 = p[:, 2] - p[:, 0]
    area = t21[:, 0] * t31[:, 1] - t21[:, 1] * t31[:, 0]
    # vOs (eq. 18): dP/ds times the UV area; its sign flipped back where the area is
    # negative, so that it points along +s on mirrored islands too
    os_ = t31[:, 1, None] * d1 - t21[:, 1, None] * d2
    os_ = _unit(os_) * np.where(orient, 1.0, -1.0)[:, None]
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
    np.add.at(sums, group, contribution)
    result = np.empty((3 * count, 4), np.float32)
    result[:, :3] = _unit(sums[group])
    result[:, 3] = np.repeat(np.where(orient, 1.0, -1.0), 3)
    return result
