"""Build small in-memory stages for tests (point caches with primvars:rest)."""
from __future__ import annotations

import numpy as np
from pxr import Sdf, Usd, UsdGeom, Vt

from usdwrinkle import schema


def point_cache_stage(rest, posed_by_frame: dict, counts, indices, q=None, width=None,
                      amplitude_scale=None, relax_iterations=None, apply_api=True,
                      path="/Sheet") -> Usd.Stage:
    """A stage with one mesh: ``primvars:rest`` = rest, ``points`` time-sampled."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    frames = sorted(posed_by_frame)
    stage.SetStartTimeCode(frames[0])
    stage.SetEndTimeCode(frames[-1])
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.asarray(counts, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(indices, np.int32)))
    for frame, posed in posed_by_frame.items():
        mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(np.asarray(posed, np.float32)), frame)
    primvars = UsdGeom.PrimvarsAPI(mesh)
    primvars.CreatePrimvar("rest", Sdf.ValueTypeNames.Point3fArray,
                           UsdGeom.Tokens.vertex).Set(
        Vt.Vec3fArray.FromNumpy(np.asarray(rest, np.float32)))
    prim = mesh.GetPrim()
    if apply_api:
        prim.ApplyAPI(schema.API_NAME)
    if q is not None:
        primvars.CreatePrimvar("wrinkle:q", Sdf.ValueTypeNames.Vector3fArray,
                               UsdGeom.Tokens.vertex).Set(
            Vt.Vec3fArray.FromNumpy(np.asarray(q, np.float32)))
    if width is not None:
        primvars.CreatePrimvar("wrinkle:width", Sdf.ValueTypeNames.FloatArray,
                               UsdGeom.Tokens.constant).Set(Vt.FloatArray([float(width)]))
    if amplitude_scale is not None:
        prim.CreateAttribute(schema.AMPLITUDE_SCALE, Sdf.ValueTypeNames.Float).Set(
            float(amplitude_scale))
    if relax_iterations is not None:
        prim.CreateAttribute(schema.RELAX_ITERATIONS, Sdf.ValueTypeNames.Int).Set(
            int(relax_iterations))
    return stage


def rotation_matrix(axis, angle) -> np.ndarray:
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    x, y, z = axis
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c + x * x * (1 - c), x * y * (1 - c) - z * s, x * z * (1 - c) + y * s],
                     [y * x * (1 - c) + z * s, c + y * y * (1 - c), y * z * (1 - c) - x * s],
                     [z * x * (1 - c) - y * s, z * y * (1 - c) + x * s, c + z * z * (1 - c)]])
