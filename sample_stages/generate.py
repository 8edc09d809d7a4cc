"""Generate the sample stages: the paper's three cases (shirt, zeppelin, curtain).

    python sample_stages/generate.py [OUTDIR]

Each stage has a camera, a light, a UsdPreviewSurface material, a UsdSkel rig and
animation (frames 1-24), WrinkleAPI on the cloth and a painted-q region. The
.usda files and the texture are committed; rerun this script after changing it.
"""
from __future__ import annotations

import os
import sys

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade, UsdSkel, Vt

import usdwrinkle  # noqa: F401  registers WrinkleAPI before USD builds its registry
from usdwrinkle import WrinkleAPI, profile_preset
from usdwrinkle.authoring.builders import grid_faces, grid_sheet
from usdwrinkle.authoring.qsources import MeshSurface, q_from_flow_map
from usdwrinkle.images.colour import srgb_encode

FRAMES = (1, 24)


def new_stage(path: str) -> Usd.Stage:
    if os.path.exists(path):
        os.remove(path)
    stage = Usd.Stage.CreateNew(path)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetStartTimeCode(FRAMES[0])
    stage.SetEndTimeCode(FRAMES[1])
    stage.SetTimeCodesPerSecond(24)
    stage.SetFramesPerSecond(24)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    return stage


def add_camera(stage, eye, target, focal=35.0):
    cam = UsdGeom.Camera.Define(stage, "/World/main_cam")
    cam.CreateFocalLengthAttr(focal)
    cam.CreateHorizontalApertureAttr(36.0)
    cam.CreateVerticalApertureAttr(24.0)
    cam.CreateClippingRangeAttr(Gf.Vec2f(0.1, 100.0))
    look = Gf.Matrix4d().SetLookAt(Gf.Vec3d(*eye), Gf.Vec3d(*target), Gf.Vec3d(0, 1, 0))
    cam.AddTransformOp().Set(look.GetInverse())


def add_lights(stage, direction_euler=(-40.0, 30.0, 0.0)):
    """A warm key and a cool fill, in UsdLux's units: a DistantLight's intensity is the
    radiance of its disc (inputs:angle, 0.53 degrees by default), so the key at the
    schema's own 50,000 (the sun's disc) gives an irradiance of 3.36, and a white
    UsdPreviewSurface facing it shows 3.36 x albedo / pi: about its albedo. The fill
    comes from the other side, low, at a sixth of that, and a warm bounce from below (the
    ground's light, at the fill's strength), so that fold flanks turned down from both are
    shaded, not black."""
    key = UsdLux.DistantLight.Define(stage, "/World/Lights/key")
    key.CreateIntensityAttr(50000.0)
    key.CreateAngleAttr(0.53)
    key.CreateColorAttr(Gf.Vec3f(1.0, 0.97, 0.92))
    key.AddRotateXYZOp().Set(Gf.Vec3f(*direction_euler))
    fill = UsdLux.DistantLight.Define(stage, "/World/Lights/fill")
    fill.CreateIntensityAttr(8000.0)
    fill.CreateAngleAttr(0.53)
    fill.CreateColorAttr(Gf.Vec3f(0.8, 0.85, 1.0))
    fill.AddRotateXYZOp().Set(Gf.Vec3f(-direction_euler[0] * 0.25,
                                       direction_euler[1] - 150.0, 0.0))
    bounce = UsdLux.DistantLight.Define(stage, "/World/Lights/bounce")
    bounce.CreateIntensityAttr(8000.0)
    bounce.CreateAngleAttr(0.53)
    bounce.CreateColorAttr(Gf.Vec3f(1.0, 0.92, 0.82))
    bounce.AddRotateXYZOp().Set(Gf.Vec3f(80.0, 0.0, 0.0))  # shines up (-Z turned to +Y)


def add_material(stage, name, color=None, texture=None):
    material = UsdShade.Material.Define(stage, f"/World/Looks/{name}")
    shader = UsdShade.Shader.Define(stage, f"/World/Looks/{name}/surface")
    shader.CreateIdAttr("UsdPreviewSurface")
    shader.CreateInput("roughness", Sdf.ValueTypeNames.Float).Set(0.6)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    if texture:
        reader = UsdShade.Shader.Define(stage, f"/World/Looks/{name}/st_reader")
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
        tex = UsdShade.Shader.Define(stage, f"/World/Looks/{name}/diffuse_texture")
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(texture)
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
            reader.ConnectableAPI(), "result")
        tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set("repeat")
        tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set("repeat")
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
            tex.ConnectableAPI().CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    else:
        shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).Set(Gf.Vec3f(*color))
    return material


