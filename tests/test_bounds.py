"""render/bounds.py: the bound of a posed mesh, the sides culled and the rectangle cleared
and read back. Oracles: UsdSkel's own skinning and Pixar's baked baselines (every posed
point lies in the bound), trimesh (closed and outward), and the frame drawn with neither
shortcut (the shortcuts change no pixel)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import trimesh
from pxr import Gf, Usd, UsdGeom

from usdwrinkle.authoring.builders import usdskel_queries
from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.outputs.images import layout_for
from usdwrinkle.render import bounds as bounds_mod
from usdwrinkle.render.bounds import culled_side, eye_bound, screen_rect
from usdwrinkle.render.passes.draw import FLIP_Y
from usdwrinkle.render.request import FrameRequest
from usdwrinkle.scene.topology import closed_orientation

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


# --- closed_orientation against trimesh -------------------------------------------------

def _split_seams(mesh: trimesh.Trimesh) -> tuple[np.ndarray, np.ndarray]:
    """Every triangle its own three points (as a glTF export splits UV seams)."""
    points = mesh.vertices[mesh.faces].reshape(-1, 3)
    return points, np.arange(len(points)).reshape(-1, 3)


@pytest.mark.parametrize("shape", ["icosphere", "box", "torus", "capsule"])
def test_closed_orientation_agrees_with_trimesh(shape):
    mesh = {"icosphere": lambda: trimesh.creation.icosphere(2),
            "box": lambda: trimesh.creation.box((1, 2, 3)),
            "torus": lambda: trimesh.creation.torus(1.0, 0.3),
            "capsule": lambda: trimesh.creation.capsule(1.0, 0.5)}[shape]()
    assert mesh.is_watertight and mesh.volume > 0
    assert closed_orientation(mesh.vertices, mesh.faces) == 1
    assert closed_orientation(mesh.vertices, mesh.faces[:, ::-1]) == -1
    assert closed_orientation(*_split_seams(mesh)) == 1  # welded by position
    opened = trimesh.Trimesh(mesh.vertices, mesh.faces[1:], process=False)
    assert not opened.is_watertight
    assert closed_orientation(opened.vertices, opened.faces) == 0
    flipped = mesh.faces.copy()
    flipped[0] = flipped[0, ::-1]  # one face against its neighbours
    assert not trimesh.Trimesh(mesh.vertices, flipped, process=False).is_winding_consistent
    assert closed_orientation(mesh.vertices, flipped) == 0


def test_a_flat_or_empty_surface_is_not_closed():
    sheet = trimesh.creation.box((1, 1, 0))  # closed but encloses nothing
    assert closed_orientation(sheet.vertices, sheet.faces) == 0
    assert closed_orientation(np.zeros((0, 3)), np.zeros((0, 3), int)) == 0


# --- every posed point lies in the bound -------------------------------------------------

def _usdskel_points(engine, path, frame):
    """UsdSkel's own skinning of ``path`` at ``frame``, in the prim's space."""
    t = Usd.TimeCode(frame)
    skel_query, skinning_query = usdskel_queries(engine.stage, path)
    prim = engine.stage.GetPrimAtPath(path)
    points = UsdGeom.Mesh(prim).GetPointsAttr().Get(t)
    assert skinning_query.ComputeSkinnedPoints(skel_query.ComputeSkinningTransforms(t),
                                               points, t)
    cache = UsdGeom.XformCache(t)
    skel_to_local = (cache.GetLocalToWorldTransform(skel_query.GetSkeleton().GetPrim()) *
                     cache.GetLocalToWorldTransform(prim).GetInverse())
    return np.array([skel_to_local.Transform(p) for p in points])


def _baseline_points(baseline):
    def points(engine, path, frame):
        return np.asarray(UsdGeom.Mesh(baseline.GetPrimAtPath(path)).GetPointsAttr()
                          .Get(frame), np.float64)
    return points


BOUND_CASES = [("usd-wg/CesiumMan.usdz", (1.0, 17.0, 40.0), None),
               ("openusd-usdskel/twoBends.usda", (1.0, 12.0, 24.0), None),
               ("usd-wg/SoC-ElephantWithMonochord.usdc", (1.0, 30.0, 90.0), None),
               ("openusd-usdskel/arm.usda", (1.0, 5.0, 10.0), None),
               ("openusd-usdskel/lbs.usda", (1.0, 10.0, 20.0), "lbs.baked.usda"),
               ("openusd-usdskel/blendshapes.usda", (1.0, 41.0, 101.0),
                "blendshapes.baked.usda")]


@pytest.mark.parametrize("name,frames,baseline", BOUND_CASES, ids=[c[0] for c in BOUND_CASES])
def test_every_posed_point_lies_in_the_bound(gl_context, corpus, name, frames, baseline):
    """Depth range and screen rectangle of the bound hold UsdSkel's (or Pixar's baked)
    posed points, under a camera framing the shot; LBS assets get a bound at all."""
    engine = WrinkleEngine(str(corpus / name), all_meshes=True, ctx=gl_context)
    oracle = _usdskel_points if baseline is None else _baseline_points(
        Usd.Stage.Open(str(corpus / "openusd-usdskel" / "baseline" / baseline)))
    width, height = 320, 180
    checked = 0
    try:
        for frame in frames:
            record = engine.sample(frame, width / height)
            view, eye_to_clip = record.camera.view, record.camera.projection @ FLIP_Y
            for path, mesh in engine.meshes.items():
                if mesh.skin is None:
                    continue
                pose = record.meshes[path]
                bound = eye_bound(mesh, pose, view)
                assert bound is not None, f"{path}: LBS with convex weights has a bound"
                posed = oracle(engine, path, frame)
                eye = np.c_[posed, np.ones(len(posed))] @ pose.local_to_world @ view
                near, far = bound.depth_range()
                depth = -eye[:, 2]
                assert near <= depth.min() + 1e-9 and depth.max() <= far + 1e-9, \
                    (path, frame, near, far, depth.min(), depth.max())
                rect = screen_rect([bound], eye_to_clip, width, height)
                if rect is None:  # reaches behind the camera: the whole frame
                    continue
                clip = eye @ eye_to_clip
                px = (clip[:, 0] / clip[:, 3] + 1) * 0.5 * width
                py = (clip[:, 1] / clip[:, 3] + 1) * 0.5 * height
                inside = (px >= rect[0]) & (px <= rect[2]) & (py >= rect[1]) & (py <= rect[3])
                on_screen = (px >= 0) & (px <= width) & (py >= 0) & (py <= height)
                assert np.all(inside | ~on_screen), (path, frame, rect)
                checked += 1
    finally:
        engine.release()
    assert checked >= len(frames)


def test_the_rectangle_of_a_closely_framed_figure_is_a_fraction_of_the_frame(
        gl_context, corpus, tmp_path):
    """The point of the rectangle: CesiumMan, framed as the bench's peer shot frames him,
    leaves most of a 960x540 frame neither cleared nor read."""
    from benchmarks.peers import CAMERA, HEIGHT, WIDTH, closely_framed

    stage = closely_framed(corpus, tmp_path)
    engine = WrinkleEngine(str(stage), all_meshes=True, ctx=gl_context, camera=CAMERA)
    try:
        for frame in (1.0, 12.0, 24.0):
            record = engine.sample(frame, WIDTH / HEIGHT)
            found = [eye_bound(mesh, record.meshes[path], record.camera.view)
                     for path, mesh in engine.meshes.items()]
            x0, y0, x1, y1 = screen_rect(found, record.camera.projection @ FLIP_Y, WIDTH,
                                         HEIGHT)
            assert (x1 - x0) * (y1 - y0) < 0.4 * WIDTH * HEIGHT, (frame, (x0, y0, x1, y1))
            (path, mesh), = engine.meshes.items()
            assert culled_side(mesh, record.meshes[path], record.camera, found[0]) == "back"
    finally:
        engine.release()


# --- what may be culled -------------------------------------------------------------------

def _sphere_stage(tmp_path, inward=False, double_sided=False, opacity=1.0, scale=1.0,
                  near=0.1, distance=4.0):
    stage = Usd.Stage.CreateNew(str(tmp_path / "sphere.usda"))
    ico = trimesh.creation.icosphere(2)
    faces = ico.faces[:, ::-1] if inward else ico.faces
    mesh = UsdGeom.Mesh.Define(stage, "/Sphere")
    mesh.CreatePointsAttr([Gf.Vec3f(*p) for p in ico.vertices])
    mesh.CreateFaceVertexCountsAttr([3] * len(faces))
    mesh.CreateFaceVertexIndicesAttr(faces.reshape(-1).tolist())
    mesh.CreateDoubleSidedAttr(double_sided)
    mesh.CreateDisplayOpacityAttr([opacity])
    mesh.AddScaleOp().Set(Gf.Vec3f(scale, 1.0, 1.0))
    camera = UsdGeom.Camera.Define(stage, "/Camera")
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 0, distance))
    camera.CreateClippingRangeAttr(Gf.Vec2f(near, 100.0))
    stage.Save()
    return stage.GetRootLayer().realPath


@pytest.mark.parametrize("case, side", [
    ({}, "back"),
    ({"inward": True}, "front"),           # wound inward: the front faces are the hidden ones
    ({"scale": -1.0}, "front"),            # a mirroring transform turns the winding
    ({"inward": True, "scale": -1.0}, "back"),
    ({"double_sided": True}, None),
    ({"opacity": 0.5}, None),              # translucent: its inside shows
    ({"near": 3.5}, None),                 # the near plane opens it
    ({"distance": 0.5, "near": 0.01}, None),  # the camera inside it
])
def test_only_a_side_that_no_camera_sees_is_culled(gl_context, tmp_path, case, side):
    engine = WrinkleEngine(_sphere_stage(tmp_path, **case), all_meshes=True, ctx=gl_context,
                           camera="/Camera")
    try:
        record = engine.sample(1.0, 1.0)
        (path, mesh), = engine.meshes.items()
        bound = eye_bound(mesh, record.meshes[path], record.camera.view)
        assert culled_side(mesh, record.meshes[path], record.camera, bound) == side
    finally:
        engine.release()


# --- the shortcuts change no pixel --------------------------------------------------------

def _frames(path, frames, width, height, suffix, **engine_args):
    engine = WrinkleEngine(str(path), **engine_args)
    try:
        out = []
        for frame in frames:
            image = engine.render(frame, FrameRequest(width, height,
                                                      layout=layout_for("x" + suffix)))
            out.append({name: plane.copy() for name, plane in image.planes.items()})
            image.release()
        return out
    finally:
        engine.release()


IDENTITY_CASES = [("shirt", SAMPLES / "shirt.usda", (1.0, 24.0), {}),
                  ("pillow", SAMPLES / "pillow.usda", (1.0, 12.0), {}),
                  ("CesiumMan", "usd-wg/CesiumMan.usdz", (1.0, 20.0), {"all_meshes": True}),
                  ("elephant", "usd-wg/SoC-ElephantWithMonochord.usdc", (30.0,),
                   {"all_meshes": True})]


@pytest.mark.parametrize("suffix, width", [(".png", 320), (".exr", 321), (".exr", 320)])
@pytest.mark.parametrize("name, path, frames, args", IDENTITY_CASES,
                         ids=[c[0] for c in IDENTITY_CASES])
def test_the_rectangle_changes_no_pixel(gl_context, corpus, monkeypatch, name, path, frames,
                                        args, suffix, width):
    """Each frame equals, bit for bit, the one with the whole frame cleared and read
    (odd and even widths: EXR's pixel pairs)."""
    path = path if isinstance(path, Path) else corpus / path
    fast = _frames(path, frames, width, 181, suffix, ctx=gl_context, **args)
    monkeypatch.setattr("usdwrinkle.render.delegate.screen_rect", lambda *a: None)
    whole = _frames(path, frames, width, 181, suffix, ctx=gl_context, **args)
    for frame, a, b in zip(frames, fast, whole, strict=True):
        for plane in a:
            same = a[plane].view(np.uint8) == b[plane].view(np.uint8)
            assert same.all(), (frame, plane, int((~same).sum()))


@pytest.mark.parametrize("name, path, frames, args", IDENTITY_CASES,
                         ids=[c[0] for c in IDENTITY_CASES])
def test_culling_changes_almost_no_pixel(gl_context, corpus, monkeypatch, name, path, frames,
                                         args):
    """Against the frame with both sides of every mesh drawn (as Storm draws them), at
    most 0.5% of the covered pixels differ: where a skinned closed mesh's back faces
    show through the cracks between its seam-split corners (CesiumMan: 9 of his 2,496 pixels
    by up to 9/255), which Storm draws unlit."""
    path = path if isinstance(path, Path) else corpus / path
    fast = _frames(path, frames, 320, 181, ".png", ctx=gl_context, **args)
    culled = []

    def spy(*a):
        culled.append(bounds_mod.culled_side(*a))
        return None

    monkeypatch.setattr("usdwrinkle.render.passes.draw.culled_side", spy)
    both = _frames(path, frames, 320, 181, ".png", ctx=gl_context, **args)
    for frame, a, b in zip(frames, fast, both, strict=True):
        a, b = a["RGBA"].astype(int), b["RGBA"].astype(int)
        covered = int((b[..., 3] > 0).sum())
        differ = np.any(a != b, axis=-1)
        assert covered > 500 and differ.sum() <= 0.005 * covered, (frame, int(differ.sum()))
        assert np.abs(a - b).mean() < 0.01, frame
    if name == "CesiumMan":  # the case exercises culling: his closed body is culled
        assert culled and set(culled) == {"back"}, culled


def test_weld_ids_partition_points_as_numpy_unique_does():
    """Issue 42, finding 11: the weld of closed_orientation used np.unique over rows (11 s
    of a 2-million-triangle fan's 45 s). weld_ids must group exactly the points np.unique
    groups, -0 with 0 included."""
    from usdwrinkle.scene.topology import weld_ids

    rng = np.random.default_rng(3)
    points = rng.integers(-3, 3, (5000, 3)).astype(np.float32) * 0.5
    points[::7, 1] = -0.0
    points[1::7, 1] = 0.0
    ids = weld_ids(points)
    _, want = np.unique(points + np.float32(0), axis=0, return_inverse=True)
    want = want.reshape(-1)
    # the same partition: equal ids exactly where numpy's ids are equal
    pairs = set(zip(ids.tolist(), want.tolist(), strict=True))
    assert len(pairs) == len(set(ids.tolist())) == len(set(want.tolist())) < 5000
