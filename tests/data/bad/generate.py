"""Generate the malformed and degenerate stages of tests/data/bad/ and cases.json.

    python tests/data/bad/generate.py

Each stage is small and tests one thing. cases.json gives the expected outcome of
``render`` and ``bake``: an error with a fragment of its one-line message, or
success with finite output (optionally with a warning fragment).
"""
from __future__ import annotations

import json
import os
import sys

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, UsdSkel, Vt

import usdwrinkle  # noqa: F401  registers WrinkleAPI before USD builds its registry
from usdwrinkle.authoring.builders import grid_sheet

HERE = os.path.dirname(os.path.abspath(__file__))
CASES: dict = {}


def grid(nx=5, ny=5, size=1.0):
    points, counts, indices = grid_sheet(nx, ny, size, centered=False)
    return points, counts.tolist(), indices.tolist()


def stage_with_mesh(name, points=None, counts=None, indices=None, wrinkle=True, frames=3,
                    posed=None):
    """A stage with /World/Cloth; ``posed`` (frame -> points) makes it a point cache."""
    path = os.path.join(HERE, f"{name}.usda")
    if os.path.exists(path):
        os.remove(path)
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(frames)
    UsdGeom.Xform.Define(stage, "/World")
    mesh = UsdGeom.Mesh.Define(stage, "/World/Cloth")
    if points is None:
        points, counts, indices = grid()
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.asarray(points, np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray(list(counts)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(list(indices)))
    if posed:
        for frame, value in posed.items():
            mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(np.asarray(value, np.float32)),
                                     frame)
    if wrinkle:
        mesh.GetPrim().ApplyAPI("WrinkleAPI")
    return stage, mesh


def case(name, outcome, fragment=None, warning=None, bake=None, visible=False):
    """``bake``: (outcome, fragment) where bake differs from render (a bake that would
    hold no wrinkle data is an error; a render of the same stage is not). ``visible``:
    the mesh covers pixels in every frame (a mesh must never vanish silently)."""
    CASES[f"{name}.usda"] = {"outcome": outcome, "fragment": fragment, "warning": warning,
                             "bake": list(bake) if bake else None, "visible": visible}


def save(stage):
    stage.GetRootLayer().Save()


def primvar(mesh, name, type_name, value, interpolation=UsdGeom.Tokens.vertex):
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(name, type_name, interpolation).Set(value)