def define_mesh(stage, path, points, counts, indices, st=None,
                st_interpolation=UsdGeom.Tokens.vertex):
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(np.asarray(points, np.float32)))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(np.asarray(counts, np.int32)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(np.asarray(indices, np.int32)))
    # a subdivision surface (USD's fallback scheme): renderers shade it with smooth
    # normals of the posed cage (usdview's default complexity draws the cage itself)
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.catmullClark)
    mesh.CreateDoubleSidedAttr(True)
    lo, hi = np.min(points, 0), np.max(points, 0)
    mesh.CreateExtentAttr(Vt.Vec3fArray([Gf.Vec3f(*lo.tolist()), Gf.Vec3f(*hi.tolist())]))
    if st is not None:
        UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
            "st", Sdf.ValueTypeNames.TexCoord2fArray, st_interpolation).Set(
            Vt.Vec2fArray.FromNumpy(np.asarray(st, np.float32)))
    return mesh


def apply_wrinkles(mesh, width, q=None, amplitude_scale=1.0, irregularity=None):
    """Author WrinkleAPI through usdwrinkle's own API (each value checked as it is set)."""
    api = WrinkleAPI.Apply(mesh.GetPrim())
    api.CreateWidthPrimvar([width])
    if q is not None:
        api.set_q(q)
    api.CreateAmplitudeScaleAttr(amplitude_scale)
    if irregularity is not None:
        api.CreateIrregularityAttr(irregularity)
    return api


def rig(stage, root_path, mesh, joints, bind_xforms, joint_indices, joint_weights,
        influences, animate):
    """A SkelRoot with a Skeleton and a SkelAnimation; ``animate(anim)`` authors samples."""
    skel = UsdSkel.Skeleton.Define(stage, f"{root_path}/Skel")
    skel.CreateJointsAttr(joints)
    skel.CreateBindTransformsAttr(Vt.Matrix4dArray([Gf.Matrix4d(m) for m in bind_xforms]))
    rest = []
    for i, name in enumerate(joints):
        parent = name.rsplit("/", 1)[0] if "/" in name else None
        local = Gf.Matrix4d(bind_xforms[i])
        if parent is not None:
            local = local * Gf.Matrix4d(bind_xforms[joints.index(parent)]).GetInverse()
        rest.append(local)
    skel.CreateRestTransformsAttr(Vt.Matrix4dArray(rest))
    anim = UsdSkel.Animation.Define(stage, f"{root_path}/Skel/Anim")
    anim.CreateJointsAttr(joints)
    animate(anim, rest)
    UsdSkel.BindingAPI.Apply(skel.GetPrim()).CreateAnimationSourceRel().SetTargets(
        [anim.GetPath()])
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateSkeletonRel().SetTargets([skel.GetPath()])
    binding.CreateJointIndicesPrimvar(False, influences).Set(
        Vt.IntArray.FromNumpy(np.asarray(joint_indices, np.int32).ravel()))
    binding.CreateJointWeightsPrimvar(False, influences).Set(
        Vt.FloatArray.FromNumpy(np.asarray(joint_weights, np.float32).ravel()))
    binding.CreateGeomBindTransformAttr(Gf.Matrix4d(1.0))
    return skel, anim


def make_texture(path, repeats=(1, 1)):
    """A woven plaid so the texture deformation shows where the cloth folds; ``repeats``
    tiles of 256 x 256 texels across and up."""
    import OpenImageIO as oiio

    size = 256
    u, v = np.meshgrid(np.arange(size * repeats[0]) / size, np.arange(size * repeats[1]) / size)
    base = np.array([0.72, 0.18, 0.16])
    stripe_a = (np.sin(u * 2 * np.pi * 8) > 0.55)[..., None]
    stripe_b = (np.sin(v * 2 * np.pi * 8) > 0.55)[..., None]
    img = base * (1 - 0.45 * stripe_a) * (1 - 0.45 * stripe_b)
    img = img + np.array([0.9, 0.85, 0.6]) * ((np.abs(np.sin(u * 2 * np.pi * 32)) > 0.97)
                                              [..., None] * 0.5)
    img = srgb_encode(img)
    spec = oiio.ImageSpec(img.shape[1], img.shape[0], 3, "uint8")
    out = oiio.ImageOutput.create(path)
    out.open(path, spec)
    out.write_image(np.ascontiguousarray((img * 255).astype(np.uint8)))
    out.close()


