"""Change tracking (scene/changes.py): an edit of the stage between two renders re-syncs
only what it touches, and the next frame equals what a fresh engine renders from the
edited stage. Syncs are counted (Mesh.sync_counts), not timed."""
from __future__ import annotations

import numpy as np
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, Vt

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.usd import schema

from conftest import grid_sheet
from helpers import point_cache_stage

WIDTH, HEIGHT = 96, 64


def squeezed_sheet() -> Usd.Stage:
    """A sheet compressed along x over frames 1..4, with a width to edit, a light and an
    unrelated prim."""
    points, counts, indices = grid_sheet(17, 17, 2.0)
    posed = {}
    for f in range(1, 5):
        p = points.copy()
        p[:, 0] *= 1.0 - 0.08 * f
        p[:, 2] = 0.02 * np.sin(3 * p[:, 1])
        posed[f] = p
    stage = point_cache_stage(points, posed, counts, indices, width=0.4)
    UsdLux.DistantLight.Define(stage, "/Key").CreateIntensityAttr(1.0)
    UsdGeom.Xform.Define(stage, "/Props").AddTranslateOp().Set(Gf.Vec3d(5, 0, 0))
    return stage


@pytest.fixture
def tracked(gl_context):
    """(stage, engine) of the squeezed sheet; the engine is released after the test."""
    stage = squeezed_sheet()
    engine = WrinkleEngine(stage, ctx=gl_context)
    yield stage, engine
    engine.release()


def render(engine, frame=3.0):
    buffers = engine.render_frame(frame, WIDTH, HEIGHT, samples=1)
    return {name: buf.pixels.copy() for name, buf in buffers.items()}


def fresh_render(stage, frame=3.0):
    """The oracle: a new engine on a copy of the edited stage."""
    copy = Usd.Stage.Open(stage.GetRootLayer())  # the same layers: the edited state
    engine = WrinkleEngine(copy)
    try:
        return render(engine, frame)
    finally:
        engine.release()


def counts(engine, path="/Sheet"):
    return engine.debug.sync_counts(path)


def assert_same(a, b):
    for name in ("color", "wrinkle.height", "normal"):
        np.testing.assert_allclose(a[name], b[name], atol=1e-5, err_msg=name)


def test_width_edit_reuploads_parameters_only(tracked):
    stage, engine = tracked
    before = render(engine)
    resources = engine.mesh_resources("/Sheet")
    synced = counts(engine)
    UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/Sheet")).GetPrimvar("wrinkle:width").Set(
        Vt.FloatArray([0.25]))
    after = render(engine)
    now = counts(engine)
    assert engine.mesh_resources("/Sheet") is resources  # not rebuilt
    assert now["resources"] == synced["resources"]
    assert now["params"] == synced["params"] + 1
    assert now["material"] == synced["material"]
    assert engine.meshes["/Sheet"].params.width[0] == pytest.approx(0.25)
    # the image changes, and is the one a fresh engine renders from the edited stage
    assert np.abs(after["wrinkle.height"] - before["wrinkle.height"]).max() > 1e-3
    assert_same(after, fresh_render(stage))


def test_topology_edit_rebuilds_the_mesh_and_restarts_history(tracked):
    stage, engine = tracked
    render(engine, 2.0)
    render(engine, 3.0)
    assert engine.debug.history_frame == 3.0
    resources = engine.mesh_resources("/Sheet")
    synced = counts(engine)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Sheet"))
    # the same quads, each split into two triangles: new faces, same surface
    quads = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 4)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]], axis=1)
    mesh.GetFaceVertexCountsAttr().Set(Vt.IntArray([3] * (2 * len(quads))))
    mesh.GetFaceVertexIndicesAttr().Set(Vt.IntArray(triangles.ravel().tolist()))
    engine.pull_changes()
    assert engine.debug.history_frame is None  # the phase history restarts
    after = render(engine, 3.0)
    assert engine.mesh_resources("/Sheet") is not resources
    assert counts(engine)["resources"] == synced["resources"] + 1
    assert len(engine.meshes["/Sheet"].topology.triangles) == 2 * len(quads)
    assert_same(after, fresh_render(stage, 3.0))


