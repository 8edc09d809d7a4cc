"""Shading normals as UsdGeomMesh specifies them and Storm draws them.

UsdGeomMesh, "A Note About Normals": a subdivision mesh (any subdivisionScheme but
"none"; catmullClark is the fallback) defines its own smooth normals; a polygonal mesh
(subdivisionScheme "none") uses its authored normals (primvars:normals over normals),
and one that authors neither "should be treated and rendered as faceted". Storm computes
both the same way (hd/smoothNormals.cpp, hd/flatNormals.cpp), and so does
usdwrinkle's normals pass (shaders/normals.glsl) from this plan:

- "smooth": per point, the sum over its polygon corners of cross(next - p, prev - p);
- "faceted": per face, the sum over its fan of cross(v[j-1] - v0, v[j] - v0);
- "authored": the authored values, skinned with the points of a UsdSkel mesh, sampled
  per frame when time-sampled.

The wave physics keep their own (area-weighted) normals (crush.glsl); these are what
the surface is shaded with, and what the wave blend bends.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from pxr import UsdGeom

from ..method.polygons import face_corners, face_starts
from ..process.errors import UsdWrinkleError
from ..usd.values import finite_in_float32, flattened, static_flattened, static_value
from .topology import Topology

_log = logging.getLogger(__name__)

SOURCES = ("smooth", "faceted", "authored")


@dataclass(frozen=True)
class NormalPlan:
    """How one mesh's shading normals are made.

    source : "smooth", "faceted" or "authored".
    entries : how many normals the table holds (points, faces, or authored values).
    corner_entry : (m, 3) int32, the entry each triangle corner is shaded with.
    csr : int32, ``entries + 1`` offsets, then per entry its list: (prev, next) point
        pairs (smooth), the face's points (faceted), the point whose skinning moves it
        (authored).
    authored : (entries, 3) float32 local normals at the default time (authored), or None.
    attribute : the authored attribute ("primvars:normals" or "normals"), or None.
    time_varying : authored values sampled per frame (a point cache's normals).
    interpolation : the authored values' interpolation (authored), or None.
    indexed : the authored primvar has indices (a bake of posed normals blocks them).
    """

    source: str
    entries: int
    corner_entry: np.ndarray
    csr: np.ndarray
    authored: np.ndarray | None = None
    attribute: str | None = None
    time_varying: bool = False
    interpolation: str | None = None
    indexed: bool = False


def _csr(keys: np.ndarray, values: np.ndarray, entries: int, width: int) -> np.ndarray:
    """Offsets (entries + 1, in ints) then ``values`` (k, width) grouped by ``keys``."""
    order = np.argsort(keys, kind="stable")
    counts = np.bincount(keys, minlength=entries) * width
    offsets = np.concatenate([[0], np.cumsum(counts)]) + entries + 1
    return np.concatenate([offsets, values[order].reshape(-1)]).astype(np.int32)


def plan_normals(prim, topology: Topology, counts: np.ndarray, indices: np.ndarray,
                 holes: np.ndarray | None, left_handed: bool) -> NormalPlan:
    """The NormalPlan of a Mesh prim (its faces as authored; ``holes``: hole faces)."""
    mesh = UsdGeom.Mesh(prim)
    path = str(prim.GetPath())
    n = topology.num_points
    counts = np.asarray(counts, np.int64)
    indices = np.asarray(indices, np.int64)
    keep = counts >= 3
    if holes is not None and len(holes):
        holes = np.asarray(holes, np.int64)
        keep[holes[(holes >= 0) & (holes < len(counts))]] = False
    scheme = static_value(mesh.GetSubdivisionSchemeAttr()) or UsdGeom.Tokens.catmullClark
    if scheme != UsdGeom.Tokens.none:
        _, point, prev, nxt = face_corners(counts, indices, keep, left_handed)
        return NormalPlan("smooth", n, topology.triangles.astype(np.int32),
                          _csr(point, np.stack([prev, nxt], axis=1), n, 2))
    authored = _authored(prim, mesh, topology, counts, indices, path)
    if authored is not None:
        return authored
    face_of, point, _, _ = face_corners(counts, indices, keep, left_handed)
    return NormalPlan("faceted", len(counts), np.repeat(
        topology.triangle_face[:, None], 3, axis=1).astype(np.int32),
        _csr(face_of, point[:, None], len(counts), 1))


def _authored(prim, mesh, topology: Topology, counts, indices, path: str):
    """The NormalPlan of authored normals (primvars:normals wins over normals), or None
    when a polygonal mesh authors none (or authors them unusably: a warning)."""
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar("normals")
    indexed = False
    if primvar and primvar.HasAuthoredValue():
        attr, interpolation = primvar.GetAttr(), primvar.GetInterpolation()
        values = static_flattened(primvar)
        indexed = bool(primvar.IsIndexed())
    else:
        attr = mesh.GetNormalsAttr()
        if not attr or not attr.HasAuthoredValue():
            return None
        interpolation = mesh.GetNormalsInterpolation()
        values = static_value(attr)
    if values is None:
        return None
    values = np.asarray(values, np.float64).reshape(-1, 3)
    name = attr.GetName()
    if not finite_in_float32(values):
        raise UsdWrinkleError("normals are not finite (NaN or Inf)", path, name)
    n = topology.num_points
    starts = face_starts(counts)
    triangles = topology.triangles
    if interpolation in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying) and len(values) == n:
        entry_point, corner = np.arange(n), triangles
    elif interpolation == UsdGeom.Tokens.faceVarying and len(values) == len(indices):
        entry_point, corner = indices, topology.corner_face_vertex
    elif interpolation == UsdGeom.Tokens.uniform and len(values) == len(counts):
        entry_point = indices[np.minimum(starts, max(len(indices) - 1, 0))] \
            if len(indices) else np.zeros(len(counts), np.int64)
        corner = np.repeat(topology.triangle_face[:, None], 3, axis=1)
    elif interpolation == UsdGeom.Tokens.constant and len(values) == 1:
        entry_point, corner = np.zeros(1, np.int64), np.zeros_like(triangles)
    else:
        _log.warning(f"{name} has {len(values)} values for {interpolation} interpolation; "
                     f"shaded as if none were authored (faceted) ({path})")
        return None
    entries = len(values)
    csr = np.concatenate([np.arange(entries + 1) + entries + 1, entry_point]).astype(np.int32)
    return NormalPlan("authored", entries, np.asarray(corner, np.int32), csr,
                      values.astype(np.float32), name,
                      attr.ValueMightBeTimeVarying(), str(interpolation), indexed)


def sample_normals(prim, plan: NormalPlan, time, frame) -> np.ndarray | None:
    """This frame's authored normals (entries, 3) float32 of a time-sampled plan."""
    if plan.source != "authored" or not plan.time_varying:
        return None
    attr = prim.GetAttribute(plan.attribute)
    if plan.attribute == "primvars:normals":
        values = flattened(UsdGeom.Primvar(attr), time)
    else:
        values = attr.Get(time)
    values = np.asarray(values if values is not None else plan.authored, np.float64)
    values = values.reshape(-1, 3)
    if len(values) != plan.entries:
        raise UsdWrinkleError(f"normals change their count over time ({len(values)} != "
                              f"{plan.entries})", str(prim.GetPath()), plan.attribute, frame)
    if not finite_in_float32(values):
        raise UsdWrinkleError("normals are not finite (NaN or Inf)", str(prim.GetPath()),
                              plan.attribute, frame)
    return values.astype(np.float32)
