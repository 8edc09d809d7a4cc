"""The coarse shot as a USD stage (a point cache in metres), and reading back the fine mesh
that ``bake --geometry --levels 3`` writes for it."""
from __future__ import annotations

import numpy as np
from pxr import Sdf, Usd, UsdGeom, Vt

from .coarse import coarse_indices, lowpass
from .shots import Shot

MESH = "/Shot/Cloth"


def levels(shot: Shot) -> int:
    """The subdivision levels whose fine vertices are the simulation's grid points: the
    coarse mesh keeps every stride-th grid line, and log2(stride) midpoint levels cut each
    coarse edge as finely."""
    count = int(round(np.log2(shot.stride)))
    assert 2 ** count == shot.stride
    return count


def coarse_triangles(rows: int, cols: int, periodic: bool) -> np.ndarray:
    """Each coarse grid cell as two triangles, the diagonal alternating (a chequer), so that
    no direction is favoured."""
    c = cols if periodic else cols - 1
    out = []
    for r in range(rows - 1):
        for k in range(c):
            a, b = r * cols + k, r * cols + (k + 1) % cols
            d, e = a + cols, b + cols
            if (r + k) % 2 == 0:
                out += [(a, d, e), (a, e, b)]
            else:
                out += [(a, d, b), (b, d, e)]
    return np.array(out, np.int32)


def write_stage(path: str, shot: Shot, fine_points: np.ndarray, *, width: float | None = None,
                amplitude_scale: float | None = None, held: bool = True,
                attributes: dict | None = None) -> None:
    """The coarse shot: frame 0 is the rest pose, frames 1..F the low-passed simulation at
    every stride-th grid line. ``width`` (m) authors primvars:wrinkle:width; ``held``
    marks the pinned vertices with primvars:wrinkle:held."""
    from usdwrinkle import WrinkleAPI  # noqa: F401 (registers the schema)

    index, rows, cols = coarse_indices(shot)
    smooth = lowpass(shot, fine_points)[:, index]
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(len(fine_points))
    stage.SetTimeCodesPerSecond(24)
    stage.SetFramesPerSecond(24)
    root = UsdGeom.Xform.Define(stage, "/Shot")
    stage.SetDefaultPrim(root.GetPrim())
    mesh = UsdGeom.Mesh.Define(stage, MESH)
    triangles = coarse_triangles(rows, cols, shot.periodic)
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([3] * len(triangles)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(triangles.ravel().tolist()))
    mesh.CreateSubdivisionSchemeAttr("none")
    rest = shot.rest[index]
    points = mesh.CreatePointsAttr()
    points.Set(Vt.Vec3fArray.FromNumpy(rest.astype(np.float32)), 0)
    for frame, posed in enumerate(smooth, start=1):
        points.Set(Vt.Vec3fArray.FromNumpy(posed.astype(np.float32)), frame)
    primvars = UsdGeom.PrimvarsAPI(mesh)
    primvars.CreatePrimvar("rest", Sdf.ValueTypeNames.Point3fArray,
                           UsdGeom.Tokens.vertex).Set(
        Vt.Vec3fArray.FromNumpy(rest.astype(np.float32)))
    api = mesh.GetPrim()
    api.ApplyAPI("WrinkleAPI")
    if width is not None:
        primvars.CreatePrimvar("wrinkle:width", Sdf.ValueTypeNames.FloatArray,
                               UsdGeom.Tokens.constant).Set([float(width)])
    if amplitude_scale is not None:
        api.CreateAttribute("wrinkle:amplitudeScale", Sdf.ValueTypeNames.Float).Set(
            float(amplitude_scale))
    if held:
        primvars.CreatePrimvar("wrinkle:held", Sdf.ValueTypeNames.FloatArray,
                               UsdGeom.Tokens.vertex).Set(
            shot.pinned[index].astype(np.float32).tolist())
    for name, (type_name, value) in (attributes or {}).items():
        api.CreateAttribute(name, type_name).Set(value)
    stage.GetRootLayer().Save()


def read_fine(layer_path: str, shot: Shot, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """The fine mesh of a --geometry bake on the simulation's grid: (points, normals), each
    (frames, n, 3) in grid order (frame 1 first), matched through the rest pose that the
    bake's frame 0 holds."""
    stage = Usd.Stage.Open(layer_path)
    fine = UsdGeom.Mesh(stage.GetPrimAtPath(MESH + "_wrinkled"))
    if not fine:
        raise RuntimeError(f"{layer_path} has no {MESH}_wrinkled")
    rest = np.asarray(fine.GetPointsAttr().Get(0), np.float64)
    order = grid_order(shot, rest)
    points = np.stack([np.asarray(fine.GetPointsAttr().Get(f), np.float64)[order]
                       for f in range(1, frames + 1)])
    normals = np.stack([np.asarray(fine.GetNormalsAttr().Get(f), np.float64)[order]
                        for f in range(1, frames + 1)])
    return points, normals


def grid_order(shot: Shot, fine_rest: np.ndarray) -> np.ndarray:
    """For each simulation grid point, the fine vertex at its rest place."""
    h = shot.spacing
    if shot.periodic:
        radius = np.median(np.hypot(shot.rest[:, 0], shot.rest[:, 1]))
        angle = np.arctan2(fine_rest[:, 1], fine_rest[:, 0]) % (2 * np.pi)
        col = np.rint(angle / (2 * np.pi) * shot.cols).astype(int) % shot.cols
        along = fine_rest[:, 2] + shot.material[:, 1].max() / 2
        row = np.rint(along / (shot.material[shot.cols, 1] - shot.material[0, 1])).astype(int)
        del radius
    else:
        col = np.rint((fine_rest[:, 0] - shot.rest[0, 0]) / h).astype(int)
        row = np.rint(-fine_rest[:, 2] / h).astype(int)
    flat = row * shot.cols + col
    if len(flat) != shot.rows * shot.cols or len(np.unique(flat)) != len(flat):
        raise RuntimeError(f"the fine mesh ({len(flat)} points) is not the {shot.name} grid")
    order = np.empty(len(flat), int)
    order[flat] = np.arange(len(flat))
    return order
