"""Scene delegate: topology, cameras, lights, materials, visibility, purpose, transforms."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade, Vt

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.process.errors import UsdWrinkleError
from usdwrinkle.scene.camera import find_camera, towards_eye, usd_camera
from usdwrinkle.scene.stage import StageSceneDelegate
from usdwrinkle.scene.topology import build_topology, ear_clip

from conftest import grid_sheet
from helpers import point_cache_stage

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


def polygon_area(points, triangles):
    a, b, c = points[triangles[:, 0]], points[triangles[:, 1]], points[triangles[:, 2]]
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def test_concave_ngon_is_ear_clipped():
    # an L-shaped hexagon (concave at (1, 1)), area 3, listed from (2, 0): the fan from
    # there would cross the notch and cover area outside the L
    points = np.array([[2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0], [0, 0, 0]],
                      np.float32)
    fan = np.array([[0, i, i + 1] for i in range(1, 5)])
    assert polygon_area(points, fan).sum() > 3.2
    topo = build_topology([6], [0, 1, 2, 3, 4, 5], points)
    assert len(topo.triangles) == 4
    assert polygon_area(points, topo.triangles).sum() == pytest.approx(3.0)
    normals = np.cross(points[topo.triangles[:, 1]] - points[topo.triangles[:, 0]],
                       points[topo.triangles[:, 2]] - points[topo.triangles[:, 0]])
    assert np.all(normals[:, 2] > 0)  # every triangle keeps the face's winding
    assert polygon_area(points, np.array(ear_clip(points))).sum() == pytest.approx(3.0)


def test_large_concave_polygon_and_clockwise_faces():
    """A 2,000-corner star (every other corner reflex): earcut covers exactly its area,
    with the face's winding, whichever way the face turns."""
    k = 2000
    theta = np.arange(k) * 2 * np.pi / k
    radius = np.where(np.arange(k) % 2 == 0, 1.0, 0.5)
    points = np.stack([radius * np.cos(theta), radius * np.sin(theta), np.zeros(k)], 1)
    xy = points[:, :2]
    shoelace = 0.5 * abs(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1)
                                * xy[:, 1]))
    for order, sign in ((np.arange(k), 1), (np.arange(k)[::-1], -1)):
        topo = build_topology([k], order, points)
        assert len(topo.triangles) == k - 2
        assert polygon_area(points, topo.triangles).sum() == pytest.approx(shoelace, rel=1e-9)
        normals = np.cross(points[topo.triangles[:, 1]] - points[topo.triangles[:, 0]],
                           points[topo.triangles[:, 2]] - points[topo.triangles[:, 0]])
        assert np.all(sign * normals[:, 2] > 0)


def test_quads_holes_and_face_varying_corners():
    points, counts, indices = grid_sheet(4, 4, 3.0)  # 9 quads
    topo = build_topology(counts, indices, points, hole_indices=[4])
    assert len(topo.triangles) == 16
    assert 4 not in set(topo.triangle_face.tolist())
    # corner_face_vertex indexes faceVertexIndices: it maps back to the same points
    np.testing.assert_array_equal(np.asarray(indices)[topo.corner_face_vertex], topo.triangles)
    # the middle vertex ring: vertex 5 has neighbours from the 1-ring of kept faces only
    ring = topo.neighbor_indices[topo.neighbor_offsets[5]:topo.neighbor_offsets[6]]
    assert set(ring.tolist()) >= {1, 4}


def test_bad_topology_is_refused():
    points = np.zeros((4, 3), np.float32)
    with pytest.raises(UsdWrinkleError, match="sum to"):
        build_topology([4, 3], [0, 1, 2, 3], points, prim_path="/M")
    with pytest.raises(UsdWrinkleError, match="out of range"):
        build_topology([3], [0, 1, 9], points, prim_path="/M")


def test_camera_selection():
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.Camera.Define(stage, "/A/first")
    UsdGeom.Camera.Define(stage, "/B/main_cam")
    assert str(find_camera(stage, None).GetPath()) == "/B/main_cam"  # primary camera
    assert str(find_camera(stage, "first").GetPath()) == "/A/first"  # by name
    assert str(find_camera(stage, "/A/first").GetPath()) == "/A/first"  # by path
    with pytest.raises(UsdWrinkleError, match="not found"):
        find_camera(stage, "/nope")
    stage.RemovePrim("/B")
    assert str(find_camera(stage, None).GetPath()) == "/A/first"  # first camera
    stage.RemovePrim("/A")
    assert find_camera(stage, None) is None  # framing


