"""The fine render topology: N levels of midpoint (1-to-4) subdivision of the rest mesh.

trimesh does the subdivision (``trimesh.remesh.subdivide``: shared edges get one
midpoint, so the fine mesh is as watertight as the coarse one) and the barycentric
coordinates (``trimesh.triangles.points_to_barycentric``). Every fine vertex is tied to
one coarse triangle and its barycentric position there: what the GPU evaluates the wave
blend at (geometry.glsl). Every fine face corner has its barycentrics in its own coarse
triangle too, so face-varying data (UVs) is carried across seams exactly.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..process.errors import UsdWrinkleError

#: fine points above which a mesh is refused (``--levels`` lowers the count): what the
#: render of the displaced mesh holds on any GL 4.5 GPU. Its largest table, the topology
#: (render/resources.topology_block: about 14 elements a point on a subdivided mesh, the
#: 1-rings and the incident triangles), must fit TABLE_WIDTH x 16384 = 33.5 M elements
#: (GL 4.5's minimum GL_MAX_TEXTURE_SIZE): 2.4 M points; 4 M baked but did not render
MAX_FINE_POINTS = 2_000_000
#: fine points the automatic level count stays under (a mesh of a few million points a
#: frame makes layers of gigabytes, and renders slowly); --levels may go to MAX_FINE_POINTS
AUTO_FINE_POINTS = 1_000_000
#: samples per wavelength the default level count aims for
MAX_LEVELS = 10


@dataclass(frozen=True)
class FineMesh:
    """A subdivided mesh.

    points : (n, 3) float32 fine rest points.
    faces : (m, 3) int32 fine triangles.
    vertex_triangle : (n,) int32 the coarse triangle of each fine vertex.
    vertex_bary : (n, 3) float32 its barycentric coordinates there.
    face_triangle : (m,) int32 the coarse triangle of each fine face.
    corner_bary : (m, 3, 3) float32 each fine face corner's barycentrics in that triangle.
    levels : int.
    entry_offsets : (n + 1,) int32; entries entry_offsets[v] .. entry_offsets[v + 1] - 1
        are every coarse triangle fine vertex v lies in (one inside a coarse triangle, two
        on a coarse edge, the valence at a coarse vertex), the first being
        vertex_triangle[v]: its normal is averaged over them, as the surface's is.
    entry_triangle : (e,) int32; entry_bary : (e, 3) float32.
    edge_length : float, the mean fine edge length in the rest pose (local space): the
        band limit lets no wave be shorter than two of them (geometry.glsl).
    """

    points: np.ndarray
    faces: np.ndarray
    vertex_triangle: np.ndarray
    vertex_bary: np.ndarray
    face_triangle: np.ndarray
    corner_bary: np.ndarray
    levels: int
    entry_offsets: np.ndarray
    entry_triangle: np.ndarray
    entry_bary: np.ndarray
    edge_length: float = 0.0


def fine_point_count(num_points: int, triangles: np.ndarray, levels: int) -> int:
    """Points after ``levels`` subdivisions, before any is made: every level adds one
    point per edge, and the edges and faces multiply as 1-to-4 splits do."""
    edges = np.sort(np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]],
                                    triangles[:, [2, 0]]]), axis=1)
    count_edges = len(np.unique(edges, axis=0)) if len(edges) else 0
    points, faces = num_points, len(triangles)
    for _ in range(levels):
        points, count_edges, faces = points + count_edges, 2 * count_edges + 3 * faces, \
            4 * faces
    return int(points)


def levels_for(phase_step: float, samples_per_wavelength: float) -> int:
    """The fewest levels for which a fine edge advances a wave's phase by at most
    2 pi / S (S samples per wavelength): ``phase_step`` is the advance |e . k| along a
    coarse edge that must be resolved (geometry/bake.py: its survey)."""
    needed = samples_per_wavelength * phase_step / (2 * math.pi)
    return 0 if needed <= 1 else min(int(math.ceil(math.log2(needed))), MAX_LEVELS)


def check_size(path: str, num_points: int, triangles: np.ndarray, levels: int) -> int:
    count = fine_point_count(num_points, triangles, levels)
    if count > MAX_FINE_POINTS:
        raise UsdWrinkleError(
            f"{levels} subdivision level(s) would make {count:,} fine points, more than "
            f"{MAX_FINE_POINTS:,}; pass fewer `levels` (or a lower `samples_per_wavelength`)",
            path)
    return count


def subdivide(rest: np.ndarray, triangles: np.ndarray, levels: int) -> FineMesh:
    """``levels`` midpoint subdivisions of the rest mesh's triangles."""
    import trimesh

    rest = np.asarray(rest, np.float64)
    faces = np.asarray(triangles, np.int64)
    face_triangle = np.arange(len(faces))
    vertices = rest
    for _ in range(levels):
        vertices, faces, index = trimesh.remesh.subdivide(vertices, faces, return_index=True)
        parent = np.empty(len(faces), np.int64)
        for old, new in index.items():
            parent[new] = old
        face_triangle = face_triangle[parent]
    coarse = rest[np.asarray(triangles, np.int64)[face_triangle]]      # (m, 3, 3)
    corners = vertices[faces]                                            # (m, 3, 3)
    bary = np.empty((len(faces), 3, 3))
    for corner in range(3):
        with np.errstate(all="ignore"):
            bary[:, corner] = trimesh.triangles.points_to_barycentric(coarse, corners[:, corner])
    # a degenerate coarse triangle has no barycentrics: its centre stands in
    bary = np.where(np.isfinite(bary).all(axis=2, keepdims=True), bary, 1.0 / 3.0)
    bary = np.clip(bary, 0.0, 1.0)
    bary /= np.maximum(bary.sum(axis=2, keepdims=True), 1e-30)
    # every (fine vertex, coarse triangle) pair once, in vertex order; a vertex's first
    # entry is its first face's coarse triangle
    flat = faces.ravel()
    corner_triangle = np.repeat(face_triangle, 3)
    order = np.lexsort((np.arange(len(flat)), corner_triangle, flat))
    pairs = np.stack([flat[order], corner_triangle[order]], 1)
    keep = np.ones(len(order), bool)
    keep[1:] = np.any(pairs[1:] != pairs[:-1], axis=1)
    entries = order[keep]
    entry_vertex = flat[entries]
    # the first entry of each vertex: the coarse triangle of its first face
    first_corner = np.full(len(vertices), len(flat), np.int64)
    np.minimum.at(first_corner, flat, np.arange(len(flat)))
    first_entry = corner_triangle[np.minimum(first_corner, len(flat) - 1)][entry_vertex] == \
        corner_triangle[entries]
    entries = entries[np.lexsort((~first_entry, entry_vertex))]
    entry_vertex = flat[entries]
    offsets = np.searchsorted(entry_vertex, np.arange(len(vertices) + 1)).astype(np.int32)
    entry_triangle = corner_triangle[entries]
    entry_bary = bary.reshape(-1, 3)[entries]
    used = np.diff(offsets) > 0
    vertex_triangle = np.zeros(len(vertices), np.int64)
    vertex_bary = np.tile([1.0, 0.0, 0.0], (len(vertices), 1))
    vertex_triangle[used] = entry_triangle[offsets[:-1][used]]
    vertex_bary[used] = entry_bary[offsets[:-1][used]]
    edges = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2)
    return FineMesh(vertices.astype(np.float32), faces.astype(np.int32),
                    vertex_triangle.astype(np.int32), vertex_bary.astype(np.float32),
                    face_triangle.astype(np.int32), bary.astype(np.float32), int(levels),
                    offsets, entry_triangle.astype(np.int32), entry_bary.astype(np.float32),
                    float(edges.mean()) if edges.size else 0.0)