def shirt(outdir):
    """A sleeve (35 x 13 = 455 vertices) on an arm that bends at the elbow."""
    stage = new_stage(os.path.join(outdir, "shirt.usda"))
    around, along, length, radius = 35, 13, 3.0, 0.38
    theta = np.arange(around) * 2 * np.pi / around
    xs = np.linspace(0, length, along)
    gx, gt = np.meshgrid(xs, theta, indexing="ij")
    points = np.stack([gx.ravel(), radius * np.cos(gt).ravel(), radius * np.sin(gt).ravel()], 1)
    counts, indices = grid_faces(along, around, wrap_cols=True)
    # face-varying UVs in the 0-1 tile with a seam where the sleeve closes (u = 0 and
    # u = 1), so that baked wrinkle maps have one non-overlapping island; the plaid
    # repeats 2 x 3 times inside its texture
    corner = indices.reshape(-1, 4)
    row, col = corner // around, corner % around
    col[:, 1:3] = np.where(col[:, 1:3] < col[:, [0, 3]], col[:, 1:3] + around, col[:, 1:3])
    st = np.stack([col / around, row / (along - 1)], -1).reshape(-1, 2)
    os.makedirs(os.path.join(outdir, "textures"), exist_ok=True)
    make_texture(os.path.join(outdir, "textures", "plaid.png"), repeats=(2, 3))
    UsdSkel.Root.Define(stage, "/World/Arm")
    mesh = define_mesh(stage, "/World/Arm/Sleeve", points, counts, indices, st,
                       UsdGeom.Tokens.faceVarying)
    material = add_material(stage, "Plaid", texture="./textures/plaid.png")
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    elbow = 1.5
    # the forearm's weight rises from 0.8 to 2.1 along the sleeve (1.3 units, 3.4 radii):
    # over 0.35 either side of the elbow the 105 degree bend creased the coarse sleeve's
    # inner side into a V that passed through itself (38 crossing coarse triangles at
    # frame 24), where no height field over the coarse faces holds the cloth's length
    # (docs/physics.md, "the shirt's rig", has the widths tried)
    w_fore = np.clip((points[:, 0] - 0.8) / 1.3, 0, 1)
    w_fore = w_fore * w_fore * (3 - 2 * w_fore)
    indices_j = np.stack([np.zeros(len(points)), np.ones(len(points))], 1)
    weights_j = np.stack([1 - w_fore, w_fore], 1)
    joints = ["shoulder", "shoulder/elbow"]
    bind = [np.eye(4), np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [elbow, 0, 0, 1]])]

    def animate(anim, rest):
        anim.CreateTranslationsAttr()
        anim.CreateRotationsAttr()
        anim.CreateScalesAttr()
        for f in range(FRAMES[0], FRAMES[1] + 1):
            s = (f - FRAMES[0]) / (FRAMES[1] - FRAMES[0])
            s = s * s * (3 - 2 * s)
            bend = Gf.Rotation(Gf.Vec3d(0, 0, 1), 105.0 * s).GetQuat()
            lift = Gf.Rotation(Gf.Vec3d(0, 0, 1), -15.0 * s).GetQuat()
            anim.GetTranslationsAttr().Set(Vt.Vec3fArray([Gf.Vec3f(0, 0, 0),
                                                          Gf.Vec3f(elbow, 0, 0)]), f)
            anim.GetRotationsAttr().Set(Vt.QuatfArray([Gf.Quatf(lift), Gf.Quatf(bend)]), f)
            anim.GetScalesAttr().Set(Vt.Vec3hArray([Gf.Vec3h(1, 1, 1)] * 2), f)

    rig(stage, "/World/Arm", mesh, joints, bind, indices_j, weights_j, 2, animate)
    # dual quaternions, as a rigger skins an elbow: linear blending collapses the inner
    # elbow, and the folds crowded into one knot of streaks whose phases settled into one
    # of two layouts under a 0.01 degree change of a joint; skinned so, the sleeve stays
    # round and its folds fan out as separate creases (issue 55; docs/physics.md)
    UsdSkel.BindingAPI(mesh.GetPrim()).CreateSkinningMethodAttr().Set(
        UsdSkel.Tokens.dualQuaternion)
    # painted region: the cuff gathers along the sleeve axis
    q = np.zeros_like(points)
    cuff = np.clip((points[:, 0] - (length - 0.7)) / 0.5, 0, 1)
    q[:, 0] = 0.55 * cuff
    # W = 0.1: at the elbow's pinch (a fifth of its length kept) the posed folds are W r,
    # and 0.28 drew them as one knot of streaks; 0.1 draws separate folds (issue 55). On a
    # sleeve of radius 10 cm (benchmarks/physics/elbow.py's scale) it is 2.6 cm, the
    # cylinder's 3.5 sqrt(R t) for cloth 0.5 mm thick (Cerda-Mahadevan)
    # irregularity 0.15: the cuff's painted gathers stood as straight black rings, stripes
    # more than gathers (issue 55); unequal folds whose crests meander read as cloth. At
    # 0.2 the elbow's displaced geometry drew 1.050 of its rest area where compressed
    # along one direction (tests/test_folds.py's bar 1.05), at 0.15 1.044 (0: 1.031)
    apply_wrinkles(mesh, width=0.1, q=q, amplitude_scale=1.0, irregularity=0.15)
    add_camera(stage, eye=(2.1, 1.5, 3.7), target=(1.35, 0.45, 0.0))
    add_lights(stage)
    stage.GetRootLayer().Save()
    return len(points)