def errors():
    points, counts, indices = grid()
    stage, _ = stage_with_mesh("face_counts_mismatch", points, counts[:-1] + [5], indices)
    save(stage)
    case("face_counts_mismatch", "error", "faceVertexCounts sum to")

    bad = list(indices)
    bad[3] = 999
    stage, _ = stage_with_mesh("index_out_of_range", points, counts, bad)
    save(stage)
    case("index_out_of_range", "error", "faceVertexIndices out of range")

    nan_points = points.copy()
    nan_points[4] = np.nan
    stage, _ = stage_with_mesh("nan_rest_points", nan_points, counts, indices)
    save(stage)
    case("nan_rest_points", "error", "points are not finite")

    later = points.copy()
    later[7, 1] = np.nan
    stage, _ = stage_with_mesh("nan_points_at_frame", posed={1: points, 2: points, 3: later})
    save(stage)
    case("nan_points_at_frame", "error", "not finite (NaN or Inf) (/World/Cloth.points at frame 3)")

    inf = points * 0.9
    inf[2, 0] = np.inf
    stage, _ = stage_with_mesh("inf_points_at_frame", posed={1: points, 2: inf})
    save(stage)
    case("inf_points_at_frame", "error", "at frame 2")

    stage, _ = stage_with_mesh("point_count_changes", posed={1: points, 2: points[:-2]})
    save(stage)
    case("point_count_changes", "error",
         "point count changes over time (23 != 25) (/World/Cloth.points at frame 2)")

    stage, mesh = stage_with_mesh("q_wrong_length")
    primvar(mesh, "wrinkle:q", Sdf.ValueTypeNames.Vector3fArray, Vt.Vec3fArray(3))
    save(stage)
    case("q_wrong_length", "error", "q has 3 values for 25 points")

    stage, mesh = stage_with_mesh("q_not_finite")
    q = np.zeros((25, 3), np.float32)
    q[5] = np.nan
    primvar(mesh, "wrinkle:q", Sdf.ValueTypeNames.Vector3fArray, Vt.Vec3fArray.FromNumpy(q))
    save(stage)
    case("q_not_finite", "error", "q is not finite (/World/Cloth.primvars:wrinkle:q)")

    stage, mesh = stage_with_mesh("q_too_long")
    primvar(mesh, "wrinkle:q", Sdf.ValueTypeNames.Vector3fArray,
            Vt.Vec3fArray.FromNumpy(np.tile([1.2, 0.0, 0.0], (25, 1)).astype(np.float32)))
    save(stage)
    case("q_too_long", "error", "|q| > 1")

    stage, mesh = stage_with_mesh("q_face_varying")
    primvar(mesh, "wrinkle:q", Sdf.ValueTypeNames.Vector3fArray, Vt.Vec3fArray(64),
            UsdGeom.Tokens.faceVarying)
    save(stage)
    case("q_face_varying", "error", "vertex interpolation")

    for name, value, fragment in (("width_zero", [0.0], "width must be finite and > 0"),
                                  ("width_negative", [-0.5], "width must be finite and > 0"),
                                  ("width_nan", [float("nan")], "width must be finite and > 0"),
                                  ("width_wrong_length", [0.1] * 7, "one value per point")):
        stage, mesh = stage_with_mesh(name)
        interpolation = UsdGeom.Tokens.constant if len(value) == 1 else UsdGeom.Tokens.vertex
        primvar(mesh, "wrinkle:width", Sdf.ValueTypeNames.FloatArray, Vt.FloatArray(value),
                interpolation)
        save(stage)
        case(name, "error", fragment)

    for name, values in (("profile_one_sample", [1.0]), ("profile_not_finite", [0, np.nan, 1])):
        stage, mesh = stage_with_mesh(name)
        mesh.GetPrim().CreateAttribute("wrinkle:heightProfile", Sdf.ValueTypeNames.FloatArray).Set(
            Vt.FloatArray([float(v) for v in values]))
        save(stage)
        case(name, "error", "a profile needs at least 2 finite samples")

    stage, mesh = stage_with_mesh("amplitude_scale_negative")
    mesh.GetPrim().CreateAttribute("wrinkle:amplitudeScale", Sdf.ValueTypeNames.Float).Set(-2.0)
    save(stage)
    case("amplitude_scale_negative", "error", "amplitude scale must be finite and >= 0")

    stage, mesh = stage_with_mesh("rest_wrong_length", posed={1: points})
    primvar(mesh, "rest", Sdf.ValueTypeNames.Point3fArray, Vt.Vec3fArray(4))
    save(stage)
    case("rest_wrong_length", "error", "primvars:rest and points differ in length")

    for name, bad_index, bad_weight, fragment in (
            ("joint_index_out_of_range", 7, 1.0, "joint indices out of range"),
            ("joint_weights_not_finite", 0, float("nan"), "joint weights are not finite")):
        stage, mesh = skinned(name)
        binding = UsdSkel.BindingAPI(mesh.GetPrim())
        idx = np.zeros(25, np.int32)
        idx[3] = bad_index
        wts = np.ones(25, np.float32)
        wts[4] = bad_weight
        binding.GetJointIndicesPrimvar().Set(Vt.IntArray(idx.tolist()))
        binding.GetJointWeightsPrimvar().Set(Vt.FloatArray(wts.tolist()))
        save(stage)
        case(name, "error", fragment)

    skinning_errors()
    wrong_types()
    time_sampled_errors()

    path = os.path.join(HERE, "not_usd.usda")
    with open(path, "w") as handle:
        handle.write("this is not a USD file\n{ ] \n")
    case("not_usd", "error", "cannot open")