def test_view_rays_are_the_pinhole_cameras(tmp_path):
    """scene.camera.towards_eye against the pinhole model from the camera's own attributes:
    a pixel centre at (x, y) in [-1, 1] looks along (x a_h / 2f, y a_h / (2f aspect), -1)
    in the camera's frame (the horizontal aperture kept, the vertical fitted to the
    image), turned into the world by the camera's transform; an orthographic camera's
    rays are all its backward axis."""
    stage = Usd.Stage.CreateInMemory()
    camera = UsdGeom.Camera.Define(stage, "/Cam")
    camera.CreateFocalLengthAttr(35.0)
    camera.CreateHorizontalApertureAttr(36.0)
    camera.CreateVerticalApertureAttr(30.0)  # not the image's aspect: fitted away
    xform = UsdGeom.Xformable(camera)
    xform.AddTranslateOp().Set(Gf.Vec3d(1.0, 2.0, 9.0))
    xform.AddRotateXYZOp().Set(Gf.Vec3f(-20.0, 35.0, 10.0))
    width, height = 48, 30
    got = towards_eye(usd_camera(camera.GetPrim(), Usd.TimeCode.Default(), width / height),
                      width, height)
    to_world = camera.ComputeLocalToWorldTransform(Usd.TimeCode.Default())
    ys, xs = np.mgrid[0:height, 0:width]
    x = ((xs + 0.5) / width * 2 - 1) * 18.0 / 35.0
    y = (1 - (ys + 0.5) / height * 2) * 18.0 / 35.0 * height / width
    expected = np.array([[-np.asarray(to_world.TransformDir(Gf.Vec3d(x[r, c], y[r, c], -1.0)))
                          for c in range(width)] for r in range(height)])
    expected /= np.linalg.norm(expected, axis=-1, keepdims=True)
    assert got.shape == (height, width, 3)
    assert np.degrees(np.arccos(np.clip(np.sum(got * expected, -1), -1, 1))).max() < 1e-3
    camera.CreateProjectionAttr(UsdGeom.Tokens.orthographic)
    flat = towards_eye(usd_camera(camera.GetPrim(), Usd.TimeCode.Default(), width / height),
                       width, height)
    back = np.asarray(to_world.TransformDir(Gf.Vec3d(0.0, 0.0, 1.0)))
    assert np.abs(flat - back / np.linalg.norm(back)).max() < 1e-6


def test_lights_are_read():
    """The sample's three distant lights (UsdLux units) and an added sphere light; the
    formulas themselves are checked in tests/test_lights.py."""
    stage = Usd.Stage.Open(str(SAMPLES / "shirt.usda"))
    stage.SetEditTarget(stage.GetSessionLayer())  # the sample's own layer stays as it is
    UsdLux.SphereLight.Define(stage, "/World/Lights/bulb").CreateIntensityAttr(3.0)
    scene = StageSceneDelegate(stage)
    frame = scene.sample(1.0, 1.5)
    kinds = sorted(light.kind for light in frame.lights)
    assert kinds == ["directional", "directional", "directional", "positional"]
    key = max((light for light in frame.lights if light.kind == "directional"),
              key=lambda light: light.color[0])
    assert np.linalg.norm(key.vector) == pytest.approx(1.0)
    solid_angle = 2 * np.pi * (1 - np.cos(np.radians(0.53) / 2))
    assert key.color[0] == pytest.approx(50000 * solid_angle)


def test_texture_inside_usdz_is_read_through_ar(corpus):
    scene = StageSceneDelegate(str(corpus / "usd-wg" / "CesiumMan.usdz"), all_meshes=True)
    record = next(iter(scene.meshes.values()))
    texture = record.material.texture
    assert texture is not None and texture.shape == (1024, 1024, 4)
    assert 0.05 < texture.linear()[..., :3].mean() < 0.95  # decoded, not black or white
    st = record.material.corner_st
    assert st.shape == (len(record.topology.triangles), 3, 2)


def test_missing_texture_warns_and_renders_untextured(tmp_path):
    stage = Usd.Stage.Open(str(SAMPLES / "shirt.usda"))
    stage.SetEditTarget(stage.GetSessionLayer())  # the sample's own layer stays as it is
    tex = UsdShade.Shader(stage.GetPrimAtPath("/World/Looks/Plaid/diffuse_texture"))
    tex.GetInput("file").Set(Sdf.AssetPath("./textures/missing.png"))
    from usdwrinkle.process.log import collect

    with collect() as warnings:
        scene = StageSceneDelegate(stage)
    record = scene.meshes["/World/Arm/Sleeve"]
    assert record.material.texture is None
    assert any("missing.png" in w and "untextured" in w for w in warnings)


def test_visibility_purpose_and_animated_transforms(gl_context):
    rest, counts, indices = grid_sheet(5, 5, 1.0)
    stage = point_cache_stage(rest, {1: rest, 2: rest}, counts, indices, width=0.2)
    xform = UsdGeom.Xformable(stage.GetPrimAtPath("/Sheet"))
    op = xform.AddTranslateOp()
    op.Set(Gf.Vec3d(0, 0, 0), 1)
    op.Set(Gf.Vec3d(0.4, 0, 0), 2)
    guide = UsdGeom.Mesh.Define(stage, "/Guide")
    guide.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(rest))
    guide.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    guide.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    guide.CreatePurposeAttr(UsdGeom.Tokens.guide)
    cam = UsdGeom.Camera.Define(stage, "/cam")
    cam.AddTranslateOp().Set(Gf.Vec3d(0, 0, 5))
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        assert list(engine.meshes) == ["/Sheet"]  # guide purpose is not rendered
        centers = []
        for frame in (1.0, 2.0):
            alpha = engine.render_frame(frame, 120, 80)["color"].pixels[..., 3]
            ys, xs = np.nonzero(alpha > 0)
            centers.append(xs.mean())
        assert centers[1] - centers[0] > 5  # the translate moved the sheet right
        UsdGeom.Imageable(stage.GetPrimAtPath("/Sheet")).GetVisibilityAttr().Set(
            UsdGeom.Tokens.invisible, 2)
        assert engine.render_frame(2.0, 120, 80)["color"].pixels[..., 3].max() == 0
    finally:
        engine.release()