def zeppelin(outdir):
    """A hull (28 x 18 + 2 poles = 506 vertices) that deflates through a blend shape."""
    stage = new_stage(os.path.join(outdir, "zeppelin.usda"))
    around, rings, length, radius = 28, 18, 4.0, 0.8
    theta = np.arange(around) * 2 * np.pi / around
    t = np.linspace(0, 1, rings + 2)[1:-1]
    x = (t - 0.5) * length
    profile = radius * np.sqrt(np.maximum(1 - (2 * t - 1) ** 2, 0)) ** 0.9
    gx, gt = np.meshgrid(x, theta, indexing="ij")
    gr = np.repeat(profile[:, None], around, axis=1)
    body = np.stack([gx.ravel(), (gr * np.cos(gt)).ravel(), (gr * np.sin(gt)).ravel()], 1)
    points = np.concatenate([body, [[-length / 2, 0, 0], [length / 2, 0, 0]]])
    counts, indices = grid_faces(rings, around, wrap_cols=True)
    tail, nose = len(body), len(body) + 1
    caps = []
    for c in range(around):
        caps.append([tail, (c + 1) % around, c])
        last = (rings - 1) * around
        caps.append([nose, last + c, last + (c + 1) % around])
    counts = np.concatenate([counts, np.full(len(caps), 3, np.int32)])
    indices = np.concatenate([indices, np.array(caps, np.int32).ravel()])
    UsdSkel.Root.Define(stage, "/World/Zeppelin")
    mesh = define_mesh(stage, "/World/Zeppelin/Hull", points, counts, indices)
    material = add_material(stage, "Canvas", color=(0.78, 0.74, 0.62))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    # deflate: the middle loses 28% of its girth, the length stays (the frame is rigid)
    mid = np.sin(np.pi * np.clip((points[:, 0] / length) + 0.5, 0, 1))
    offsets = np.zeros_like(points)
    offsets[:, 1:] = -0.28 * mid[:, None] * points[:, 1:]
    shape = UsdSkel.BlendShape.Define(stage, "/World/Zeppelin/Hull/deflate")
    shape.CreateOffsetsAttr(Vt.Vec3fArray.FromNumpy(offsets.astype(np.float32)))
    binding = UsdSkel.BindingAPI.Apply(mesh.GetPrim())
    binding.CreateBlendShapesAttr(["deflate"])
    binding.CreateBlendShapeTargetsRel().SetTargets([shape.GetPath()])

    def animate(anim, rest):
        anim.CreateBlendShapesAttr(["deflate"])
        anim.CreateTranslationsAttr().Set(Vt.Vec3fArray([Gf.Vec3f(0, 0, 0)]))
        anim.CreateRotationsAttr().Set(Vt.QuatfArray([Gf.Quatf(1, 0, 0, 0)]))
        anim.CreateScalesAttr().Set(Vt.Vec3hArray([Gf.Vec3h(1, 1, 1)]))
        weights = anim.CreateBlendShapeWeightsAttr()
        for f in range(FRAMES[0], FRAMES[1] + 1):
            s = (f - FRAMES[0]) / (FRAMES[1] - FRAMES[0])
            weights.Set(Vt.FloatArray([s]), f)

    rig(stage, "/World/Zeppelin", mesh, ["hull"], [np.eye(4)],
        np.zeros(len(points)), np.ones(len(points)), 1, animate)
    # painted region: the nose cone is pulled tight around its tip
    q = np.zeros_like(points)
    near_nose = np.clip((points[:, 0] - 1.2) / 0.6, 0, 1)
    circum = np.stack([np.zeros(len(points)), -points[:, 2], points[:, 1]], 1)
    circum /= np.maximum(np.linalg.norm(circum, axis=1, keepdims=True), 1e-9)
    q = circum * (0.6 * near_nose)[:, None]
    apply_wrinkles(mesh, width=0.3, q=q)
    add_camera(stage, eye=(1.6, 1.4, 5.2), target=(0.0, 0.0, 0.0))
    add_lights(stage)
    stage.GetRootLayer().Save()
    return len(points)