def blend_shaped(name, offsets=None, inbetween=None, weights=None, point_indices=None,
                 target="/World/Cloth/Shape"):
    """A skinned sheet with one blend shape (and an inbetween), animated by weights."""
    stage, mesh = skinned(name)
    skel = UsdSkel.Skeleton(stage.GetPrimAtPath("/World/Skel"))
    anim = UsdSkel.Animation.Define(stage, "/World/Skel/Anim")
    anim.CreateJointsAttr(["root"])
    anim.CreateBlendShapesAttr(["shape"])
    anim.CreateTranslationsAttr(Vt.Vec3fArray([Gf.Vec3f(0)]))
    anim.CreateRotationsAttr(Vt.QuatfArray([Gf.Quatf(1)]))
    anim.CreateScalesAttr(Vt.Vec3hArray([Gf.Vec3h(1)]))
    for frame, weight in (weights or {1: 0.0, 2: 0.5, 3: 1.0}).items():
        anim.CreateBlendShapeWeightsAttr().Set(Vt.FloatArray([weight]), frame)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets(
        [anim.GetPath()])
    shape = UsdSkel.BlendShape.Define(stage, "/World/Cloth/Shape")
    shape.CreateOffsetsAttr(Vt.Vec3fArray.FromNumpy(np.asarray(
        offsets if offsets is not None else np.tile([0.0, 0.0, 0.1], (4, 1)), np.float32)))
    shape.CreatePointIndicesAttr(Vt.IntArray(point_indices or [0, 1, 2, 3]))
    if inbetween is not None:
        shape.CreateInbetween("half").SetOffsets(Vt.Vec3fArray.FromNumpy(
            np.asarray(inbetween, np.float32)))
        shape.GetInbetween("half").SetWeight(0.5)
    binding = UsdSkel.BindingAPI(mesh.GetPrim())
    binding.CreateBlendShapesAttr(["shape"])
    binding.CreateBlendShapeTargetsRel().SetTargets([Sdf.Path(target)])
    return stage, mesh


def skinning_errors():
    """Skinning data that would make a mesh vanish (NaN everywhere on the GPU)."""
    stage, mesh = skinned("geom_bind_not_finite")
    UsdSkel.BindingAPI(mesh.GetPrim()).CreateGeomBindTransformAttr(
        Gf.Matrix4d(1, 0, 0, 0, 0, float("nan"), 0, 0, 0, 0, 1, 0, 0, 0, 0, 1))
    save(stage)
    case("geom_bind_not_finite", "error", "geomBindTransform is not finite")

    nan_offsets = np.tile([0.0, 0.0, 0.1], (4, 1))
    nan_offsets[2, 1] = np.nan
    stage, _ = blend_shaped("blend_shape_offsets_not_finite", offsets=nan_offsets)
    save(stage)
    case("blend_shape_offsets_not_finite", "error", "blend shape offsets are not finite")

    stage, _ = blend_shaped("inbetween_offsets_not_finite", inbetween=nan_offsets)
    save(stage)
    case("inbetween_offsets_not_finite", "error", "blend shape offsets are not finite")

    stage, _ = blend_shaped("blend_shape_weight_not_finite",
                            weights={1: 0.0, 2: float("nan"), 3: 1.0})
    save(stage)
    case("blend_shape_weight_not_finite", "error",
         "blend shape weights are not finite (/World/Cloth.skel:blendShapes at frame 2)")

    stage, _ = blend_shaped("blend_shape_weight_huge", weights={1: 0.0, 2: 1e30, 3: 1.0})
    save(stage)
    case("blend_shape_weight_huge", "error", "(/World/Cloth.skel:blendShapes at frame 2)")

    stage, _ = blend_shaped("blend_shape_indices_out_of_range", point_indices=[0, 1, 2, 99])
    save(stage)
    case("blend_shape_indices_out_of_range", "error", "blend shape point indices out of range")

    stage, _ = blend_shaped("blend_shape_target_missing", target="/World/Cloth/NoShape")
    save(stage)
    case("blend_shape_target_missing", "error", "blend shape")


def wrong_types():
    """Mesh attributes authored with a type no reader can use."""
    points, counts, indices = grid()
    for name, attribute, type_name, value in (
            ("points_wrong_type", "points", Sdf.ValueTypeNames.String, "not points"),
            ("points_scalar", "points", Sdf.ValueTypeNames.Point3f, Gf.Vec3f(1, 2, 3)),
            ("face_counts_wrong_type", "faceVertexCounts", Sdf.ValueTypeNames.StringArray,
             Vt.StringArray(["4"] * 16)),
            ("face_indices_wrong_type", "faceVertexIndices", Sdf.ValueTypeNames.Int, 3),
            ("rest_wrong_type", "primvars:rest", Sdf.ValueTypeNames.StringArray,
             Vt.StringArray(["x"] * 25))):
        path = os.path.join(HERE, f"{name}.usda")
        layer = Sdf.Layer.CreateNew(path)
        layer.ImportFromString(f"""#usda 1.0
(
    startTimeCode = 1
    endTimeCode = 3
    upAxis = "Y"
)
def Xform "World" {{
    def Mesh "Cloth" (apiSchemas = ["WrinkleAPI"]) {{
        int[] faceVertexCounts = {list(counts)}
        int[] faceVertexIndices = {list(indices)}
        point3f[] points = {[tuple(p) for p in points.tolist()]}
    }}
}}
""")
        mesh_spec = layer.GetPrimAtPath("/World/Cloth")
        if attribute in mesh_spec.attributes:
            mesh_spec.RemoveProperty(mesh_spec.attributes[attribute])
        Sdf.AttributeSpec(mesh_spec, attribute, type_name).default = value
        layer.Save()
        case(name, "error", f"{attribute} must be")