def test_unrelated_edits_resync_nothing(tracked):
    stage, engine = tracked
    render(engine, 2.0)
    render(engine, 3.0)
    synced = counts(engine)
    stage.GetPrimAtPath("/Props").CreateAttribute("userNote", Sdf.ValueTypeNames.String) \
        .Set("moved")
    UsdGeom.Xformable(stage.GetPrimAtPath("/Props")).GetOrderedXformOps()[0].Set(
        Gf.Vec3d(7, 0, 0))
    UsdLux.DistantLight(stage.GetPrimAtPath("/Key")).GetIntensityAttr().Set(2.0)
    UsdGeom.Xform.Define(stage, "/Props/New")
    bits, added, removed = engine.process_changes()
    assert (bits, added, removed) == ({}, [], [])
    render(engine, 4.0)
    now = counts(engine)
    assert {k: now[k] for k in ("resources", "params", "material")} == \
           {k: synced[k] for k in ("resources", "params", "material")}
    assert now["frame"] == synced["frame"] + 1  # the new frame only
    assert engine.debug.history_frame == 4.0  # the history went on


def test_material_edit_and_new_mesh(tracked):
    stage, engine = tracked
    render(engine)
    synced = counts(engine)
    UsdGeom.Mesh(stage.GetPrimAtPath("/Sheet")).CreateDisplayColorPrimvar().Set(
        Vt.Vec3fArray([Gf.Vec3f(0.9, 0.1, 0.1)]))
    points, counts_, indices = grid_sheet(5, 5, 0.5)
    other = UsdGeom.Mesh.Define(stage, "/Other")
    other.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points + [0, 0, 0.3]))
    other.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts_))
    other.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    after = render(engine)
    now = counts(engine)
    assert now["material"] == synced["material"] + 1
    assert now["resources"] == synced["resources"] and now["params"] == synced["params"]
    assert "/Other" in engine.rprim_paths
    assert_same(after, fresh_render(stage))
    stage.RemovePrim("/Other")
    render(engine)
    assert "/Other" not in engine.rprim_paths


def test_wrinkle_api_attribute_change_is_a_parameter_edit(tracked):
    stage, engine = tracked
    render(engine)
    synced = counts(engine)
    stage.GetPrimAtPath("/Sheet").CreateAttribute(
        schema.AMPLITUDE_SCALE, Sdf.ValueTypeNames.Float).Set(0.5)
    after = render(engine)
    assert counts(engine)["params"] == synced["params"] + 1
    assert counts(engine)["resources"] == synced["resources"]
    assert_same(after, fresh_render(stage))


def test_the_camera_and_lights_are_found_once_until_a_resync(tracked, monkeypatch):
    """Issue 25: the camera and the lights were looked up by walking the whole stage at
    every frame (and the camera three times a run). The prims are now kept until a prim
    is resynced; a light or camera added later is still seen, and equals what a fresh
    engine renders from the edited stage."""
    from usdwrinkle.scene import sampling

    stage, engine = tracked
    walks = {"camera": 0, "lights": 0}
    find_camera, light_prims = sampling.camera_mod.find_camera, sampling.light_prims

    def counted(name, function):
        def call(*args):
            walks[name] += 1
            return function(*args)
        return call

    monkeypatch.setattr(sampling.camera_mod, "find_camera", counted("camera", find_camera))
    monkeypatch.setattr(sampling, "light_prims", counted("lights", light_prims))
    for frame in (1.0, 2.0):
        render(engine, frame)
    assert walks == {"camera": 0, "lights": 1}  # the engine found the camera when made
    # values are read per frame: no walk for an intensity edit
    UsdLux.DistantLight(stage.GetPrimAtPath("/Key")).GetIntensityAttr().Set(2.0)
    intensity = render(engine, 3.0)
    assert walks == {"camera": 0, "lights": 1}
    assert_same(intensity, fresh_render(stage, 3.0))
    # a new light and a new camera: prims resynced, walked again, and both are used
    fill = UsdLux.SphereLight.Define(stage, "/Fill")
    fill.CreateIntensityAttr(3.0)
    UsdGeom.Xformable(fill).AddTranslateOp().Set(Gf.Vec3d(0, 0, 3))
    camera = UsdGeom.Camera.Define(stage, "/Cam")
    UsdGeom.Xformable(camera).AddTranslateOp().Set(Gf.Vec3d(0.3, 0, 6))
    before = dict(walks)  # fresh_render's own engine walked its stage once too
    after = render(engine, 4.0)  # the next frame: the same phase history as a fresh run
    assert walks == {"camera": before["camera"] + 1, "lights": before["lights"] + 1}
    assert engine.sample(4.0, WIDTH / HEIGHT).camera.path == "/Cam"
    assert len(engine.sample(4.0, WIDTH / HEIGHT).lights) == 2
    assert np.abs(after["color"] - intensity["color"]).max() > 0.05
    assert_same(after, fresh_render(stage, 4.0))