def curtain(outdir):
    """A curtain (23 x 4 = 92 vertices) gathered along its rail by four joints."""
    stage = new_stage(os.path.join(outdir, "curtain.usda"))
    cols, rows, width, height = 23, 4, 2.4, 2.0
    xs = np.linspace(0, width, cols)
    ys = np.linspace(0, -height, rows)
    gy, gx = np.meshgrid(ys, xs, indexing="ij")
    # a gentle pleat so the drape has a normal to bend
    gz = 0.04 * np.sin(gx * 2 * np.pi / (width / 6))
    points = np.stack([gx.ravel(), gy.ravel(), gz.ravel()], 1)
    counts, indices = grid_faces(rows, cols)
    st = np.stack([(gx / width).ravel() * 2, (gy / height).ravel() * 2 + 2], 1)
    UsdSkel.Root.Define(stage, "/World/Curtain")
    mesh = define_mesh(stage, "/World/Curtain/Cloth", points, counts, indices, st)
    material = add_material(stage, "Velvet", color=(0.25, 0.32, 0.62))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    anchors = np.linspace(0, width, 4)
    joints = ["rail", "rail/ring1", "rail/ring2", "rail/ring3"]
    bind = [np.eye(4)] + [np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [a, 0, 0, 1]])
                          for a in anchors[1:]]
    # each vertex follows the two rings around it (linear in x), ring 0 is the rail itself
    seg = np.clip(np.searchsorted(anchors, points[:, 0], side="right") - 1, 0, 2)
    local = (points[:, 0] - anchors[seg]) / (anchors[seg + 1] - anchors[seg])
    ji = np.stack([seg, seg + 1], 1)
    jw = np.stack([1 - local, local], 1)
    gathered = np.array([0.0, 0.35, 0.65, 0.95])

    def animate(anim, rest):
        anim.CreateTranslationsAttr()
        anim.CreateRotationsAttr().Set(Vt.QuatfArray([Gf.Quatf(1, 0, 0, 0)] * 4))
        anim.CreateScalesAttr().Set(Vt.Vec3hArray([Gf.Vec3h(1, 1, 1)] * 4))
        for f in range(FRAMES[0], FRAMES[1] + 1):
            s = (f - FRAMES[0]) / (FRAMES[1] - FRAMES[0])
            s = s * s * (3 - 2 * s)
            pos = anchors + s * (gathered - anchors)
            # joint-local translations: ring k sits relative to the rail (joint 0)
            anim.GetTranslationsAttr().Set(
                Vt.Vec3fArray([Gf.Vec3f(0, 0, 0)] + [Gf.Vec3f(float(p), 0, 0)
                                                     for p in pos[1:]]), f)

    rig(stage, "/World/Curtain", mesh, joints, bind, ji, jw, 2, animate)
    # painted region: the hem is sewn gathered
    q = np.zeros_like(points)
    hem = points[:, 1] < -height + 0.01
    q[hem, 0] = 0.5
    apply_wrinkles(mesh, width=0.16, q=q, amplitude_scale=1.0)
    add_camera(stage, eye=(1.0, -0.6, 4.2), target=(0.9, -1.0, 0.0))
    add_lights(stage, direction_euler=(-25.0, 35.0, 0.0))
    stage.GetRootLayer().Save()
    return len(points)