def time_sampled_errors():
    """WrinkleAPI values that break a rule only at a later time sample, and a NaN
    primvars:rest: render must refuse them as check reports them."""
    points, counts, indices = grid()
    posed = {1: points, 2: points * [0.7, 1, 1], 3: points * [0.6, 1, 1]}
    for name, attribute, type_name, good, bad, fragment in (
            ("width_nan_at_frame", "primvars:wrinkle:width", Sdf.ValueTypeNames.FloatArray,
             Vt.FloatArray([0.3]), Vt.FloatArray([float("nan")]),
             "width must be finite and > 0"),
            ("q_wrong_length_at_frame", "primvars:wrinkle:q", Sdf.ValueTypeNames.Vector3fArray,
             Vt.Vec3fArray(25), Vt.Vec3fArray(3), "q has 3 values for 25 points"),
            ("amplitude_scale_nan_at_frame", "wrinkle:amplitudeScale",
             Sdf.ValueTypeNames.Float, 1.0, float("nan"),
             "amplitude scale must be finite and >= 0"),
            ("profile_nan_at_frame", "wrinkle:heightProfile", Sdf.ValueTypeNames.FloatArray,
             Vt.FloatArray([1.0, -1.0, 1.0]), Vt.FloatArray([1.0, float("nan")]),
             "a profile needs at least 2 finite samples"),
            ("relax_out_of_range_at_frame", "wrinkle:relaxIterations", Sdf.ValueTypeNames.Int,
             8, 1_000_000, "relax iterations must be in"),
            ("biaxial_out_of_range_at_frame", "wrinkle:biaxial", Sdf.ValueTypeNames.Float,
             0.5, 7.0, "biaxial weight must be in")):
        stage, mesh = stage_with_mesh(name, posed=posed)
        if attribute.startswith("primvars:"):
            attr = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
                attribute[len("primvars:"):], type_name,
                UsdGeom.Tokens.constant if "width" in attribute else UsdGeom.Tokens.vertex
            ).GetAttr()
        else:
            attr = mesh.GetPrim().CreateAttribute(attribute, type_name)
        attr.Set(good, 1)
        attr.Set(good, 2)
        attr.Set(bad, 3)
        save(stage)
        case(name, "error", fragment)

    stage, mesh = stage_with_mesh("rest_not_finite", posed=posed)
    rest = points.copy()
    rest[3] = np.nan
    primvar(mesh, "rest", Sdf.ValueTypeNames.Point3fArray, Vt.Vec3fArray.FromNumpy(rest))
    save(stage)
    case("rest_not_finite", "error", "points are not finite (NaN or Inf) "
                                     "(/World/Cloth.primvars:rest)")


def skinned(name):
    stage, mesh = stage_with_mesh(name, wrinkle=True)
    root = UsdSkel.Root.Define(stage, "/World")
    del root
    skel = UsdSkel.Skeleton.Define(stage, "/World/Skel")
    skel.CreateJointsAttr(["root"])
    skel.CreateBindTransformsAttr(Vt.Matrix4dArray([Gf.Matrix4d(1)]))
    skel.CreateRestTransformsAttr(Vt.Matrix4dArray([Gf.Matrix4d(1)]))
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([skel.GetPath()])
    binding.CreateJointIndicesPrimvar(False, 1).Set(Vt.IntArray([0] * 25))
    binding.CreateJointWeightsPrimvar(False, 1).Set(Vt.FloatArray([1.0] * 25))
    return stage, mesh