def test_point_cache_rest_falls_back_to_default_points():
    rest, counts, indices = grid_sheet(4, 4, 1.0)
    stage = Usd.Stage.CreateInMemory()
    mesh = UsdGeom.Mesh.Define(stage, "/M")
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(rest))
    mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(rest * 0.5), 1)
    scene = StageSceneDelegate(stage)
    record = scene.meshes["/M"]
    assert record.point_cached
    np.testing.assert_allclose(record.rest_points, rest)
    frame = scene.sample_mesh("/M", Usd.TimeCode(1), UsdGeom.XformCache(Usd.TimeCode(1)))
    np.testing.assert_allclose(frame.points, rest * 0.5)


def test_late_schema_registration_says_how_to_fix():
    code = (
        "import os; os.environ.pop('PXR_PLUGINPATH_NAME', None)\n"
        "from pxr import Usd; Usd.SchemaRegistry()\n"
        "import warnings\n"
        "with warnings.catch_warnings(record=True) as w:\n"
        "    warnings.simplefilter('always')\n"
        "    import usdwrinkle\n"
        "print('WARN', w[0].message if w else '')\n"
        "from usdwrinkle.usd import schema\n"
        "try:\n"
        "    schema.require_schema()\n"
        "except Exception as exc:\n"
        "    print('ERROR', exc)\n")
    env = {k: v for k, v in __import__("os").environ.items() if k != "PXR_PLUGINPATH_NAME"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=env, timeout=120).stdout
    assert "WARN usdwrinkle was imported after USD built its schema registry" in out
    assert "ERROR the WrinkleAPI schema is not known to USD" in out
    assert "PXR_PLUGINPATH_NAME=" in out


def test_a_repainted_texture_is_read_again(tmp_path):
    """Issue 25: load_texture's cache was keyed by name alone, so a long-running host
    (usdview) never saw a texture the artist repainted. It is keyed by the file's
    modification time and size too."""
    import os

    import OpenImageIO as oiio

    from usdwrinkle.scene.material import load_texture

    path = tmp_path / "paint.png"

    def paint(value: int, mtime: int) -> None:
        pixels = np.full((4, 4, 3), value, np.uint8)
        buf = oiio.ImageBuf(oiio.ImageSpec(4, 4, 3, oiio.UINT8))
        buf.set_pixels(oiio.ROI(), pixels)
        assert buf.write(str(path))
        os.utime(path, ns=(mtime, mtime))

    paint(10, 1_000_000_000_000_000_000)
    first = load_texture(str(path), "raw")
    assert first is load_texture(str(path), "raw")  # unchanged: the cached decode
    paint(200, 1_000_000_002_000_000_000)
    second = load_texture(str(path), "raw")
    assert int(first.pixels[0, 0, 0]) == 10 and int(second.pixels[0, 0, 0]) == 200


def test_the_stage_inputs_cache_is_bounded(tmp_path):
    """Issue 25: _INPUTS kept the inputs of every stage a process ever opened. It keeps
    the most recent INPUTS_KEPT; an evicted stage's inputs are scanned again."""
    from usdwrinkle.scene import stage as stage_module

    stages = []
    for i in range(stage_module.INPUTS_KEPT + 4):
        path = tmp_path / f"s{i}.usda"
        Usd.Stage.CreateNew(str(path)).Save()
        stages.append((path, stage_module.open_stage(str(path))))
    assert len(stage_module._INPUTS) <= stage_module.INPUTS_KEPT
    first_path, first = stages[0]
    assert first.GetRootLayer().identifier not in stage_module._INPUTS
    assert stage_module.stage_inputs(first).protects(str(first_path))


def test_a_dropped_scene_delegate_frees_its_stage_at_once():
    """The delegate and its FrameSampler make no reference cycle: a dropped delegate (and
    the stage it opened, with any unsaved edits of its layers, which a later
    Usd.Stage.Open of the same file would otherwise be given) goes with its last
    reference, not at some later garbage collection."""
    import gc
    import weakref

    gc.disable()
    try:
        scene = StageSceneDelegate(str(SAMPLES / "shirt.usda"))
        scene.sample(1.0, 1.5)
        alive = weakref.ref(scene)
        del scene
        assert alive() is None
    finally:
        gc.enable()