def make_flow_map(path):
    """A painted flow map: compression runs around the centre (a drawstring gather, so the
    folds radiate), and the amount fades out towards the rim.

    RG = direction in (u, v) as 2c - 1 with v up; B = amount.
    """
    import OpenImageIO as oiio

    size = 128
    v, u = np.mgrid[0:size, 0:size]
    u = (u + 0.5) / size - 0.5
    v = 0.5 - (v + 0.5) / size  # image rows run down, v runs up
    radius = np.hypot(u, v)
    swirl = np.stack([-v, u], -1) / np.maximum(radius, 1e-6)[..., None]
    amount = np.clip(1.0 - radius / 0.45, 0.0, 1.0) * 0.8
    rgb = np.concatenate([0.5 + 0.5 * swirl, amount[..., None]], -1)
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(size, size, 3, "uint8"))
    out.write_image(np.ascontiguousarray(np.round(rgb * 255).astype(np.uint8)))
    out.close()


def flag(outdir):
    """A static banner (25 x 17 = 425 vertices): its wrinkles are painted, not deformed."""
    stage = new_stage(os.path.join(outdir, "flag.usda"))
    cols, rows, width, height = 25, 17, 3.0, 2.0
    xs, ys = np.linspace(-width / 2, width / 2, cols), np.linspace(0, height, rows)
    gy, gx = np.meshgrid(ys, xs, indexing="ij")
    points = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], 1)
    counts, indices = grid_faces(rows, cols)
    st = np.stack([(gx.ravel() + width / 2) / width, gy.ravel() / height], 1)
    mesh = define_mesh(stage, "/World/Flag", points, counts, indices, st)
    material = add_material(stage, "Silk", color=(0.85, 0.72, 0.3))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    flow = os.path.join(outdir, "textures", "flow_gather.png")
    make_flow_map(flow)
    api = apply_wrinkles(mesh, width=0.12)
    api.set_q(q_from_flow_map(MeshSurface(mesh.GetPrim()), flow, "st", "B"))
    api.set_profile(profile_preset("sharp"))
    add_camera(stage, eye=(0.0, 1.0, 4.2), target=(0.0, 1.0, 0.0))
    add_lights(stage, direction_euler=(-35.0, 25.0, 0.0))
    stage.GetRootLayer().Save()
    return len(points)


def point_cache(mesh, rest, posed_at):
    """Time-sampled points (``posed_at(s)``, s from 0 to 1 over the frames) with the rest
    pose as primvars:rest."""
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "rest", Sdf.ValueTypeNames.Point3fArray, UsdGeom.Tokens.vertex).Set(
        Vt.Vec3fArray.FromNumpy(np.asarray(rest, np.float32)))
    points = mesh.GetPointsAttr()
    extent = mesh.GetExtentAttr()
    for f in range(FRAMES[0], FRAMES[1] + 1):
        s = (f - FRAMES[0]) / (FRAMES[1] - FRAMES[0])
        posed = np.asarray(posed_at(s * s * (3 - 2 * s)), np.float32)
        points.Set(Vt.Vec3fArray.FromNumpy(posed), f)
        lo, hi = posed.min(0), posed.max(0)
        extent.Set(Vt.Vec3fArray([Gf.Vec3f(*lo.tolist()), Gf.Vec3f(*hi.tolist())]), f)


