"""Mesh topology: triangulation (concave n-gons, holes) and adjacency in CSR form.

All arrays are numpy; only faces that are not convex are visited one by one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import UsdWrinkleError


@dataclass(frozen=True)
class Topology:
    """Triangulated topology of one mesh.

    Attributes
    ----------
    num_points : int
    triangles : (m, 3) int32
        Point indices of each triangle, wound as the source face.
    triangle_face : (m,) int32
        The source face of each triangle.
    corner_face_vertex : (m, 3) int32
        For each triangle corner, its position in ``faceVertexIndices``
        (the index of a faceVarying value).
    neighbor_offsets, neighbor_indices : (n+1,) and (e,) int32
        The 1-ring of each point (CSR): ``neighbor_indices[offsets[i]:offsets[i+1]]``.
    triangle_offsets, triangle_indices : (n+1,) and (3m,) int32
        Triangles incident to each point (CSR).
    """

    num_points: int
    triangles: np.ndarray
    triangle_face: np.ndarray
    corner_face_vertex: np.ndarray
    neighbor_offsets: np.ndarray
    neighbor_indices: np.ndarray
    triangle_offsets: np.ndarray
    triangle_indices: np.ndarray

    @property
    def edges(self) -> np.ndarray:
        """(e/2, 2) int32 unique undirected edges (i < j)."""
        src = np.repeat(np.arange(self.num_points, dtype=np.int32),
                        np.diff(self.neighbor_offsets))
        keep = src < self.neighbor_indices
        return np.stack([src[keep], self.neighbor_indices[keep]], axis=1)


def validate_faces(counts: np.ndarray, indices: np.ndarray, num_points: int,
                   prim_path: str | None = None) -> None:
    """Refuse face data that cannot describe a mesh."""
    if counts.size and counts.min() < 0:
        raise UsdWrinkleError("negative face vertex count", prim_path, "faceVertexCounts")
    if int(counts.sum()) != indices.size:
        raise UsdWrinkleError(
            f"faceVertexCounts sum to {int(counts.sum())} but there are {indices.size} "
            "faceVertexIndices", prim_path, "faceVertexCounts")
    if indices.size and (indices.min() < 0 or indices.max() >= num_points):
        raise UsdWrinkleError(
            f"faceVertexIndices out of range [0, {num_points})", prim_path, "faceVertexIndices")


def _newell_normal(poly: np.ndarray) -> np.ndarray:
    nxt = np.roll(poly, -1, axis=0)
    return np.array([
        np.sum((poly[:, 1] - nxt[:, 1]) * (poly[:, 2] + nxt[:, 2])),
        np.sum((poly[:, 2] - nxt[:, 2]) * (poly[:, 0] + nxt[:, 0])),
        np.sum((poly[:, 0] - nxt[:, 0]) * (poly[:, 1] + nxt[:, 1])),
    ])


def ear_clip(poly: np.ndarray) -> list[tuple[int, int, int]]:
    """Triangulate one simple polygon (possibly concave) by ear clipping.

    Parameters
    ----------
    poly : (k, 3) float
        The polygon's points in order.

    Returns
    -------
    list of (a, b, c) local corner indices, k - 2 of them. A polygon with no
    ear (self-intersecting or degenerate) falls back to a fan.
    """
    k = len(poly)
    normal = _newell_normal(poly.astype(np.float64))
    length = np.linalg.norm(normal)
    if length < 1e-30:
        return [(0, i, i + 1) for i in range(1, k - 1)]
    normal /= length
    axis_u = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    axis_u /= np.linalg.norm(axis_u)
    axis_v = np.cross(normal, axis_u)
    flat = np.stack([poly @ axis_u, poly @ axis_v], axis=1)

    def cross2(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    remaining = list(range(k))
    out: list[tuple[int, int, int]] = []
    guard = 0
    while len(remaining) > 3 and guard < k * k:
        guard += 1
        found = False
        m = len(remaining)
        for idx in range(m):
            a, b, c = remaining[idx - 1], remaining[idx], remaining[(idx + 1) % m]
            if cross2(flat[a], flat[b], flat[c]) <= 0:  # reflex or flat corner
                continue
            inside = False
            for other in remaining:
                if other in (a, b, c):
                    continue
                p = flat[other]
                if (cross2(flat[a], flat[b], p) >= 0 and cross2(flat[b], flat[c], p) >= 0
                        and cross2(flat[c], flat[a], p) >= 0):
                    inside = True
                    break
            if not inside:
                out.append((a, b, c))
                remaining.pop(idx)
                found = True
                break
        if not found:
            break
    if len(remaining) > 3:  # no ear left: degenerate polygon, fan the rest
        out.extend((remaining[0], remaining[i], remaining[i + 1])
                   for i in range(1, len(remaining) - 1))
    elif len(remaining) == 3:
        out.append(tuple(remaining))
    return out


def triangulate(counts: np.ndarray, indices: np.ndarray, points: np.ndarray,
                hole_indices: np.ndarray | None = None):
    """Triangulate faces; returns (triangles, triangle_face, corner_face_vertex).

    Faces with fewer than 3 vertices and faces in ``hole_indices`` produce no
    triangles. Convex faces are fanned in bulk; concave ones are ear-clipped.
    """
    counts = np.asarray(counts, dtype=np.int64)
    indices = np.asarray(indices, dtype=np.int64)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]) if counts.size else np.zeros(0, np.int64)
    keep = counts >= 3
    if hole_indices is not None and len(hole_indices):
        holes = np.asarray(hole_indices, dtype=np.int64)
        holes = holes[(holes >= 0) & (holes < counts.size)]
        keep[holes] = False
    faces = np.nonzero(keep)[0]
    tri_per_face = counts[faces] - 2
    face_of_tri = np.repeat(faces, tri_per_face)
    local = np.arange(tri_per_face.sum()) - np.repeat(np.cumsum(tri_per_face) - tri_per_face,
                                                       tri_per_face)
    base = starts[face_of_tri]
    corner = np.stack([base, base + local + 1, base + local + 2], axis=1)

    # Concave faces: a fan is wrong there. A face is convex when every corner turns
    # the same way about its Newell normal.
    big = faces[counts[faces] > 3]
    concave = []
    pts = np.asarray(points, dtype=np.float64)
    for face in big:  # loops only over n-gons with n > 3, vectorised per face
        ids = indices[starts[face]:starts[face] + counts[face]]
        poly = pts[ids]
        normal = _newell_normal(poly)
        prev = poly - np.roll(poly, 1, axis=0)
        nxt = np.roll(poly, -1, axis=0) - poly
        turns = np.cross(prev, nxt) @ normal
        if np.any(turns < -1e-12 * max(np.abs(turns).max(), 1e-30)):
            concave.append(face)
    if concave:
        # ear clipping also gives n - 2 triangles: overwrite the fan rows of those faces
        tri_start = np.concatenate([[0], np.cumsum(tri_per_face)])
        for face in concave:
            row = tri_start[np.searchsorted(faces, face)]
            ids = indices[starts[face]:starts[face] + counts[face]]
            corner[row:row + counts[face] - 2] = np.array(ear_clip(pts[ids]), np.int64) \
                + starts[face]
    triangles = indices[corner] if corner.size else np.zeros((0, 3), np.int64)
    return (triangles.astype(np.int32).reshape(-1, 3), face_of_tri.astype(np.int32),
            corner.astype(np.int32).reshape(-1, 3))


def _csr(src: np.ndarray, dst: np.ndarray, n: int):
    order = np.lexsort((dst, src))
    src, dst = src[order], dst[order]
    offsets = np.zeros(n + 1, dtype=np.int32)
    np.cumsum(np.bincount(src, minlength=n), out=offsets[1:])
    return offsets, dst.astype(np.int32)


def build_topology(counts, indices, points, hole_indices=None,
                   prim_path: str | None = None) -> Topology:
    """Validate, triangulate and build the adjacency of a mesh."""
    counts = np.asarray(counts, dtype=np.int32)
    indices = np.asarray(indices, dtype=np.int32)
    n = len(points)
    validate_faces(counts, indices, n, prim_path)
    triangles, tri_face, corner = triangulate(counts, indices, points, hole_indices)
    m = len(triangles)
    # 1-ring from triangle edges, both directions, unique
    a = triangles.reshape(-1)
    b = triangles[:, [1, 2, 0]].reshape(-1)
    src = np.concatenate([a, b]).astype(np.int64)
    dst = np.concatenate([b, a]).astype(np.int64)
    ok = src != dst
    pairs = np.unique(src[ok] * n + dst[ok]) if ok.any() else np.zeros(0, np.int64)
    nb_off, nb_idx = _csr(pairs // max(n, 1), pairs % max(n, 1), n)
    tri_src = triangles.reshape(-1).astype(np.int64)
    tri_ids = np.repeat(np.arange(m, dtype=np.int64), 3)
    tr_off, tr_idx = _csr(tri_src, tri_ids, n)
    return Topology(n, triangles, tri_face, corner, nb_off, nb_idx, tr_off, tr_idx)


def vertex_normals(points: np.ndarray, topology: Topology) -> np.ndarray:
    """Area-weighted vertex normals, (n, 3) float32; zero-area rings give (0, 0, 0)."""
    pts = np.asarray(points, dtype=np.float64)
    tri = topology.triangles
    normals = np.zeros((topology.num_points, 3))
    if len(tri):
        face = np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]])
        for c in range(3):
            np.add.at(normals, tri[:, c], face)
    length = np.linalg.norm(normals, axis=1, keepdims=True)
    return np.where(length > 1e-30, normals / np.maximum(length, 1e-30), 0.0).astype(np.float32)


def mean_edge_length(points: np.ndarray, topology: Topology) -> float:
    """Mean length of the unique edges; 0 for a mesh without edges."""
    edges = topology.edges
    if not len(edges):
        return 0.0
    pts = np.asarray(points, dtype=np.float64)
    return float(np.linalg.norm(pts[edges[:, 1]] - pts[edges[:, 0]], axis=1).mean())
