"""Walks over a mesh's polygons (faceVertexCounts, faceVertexIndices) that both the scene
(scene/normals.py: the normals Storm makes) and the bake (maps/tangents.py: the normals
Blender makes) need. Numpy only; neutral: no Usd, no GL."""
from __future__ import annotations

import numpy as np


def face_starts(counts) -> np.ndarray:
    """(f,) int64: where each face's corners start in faceVertexIndices."""
    counts = np.asarray(counts, np.int64)
    return np.cumsum(counts) - counts


def face_corners(counts: np.ndarray, indices: np.ndarray, keep: np.ndarray,
                 left_handed: bool = False):
    """(face of each kept corner, point, previous point, next point) over every corner
    of the faces ``keep`` selects (a mask over ``counts``), in the right-handed winding
    Storm converts meshes to (``left_handed``: the authored winding turned)."""
    counts = np.asarray(counts, np.int64)
    starts = face_starts(counts)
    faces = np.nonzero(keep)[0]
    k = counts[faces]
    face_of = np.repeat(faces, k)
    local = np.arange(int(k.sum())) - np.repeat(np.cumsum(k) - k, k)
    base = np.repeat(starts[faces], k)
    size = np.repeat(k, k)
    point = indices[base + local]
    prev = indices[base + (local - 1) % size]
    nxt = indices[base + (local + 1) % size]
    if left_handed:
        prev, nxt = nxt, prev
    return face_of, point, prev, nxt