def pillow(outdir):
    """A pillow (48 x 25 = 1,200 vertices) squeezed from its four sides: its top and bottom
    are compressed along both axes at once (wrinkle:biaxial = 1: crossing wrinkles)."""
    stage = new_stage(os.path.join(outdir, "pillow.usda"))
    around, rings = 48, 27
    theta = np.arange(around) * 2 * np.pi / around
    phi = np.linspace(0, np.pi, rings)[1:-1]
    gp, gt = np.meshgrid(phi, theta, indexing="ij")
    # a squashed superellipsoid: broad flat faces, rounded edges
    def shape(angle, power):
        return np.sign(np.cos(angle)) * np.abs(np.cos(angle)) ** power
    x = 1.1 * np.sin(gp) ** 0.35 * shape(gt, 0.35)
    z = 0.75 * np.sin(gp) ** 0.35 * np.sign(np.sin(gt)) * np.abs(np.sin(gt)) ** 0.35
    y = 0.28 * shape(gp, 0.6)
    body = np.stack([x.ravel(), y.ravel(), z.ravel()], 1)
    points = np.concatenate([body, [[0, 0.28, 0], [0, -0.28, 0]]])
    counts, indices = grid_faces(rings - 2, around, wrap_cols=True)
    top, bottom = len(body), len(body) + 1
    caps = []
    last = (rings - 3) * around
    for c in range(around):
        caps.append([top, (c + 1) % around, c])
        caps.append([bottom, last + c, last + (c + 1) % around])
    counts = np.concatenate([counts, np.full(len(caps), 3, np.int32)])
    indices = np.concatenate([indices, np.array(caps, np.int32).ravel()])
    mesh = define_mesh(stage, "/World/Pillow", points, counts, indices)
    material = add_material(stage, "Linen", color=(0.86, 0.82, 0.74))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)

    def squeeze(s):
        # hands press the sides in: x to 72%, z to 80% near the middle; the filling swells
        bulge = np.exp(-(points[:, 0] ** 2 / 1.2 + points[:, 2] ** 2 / 0.6))
        sx = 1 - 0.28 * s * (0.6 + 0.4 * bulge)
        sz = 1 - 0.2 * s * (0.6 + 0.4 * bulge)
        sy = 1 + 0.9 * s * bulge
        return points * np.stack([sx, sy, sz], 1)

    point_cache(mesh, points, squeeze)
    api = apply_wrinkles(mesh, width=0.2)
    api.CreateBiaxialAttr(1.0)
    add_camera(stage, eye=(0.0, 2.4, 2.6), target=(0.0, 0.0, 0.0))
    add_lights(stage, direction_euler=(-55.0, 20.0, 0.0))
    stage.GetRootLayer().Save()
    return len(points)


def pull(outdir):
    """A sheet (31 x 31 = 961 vertices) pinned at two opposite corners and pulled apart
    along the diagonal: a band of tension along it, where the cloth is stretched but not
    narrowed (wrinkle:tension = 1: crests along the pull)."""
    stage = new_stage(os.path.join(outdir, "pull.usda"))
    points, counts, indices = grid_sheet(31, 31, 2.0)
    points = points[:, [0, 2, 1]] * np.array([1, 1, -1])  # in the XZ plane, y up
    mesh = define_mesh(stage, "/World/Sheet", points, counts, indices,
                       (points[:, [0, 2]] * np.array([1, -1]) + 1) / 2)
    material = add_material(stage, "Cotton", color=(0.55, 0.7, 0.82))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(material)
    diagonal = np.array([1.0, 0.0, 1.0]) / np.sqrt(2)
    across = np.array([-1.0, 0.0, 1.0]) / np.sqrt(2)

    def stretch(s):
        u = points @ diagonal            # along the pull, -sqrt 2 .. sqrt 2
        v = points @ across              # across it
        band = np.exp(-(v / 0.45) ** 2)  # the pull is carried by a band between the pins
        # the band lengthens by up to 22% (the pins move apart); its width stays
        du = 0.22 * s * band * u
        sag = -0.12 * s * (1 - band) * (1 - (u / np.sqrt(2)) ** 2)
        return points + du[:, None] * diagonal + np.stack(
            [np.zeros(len(u)), sag, np.zeros(len(u))], 1)

    point_cache(mesh, points, stretch)
    api = apply_wrinkles(mesh, width=0.16)
    api.CreateTensionAttr(1.0)
    api.CreateTensionThresholdAttr(0.02)
    add_camera(stage, eye=(0.0, 2.6, 2.2), target=(0.0, -0.1, 0.0))
    add_lights(stage, direction_euler=(-60.0, 35.0, 0.0))
    stage.GetRootLayer().Save()
    return len(points)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    outdir = argv[0] if argv else os.path.dirname(os.path.abspath(__file__))
    os.makedirs(outdir, exist_ok=True)
    os.makedirs(os.path.join(outdir, "textures"), exist_ok=True)
    for make in (shirt, zeppelin, curtain, flag, pillow, pull):
        count = make(outdir)
        print(f"{make.__name__}.usda: {count} vertices")
    return 0


if __name__ == "__main__":
    sys.exit(main())