def degenerate():
    points, counts, indices = grid()
    collinear = np.stack([np.linspace(0, 1, 25), np.zeros(25), np.zeros(25)], 1)
    stage, _ = stage_with_mesh("collinear_points", collinear, counts, indices,
                               posed={1: collinear, 2: collinear * 0.5})
    save(stage)
    case("collinear_points", "ok")

    coincident = np.zeros((25, 3), np.float32)
    stage, _ = stage_with_mesh("coincident_points", coincident, counts, indices)
    save(stage)
    case("coincident_points", "ok")

    crushed = points.copy()
    crushed[:, 1] = 0.0  # every face has zero area at frame 2
    stage, _ = stage_with_mesh("zero_area_faces", posed={1: points, 2: crushed})
    save(stage)
    case("zero_area_faces", "ok")

    fin = np.vstack([points, [[0.5, 0.5, 1.0], [0.5, 0.5, -1.0]]])
    extra_counts = counts + [3, 3]
    extra = indices + [6, 7, 25, 6, 7, 26]  # two more faces on the edge 6-7
    stage, _ = stage_with_mesh("non_manifold_edges", fin, extra_counts, extra,
                               posed={1: fin, 2: fin * [0.7, 1, 1]})
    save(stage)
    case("non_manifold_edges", "ok", visible=True)

    lonely = np.vstack([points, [[5, 5, 5], [6, 6, 6]]])
    stage, _ = stage_with_mesh("isolated_vertices", lonely, counts, indices,
                               posed={1: lonely, 2: lonely * [0.6, 1, 1]})
    save(stage)
    case("isolated_vertices", "ok")

    ell = np.array([[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]],
                   np.float32)
    stage, _ = stage_with_mesh("concave_ngon", ell, [6], list(range(6)),
                               posed={1: ell, 2: ell * [0.5, 1, 1]})
    save(stage)
    case("concave_ngon", "ok", visible=True)

    stage, mesh = stage_with_mesh("holes", posed={1: points, 2: points * [0.7, 1, 1]})
    mesh.CreateHoleIndicesAttr(Vt.IntArray([5, 6]))
    save(stage)
    case("holes", "ok", visible=True)

    stage, mesh = stage_with_mesh("empty_mesh", np.zeros((0, 3)), [], [])
    save(stage)
    case("empty_mesh", "ok", warning="mesh has no points; skipped",
         bake=("error", "no mesh with WrinkleAPI can be wrinkled"))

    stage, mesh = stage_with_mesh("points_without_faces", points, [], [])
    save(stage)
    case("points_without_faces", "ok", warning="mesh has no faces; skipped",
         bake=("error", "no mesh with WrinkleAPI can be wrinkled"))

    stage, _ = stage_with_mesh("no_wrinkled_meshes", wrinkle=False)
    save(stage)
    case("no_wrinkled_meshes", "ok", warning="no mesh has WrinkleAPI applied", visible=True,
         bake=("error", "pass --all-meshes to wrinkle every mesh"))

    stage, mesh = stage_with_mesh("huge_width", posed={1: points, 2: points * [0.5, 1, 1]})
    primvar(mesh, "wrinkle:width", Sdf.ValueTypeNames.FloatArray, Vt.FloatArray([1e6]),
            UsdGeom.Tokens.constant)
    save(stage)
    case("huge_width", "ok", visible=True)

    stage, mesh = stage_with_mesh("tiny_width", posed={1: points, 2: points * [0.5, 1, 1]})
    primvar(mesh, "wrinkle:width", Sdf.ValueTypeNames.FloatArray, Vt.FloatArray([1e-6]),
            UsdGeom.Tokens.constant)
    save(stage)
    case("tiny_width", "ok", visible=True)

    stage, mesh = stage_with_mesh("missing_skeleton")
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([Sdf.Path("/World/NoSuchSkel")])
    save(stage)
    case("missing_skeleton", "ok", warning="skel binding to a missing or unusable skeleton",
         visible=True)

    stage, mesh = stage_with_mesh("missing_texture")
    material = UsdShade.Material.Define(stage, "/World/Look")
    shader = UsdShade.Shader.Define(stage, "/World/Look/surface")
    shader.CreateIdAttr("UsdPreviewSurface")
    tex = UsdShade.Shader.Define(stage, "/World/Look/tex")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./does/not/exist.png")
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        tex.ConnectableAPI().CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    save(stage)
    case("missing_texture", "ok", warning="not found; rendering untextured", visible=True)

    stage, mesh = stage_with_mesh("extreme_compression",
                                  posed={1: points, 2: points * [1e-4, 1, 1]})
    primvar(mesh, "wrinkle:q", Sdf.ValueTypeNames.Vector3fArray,
            Vt.Vec3fArray.FromNumpy(np.tile([0.0, 1.0, 0.0], (25, 1)).astype(np.float32)))
    save(stage)
    case("extreme_compression", "ok")


def main() -> int:
    errors()
    degenerate()
    with open(os.path.join(HERE, "cases.json"), "w") as handle:
        json.dump(CASES, handle, indent=2, sort_keys=True)
        handle.write("\n")
    print(f"{len(CASES)} cases")
    return 0


if __name__ == "__main__":
    sys.exit(main())
