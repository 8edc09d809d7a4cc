"""Small synthetic stages: the one set of builders that the tests, the sample-stage
generator (sample_stages/generate.py) and the benchmarks share.

- :func:`grid_faces`: quad faces of a rows x cols point grid (optionally closed around);
- :func:`grid_sheet`: a flat sheet of quads;
- :func:`point_cache_stage`: an in-memory point-cached mesh with ``primvars:rest``;
- :func:`sleeve_stage`: an in-memory skinned sleeve that bends at the elbow, any size.
"""
from __future__ import annotations

import math

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdSkel, Vt

from ..usd import schema


def grid_faces(rows: int, cols: int, wrap_cols: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(faceVertexCounts, faceVertexIndices) of the quads of a rows x cols grid of points
    (point r * cols + c); ``wrap_cols`` closes each row into a ring (a tube)."""
    r, c = np.meshgrid(np.arange(rows - 1), np.arange(cols if wrap_cols else cols - 1),
                       indexing="ij")
    a = (r * cols + c).ravel()
    b = (r * cols + (c + 1) % cols).ravel()
    quads = np.stack([a, b, b + cols, a + cols], 1).astype(np.int32)
    return np.full(len(quads), 4, np.int32), quads.ravel()


def grid_sheet(nx: int = 21, ny: int = 21, size: float = 2.0, centered: bool = True):
    """A flat sheet in the XY plane, ``size`` wide: points (n, 3) float32,
    faceVertexCounts, faceVertexIndices. Centred on the origin, or from (0, 0)."""
    low = -size / 2 if centered else 0.0
    xs = np.linspace(low, low + size, nx)
    ys = np.linspace(low, low + size, ny)
    gx, gy = np.meshgrid(xs, ys)
    points = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], 1).astype(np.float32)
    counts, indices = grid_faces(ny, nx)
    return points, counts, indices


def point_cache_stage(rest, posed_by_frame: dict, counts, indices, q=None, width=None,
                      amplitude_scale=None, relax_iterations=None, apply_api=True,
                      path="/Sheet", slack=0.0, crest_damping=0.0,
                      irregularity=0.0) -> Usd.Stage:
    """A stage with one mesh: ``primvars:rest`` = rest, ``points`` time-sampled.

    These are the analytic cases: ``slack``, ``crest_damping`` and ``irregularity`` are
    authored as 0 (the paper's amplitude law, frames that follow the strain at once and
    regular waves, which the analytic bars assume) unless given; None leaves the attribute
    unauthored (its fallback applies)."""
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
    analytic = ((schema.SLACK, slack), (schema.CREST_DAMPING, crest_damping),
                (schema.IRREGULARITY, irregularity))
    for name, value in analytic if apply_api else ():
        if value is not None:
            prim.CreateAttribute(name, Sdf.ValueTypeNames.Float).Set(float(value))
    return stage


def sleeve_stage(vertices: int) -> Usd.Stage:
    """An in-memory skinned sleeve of about ``vertices`` points that bends at its middle.

    LBS with two joints, WrinkleAPI applied, a camera that frames it: the shape of the
    shirt sample at any size.
    """
    around = max(8, int(round(math.sqrt(vertices / 3.0))))
    along = max(2, int(round(vertices / around)))
    length, radius = 3.0, 0.4
    theta = np.arange(around) * 2 * np.pi / around
    xs = np.linspace(0, length, along)
    gx, gt = np.meshgrid(xs, theta, indexing="ij")
    points = np.stack([gx.ravel(), radius * np.cos(gt).ravel(), radius * np.sin(gt).ravel()],
                      1).astype(np.float32)
    counts, indices = grid_faces(along, around, wrap_cols=True)
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(24)
    UsdSkel.Root.Define(stage, "/Arm")
    mesh = UsdGeom.Mesh.Define(stage, "/Arm/Sleeve")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    mesh.GetPrim().ApplyAPI(schema.API_NAME)
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "wrinkle:width", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.constant).Set(
        Vt.FloatArray([0.25]))
    skel = UsdSkel.Skeleton.Define(stage, "/Arm/Skel")
    skel.CreateJointsAttr(["shoulder", "shoulder/elbow"])
    bind = [Gf.Matrix4d(1), Gf.Matrix4d(1).SetTranslate(Gf.Vec3d(1.5, 0, 0))]
    skel.CreateBindTransformsAttr(Vt.Matrix4dArray(bind))
    skel.CreateRestTransformsAttr(Vt.Matrix4dArray([bind[0], bind[1]]))
    anim = UsdSkel.Animation.Define(stage, "/Arm/Skel/Anim")
    anim.CreateJointsAttr(["shoulder", "shoulder/elbow"])
    anim.CreateTranslationsAttr().Set(Vt.Vec3fArray([Gf.Vec3f(0), Gf.Vec3f(1.5, 0, 0)]))
    anim.CreateScalesAttr().Set(Vt.Vec3hArray([Gf.Vec3h(1, 1, 1)] * 2))
    rotations = anim.CreateRotationsAttr()
    for frame in range(1, 25):
        angle = 100.0 * (frame - 1) / 23
        rotations.Set(Vt.QuatfArray([Gf.Quatf(1, 0, 0, 0), Gf.Quatf(
            Gf.Rotation(Gf.Vec3d(0, 0, 1), angle).GetQuat())]), frame)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets(
        [anim.GetPath()])
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([skel.GetPath()])
    w = np.clip((points[:, 0] - 1.2) / 0.6, 0, 1)
    binding.CreateJointIndicesPrimvar(False, 2).Set(
        Vt.IntArray.FromNumpy(np.tile([0, 1], len(points)).astype(np.int32)))
    binding.CreateJointWeightsPrimvar(False, 2).Set(
        Vt.FloatArray.FromNumpy(np.stack([1 - w, w], 1).ravel().astype(np.float32)))
    binding.CreateGeomBindTransformAttr(Gf.Matrix4d(1))
    cam = UsdGeom.Camera.Define(stage, "/main_cam")
    cam.CreateHorizontalApertureAttr(36.0)
    cam.CreateVerticalApertureAttr(36.0)
    cam.CreateFocalLengthAttr(30.0)
    look = Gf.Matrix4d().SetLookAt(Gf.Vec3d(1.6, 1.2, 4.5), Gf.Vec3d(1.4, 0.6, 0),
                                   Gf.Vec3d(0, 1, 0))
    cam.AddTransformOp().Set(look.GetInverse())
    return stage


def usdskel_queries(stage: Usd.Stage, path: str):
    """UsdSkel's own (SkelQuery, SkinningQuery) for the mesh at ``path``, from a fresh
    UsdSkel.Cache over its SkelRoot: the oracle that the tests and the bench compare the
    skin pass with, built without usdwrinkle's scene code. (None, None) if UsdSkel does
    not skin it."""
    prim = stage.GetPrimAtPath(path)
    root = UsdSkel.Root.Find(prim)
    if not root:
        return None, None
    cache = UsdSkel.Cache()
    cache.Populate(root, Usd.PrimDefaultPredicate)
    for binding in cache.ComputeSkelBindings(root, Usd.PrimDefaultPredicate):
        for query in binding.GetSkinningTargets():
            if query.GetPrim() == prim:
                return cache.GetSkelQuery(binding.GetSkeleton()), query
    return None, None
