"""Lights and surfaces as usdview's Storm shades them (issue 24), checked against the
UsdLux definitions and a numpy transcription of Storm's formulas (OpenUSD 25.08:
hdSt/light.cpp, usdShaders/previewSurface.glslfx, glf/simpleLighting.glslfx).

tests/test_realclients.py compares whole frames with Storm itself where bpy is present.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.scene.lights import (
    CONSTANT_SH,
    IRRADIANCE_BANDS,
    blackbody_rgb,
    latlong_directions,
    project_sh9,
    read_lights,
    sh9_basis,
)
from usdwrinkle.scene.stage import StageSceneDelegate

SUN_SOLID_ANGLE = 2 * math.pi * (1 - math.cos(math.radians(0.53) / 2))


def lights_of(stage):
    return read_lights(stage, Usd.TimeCode.Default(), UsdGeom.XformCache())


def one_light(kind, **inputs):
    stage = Usd.Stage.CreateInMemory()
    light = getattr(UsdLux, kind).Define(stage, "/L")
    for name, value in inputs.items():
        light.GetPrim().GetAttribute(f"inputs:{name}").Set(value)
    return stage, light


def test_a_distant_light_gives_its_radiance_times_its_solid_angle():
    stage, light = one_light("DistantLight", intensity=50000.0, color=Gf.Vec3f(1, 0.5, 0.25))
    light.AddRotateXOp().Set(-90.0)  # shining down -Y: towards the light is +Y
    (record,) = lights_of(stage)
    assert record.kind == "directional"
    np.testing.assert_allclose(record.color, [50000 * SUN_SOLID_ANGLE * c for c in (1, .5, .25)],
                               rtol=1e-6)
    np.testing.assert_allclose(record.vector, [0, 1, 0], atol=1e-9)
    stage, light = one_light("DistantLight", intensity=2.0, angle=10.0, normalize=True)
    np.testing.assert_allclose(lights_of(stage)[0].color, 2.0)  # normalize: no solid angle


def test_lights_are_read_once_unless_they_vary_or_the_stage_is_edited():
    """Issue 45: the lights were read at every frame (a third of the paper's shirt frame on
    a GPU node). Lights that do not vary are kept; an animated intensity, an animated
    parent transform and an edit of the stage are each seen at the next frame."""
    stage, light = one_light("SphereLight", intensity=2.0, normalize=True)
    parent = UsdGeom.Xform.Define(stage, "/Rig")
    animated = UsdLux.DistantLight.Define(stage, "/Rig/Key")
    animated.CreateIntensityAttr(1.0).Set(3.0)
    scene = StageSceneDelegate(stage)

    def colours(frame):
        return sorted(float(record.color[0]) for record in scene.sample(frame, 1.0).lights)

    sun = SUN_SOLID_ANGLE
    assert colours(1.0) == pytest.approx(sorted([2.0, 3.0 * sun]))
    first = scene.sample(1.0, 1.0).lights
    assert scene.sample(2.0, 1.0).lights[0] is first[0]  # kept: nothing varies
    light.GetIntensityAttr().Set(4.0)  # an edit (the paint window's, usdview's)
    assert colours(2.0) == pytest.approx(sorted([4.0, 3.0 * sun]))
    animated.GetIntensityAttr().Set(3.0, 1.0)
    animated.GetIntensityAttr().Set(5.0, 2.0)  # now animated: read at every frame
    assert colours(1.0) == pytest.approx(sorted([4.0, 3.0 * sun]))
    assert colours(2.0) == pytest.approx(sorted([4.0, 5.0 * sun]))
    animated.GetIntensityAttr().Clear()
    animated.GetIntensityAttr().Set(3.0)
    rotate = parent.AddRotateXOp()  # the rig turns: the light's direction varies
    rotate.Set(0.0, 1.0)
    rotate.Set(90.0, 2.0)
    directions = {frame: next(r for r in scene.sample(frame, 1.0).lights
                              if r.kind == "directional").vector for frame in (1.0, 2.0)}
    np.testing.assert_allclose(directions[1.0], [0, 0, 1], atol=1e-9)
    np.testing.assert_allclose(directions[2.0], [0, -1, 0], atol=1e-9)
    assert colours(None) == pytest.approx(sorted([4.0, 3.0 * sun]))  # the default time


def test_a_camera_is_read_once_unless_it_varies_or_the_stage_is_edited():
    """Issue 45, as the lights: a still camera is kept; an edit of its lens, and an
    animated transform of a prim above it, are seen at the next frame."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.Mesh.Define(stage, "/M").CreatePointsAttr([(0, 0, 0), (1, 0, 0), (0, 1, 0)])
    rig = UsdGeom.Xform.Define(stage, "/Rig")
    camera = UsdGeom.Camera.Define(stage, "/Rig/Cam")
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 0, 10))
    scene = StageSceneDelegate(stage)

    def sample(frame):
        return scene.sample(frame, 1.0, "/Rig/Cam").camera

    first = sample(1.0)
    assert sample(2.0) is first  # kept: nothing varies
    camera.GetFocalLengthAttr().Set(100.0)  # an edit: a longer lens
    zoomed = sample(2.0)
    assert zoomed.projection[0, 0] == pytest.approx(first.projection[0, 0] * 100 / 50)
    translate = rig.AddTranslateOp()  # the rig moves: the camera varies
    translate.Set(Gf.Vec3d(0, 0, 0), 1.0)
    translate.Set(Gf.Vec3d(0, 5, 0), 2.0)
    np.testing.assert_allclose(sample(1.0).position, [0, 0, 10], atol=1e-9)
    np.testing.assert_allclose(sample(2.0).position, [0, 5, 10], atol=1e-9)


@pytest.mark.parametrize("kind, inputs, area", [
    ("SphereLight", {"radius": 0.25}, math.pi * 0.0625),
    ("DiskLight", {"radius": 2.0}, math.pi * 4.0),
    ("RectLight", {"width": 3.0, "height": 0.5}, 1.5),
    ("CylinderLight", {"length": 4.0, "radius": 0.5}, 2.0),
])
def test_area_lights_give_radiance_times_area_and_fall_off(kind, inputs, area):
    stage, light = one_light(kind, intensity=10.0, exposure=2.0, **inputs)
    light.AddTranslateOp().Set(Gf.Vec3d(1, 2, 3))
    (record,) = lights_of(stage)
    assert record.kind == "positional" and record.attenuate
    np.testing.assert_allclose(record.color, 10.0 * 4.0 * area, rtol=1e-6)
    np.testing.assert_allclose(record.vector, [1, 2, 3])
    shaped = kind in ("RectLight", "DiskLight")  # they light the cone about their -Z
    assert record.spot_cutoff == (90.0 if shaped else 180.0)


def test_exposure_is_clamped_and_colour_temperature_keeps_luminance():
    stage, _ = one_light("SphereLight", intensity=1.0, exposure=80.0, normalize=True)
    np.testing.assert_allclose(lights_of(stage)[0].color, 2.0 ** 50)  # Storm's +-50 stops
    luma = np.array([0.2126, 0.7152, 0.0722])
    for kelvin in (2000.0, 3200.0, 6500.0, 9000.0):
        assert float(blackbody_rgb(kelvin) @ luma) == pytest.approx(1.0, rel=1e-9)
    warm, daylight, cool = blackbody_rgb(3200.0), blackbody_rgb(6500.0), blackbody_rgb(9000.0)
    assert warm[0] > warm[1] > warm[2] and cool[2] > cool[0]
    assert np.ptp(daylight) < 0.12  # 6500 K is about white in Rec.709 (D65)
    stage, _ = one_light("SphereLight", intensity=1.0, normalize=True,
                         enableColorTemperature=True, colorTemperature=3200.0)
    np.testing.assert_allclose(lights_of(stage)[0].color, warm)


def test_invisible_lights_are_off_and_a_stage_without_lights_gets_the_camera_light():
    stage, light = one_light("DistantLight")
    light.MakeInvisible()
    assert lights_of(stage) == []
    mesh = UsdGeom.Mesh.Define(stage, "/Quad")
    mesh.CreatePointsAttr([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    frame = StageSceneDelegate(stage).sample(None, 1.0)
    (camera,) = frame.lights
    assert camera.kind == "positional" and not camera.attenuate
    np.testing.assert_allclose(camera.color, math.pi)
    np.testing.assert_allclose(camera.vector, frame.camera.position)


def test_sh9_irradiance_of_a_sky_against_numerical_integration():
    """The dome's SH9 irradiance (shaders/include/surface.glsl: sh9 with the irradiance
    band weights) against the irradiance integrated over the lat-long map itself."""
    height, width = 64, 128
    directions, solid_angle = latlong_directions(width, height)
    sky = np.where(directions[..., 1:2] > 0, 1.0, 0.1) * np.array([0.6, 0.8, 1.0])
    sky *= 1.0 + 0.5 * np.clip(directions[..., 0:1], 0, None)  # brighter towards +X
    coefficients = project_sh9(sky, np.eye(3))
    flat_d, flat_w, flat_l = directions.reshape(-1, 3), solid_angle.reshape(-1), sky.reshape(-1, 3)
    for normal in ([0, 1, 0], [1, 0, 0], [0, -1, 0], [0.6, 0.0, 0.8]):
        n = np.asarray(normal, float) / np.linalg.norm(normal)
        exact = (np.clip(flat_d @ n, 0, None) * flat_w) @ flat_l / math.pi
        approximated = (sh9_basis(n[None]) * IRRADIANCE_BANDS) @ coefficients
        np.testing.assert_allclose(approximated[0], exact, rtol=0.1, atol=0.02)
    constant = (sh9_basis(np.array([[0.3, 0.4, 0.866]])) * IRRADIANCE_BANDS) @ CONSTANT_SH
    np.testing.assert_allclose(constant, 1.0, rtol=1e-5)  # a constant dome of radiance 1


# -- surfaces ----------------------------------------------------------------------------
def quad_stage(material: dict | None, light_rotation=None, display=(0.5, 0.5, 0.5)):
    """A quad facing +Z seen head-on from z = 5, lit by a sun (or by nothing)."""
    stage = Usd.Stage.CreateInMemory()
    UsdGeom.SetStageUpAxis(stage, "Y")
    camera = UsdGeom.Camera.Define(stage, "/Cam")
    camera.AddTranslateOp().Set(Gf.Vec3d(0, 0, 5))
    camera.CreateFocalLengthAttr(50.0)
    camera.CreateHorizontalApertureAttr(20.955)
    camera.CreateVerticalApertureAttr(20.955)
    mesh = UsdGeom.Mesh.Define(stage, "/Quad")
    mesh.CreatePointsAttr([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)])
    mesh.CreateFaceVertexCountsAttr([4])
    mesh.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    mesh.CreateSubdivisionSchemeAttr("none")
    mesh.CreateDisplayColorAttr([display])
    if material is not None:
        look = UsdShade.Material.Define(stage, "/Look")
        shader = UsdShade.Shader.Define(stage, "/Look/Surface")
        shader.CreateIdAttr("UsdPreviewSurface")
        for name, value in material.items():
            kind = Sdf.ValueTypeNames.Color3f if isinstance(value, tuple) else \
                Sdf.ValueTypeNames.Int if isinstance(value, int) else Sdf.ValueTypeNames.Float
            shader.CreateInput(name, kind).Set(value)
        look.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
        UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(look)
    if light_rotation is not None:
        sun = UsdLux.DistantLight.Define(stage, "/Sun")
        sun.AddRotateXYZOp().Set(Gf.Vec3f(*light_rotation))
    return stage


def storm_preview(diffuse, n, e, to_light, irradiance, roughness=0.5, metallic=0.0, ior=1.5,
                  specular_workflow=False, specular_color=(0, 0, 0), clearcoat=0.0,
                  clearcoat_roughness=0.01):
    """previewSurface.glslfx's evaluateLight for one light, in numpy."""
    diffuse = np.asarray(diffuse, float)
    h = (e + to_light) / np.linalg.norm(e + to_light)
    n_l, n_e, n_h, e_h = (max(0.0, float(np.dot(a, b))) for a, b in
                          ((n, to_light), (n, e), (n, h), (e, h)))
    fresnel = max(0.0, 1.0 - e_h) ** 5

    def lobe(f0, f90, rough):
        rough = max(0.001, rough)
        alpha2 = rough ** 4
        d = (alpha2 + 0.001) / (math.pi * (n_h * n_h * (alpha2 - 1) + 1) ** 2)
        k = rough * rough / 2
        g = n_e / (n_e * (1 - k) + k) * n_l / (n_l * (1 - k) + k)
        return (f0 + (f90 - f0) * fresnel) * g * d / (4 * n_l * n_e + 0.001)

    r = (1 - ior) / (1 + ior)
    f0, f90, d = np.asarray(specular_color, float), np.ones(3), diffuse / math.pi
    if not specular_workflow:
        spec_color = 1.0 + (diffuse - 1.0) * metallic
        f0 = r * r * spec_color * (1 - metallic) + spec_color * metallic
        f90 = spec_color
        d = d * (1 - metallic)
    s = lobe(f0, f90, roughness)
    d = d * (1 - (f0 + (f90 - f0) * fresnel))
    if clearcoat > 0:
        s = s + clearcoat * lobe(np.full(3, r * r), np.ones(3), clearcoat_roughness)
    return n_l * (d + s) * irradiance


@pytest.mark.parametrize("material", [
    {"diffuseColor": (0.5, 0.5, 0.5)},
    {"diffuseColor": (0.8, 0.3, 0.2), "roughness": 0.2},
    {"diffuseColor": (0.9, 0.6, 0.2), "metallic": 1.0, "roughness": 0.35},
    {"diffuseColor": (0.2, 0.5, 0.3), "useSpecularWorkflow": 1,
     "specularColor": (0.3, 0.3, 0.8), "roughness": 0.4},
    {"diffuseColor": (0.4, 0.4, 0.6), "clearcoat": 1.0, "clearcoatRoughness": 0.1},
])
def test_preview_surface_is_storms(gl_context, material):
    """The quad's centre under a sun 35 degrees off the view, against evaluateLight."""
    stage = quad_stage(material, light_rotation=(35.0, 0.0, 0.0))
    engine = WrinkleEngine(stage, ctx=gl_context, camera="/Cam")
    try:
        color = engine.render_frame(None, 65, 65, wrinkles=False, samples=1)["color"]
    finally:
        engine.release()
    to_light = np.array([0.0, -math.sin(math.radians(35)), math.cos(math.radians(35))])
    expected = storm_preview(
        material["diffuseColor"], np.array([0, 0, 1.0]), np.array([0, 0, 1.0]), to_light,
        50000 * SUN_SOLID_ANGLE, roughness=material.get("roughness", 0.5),
        metallic=material.get("metallic", 0.0),
        specular_workflow=bool(material.get("useSpecularWorkflow", 0)),
        specular_color=material.get("specularColor", (0, 0, 0)),
        clearcoat=material.get("clearcoat", 0.0),
        clearcoat_roughness=material.get("clearcoatRoughness", 0.01))
    np.testing.assert_allclose(color.pixels[32, 32, :3], expected, rtol=2e-4, atol=1e-5)


def test_the_fallback_surface_is_storms_simple_lighting(gl_context):
    """No material: displayColor x Lambert / 3.1415, a Blinn lobe (shininess 32, 0.1)
    with a directional viewer, and the ambient terms (glf simpleLighting)."""
    for rotation, display in (((35.0, 0.0, 0.0), (0.25, 0.5, 0.75)), (None, (0.5, 0.5, 0.5))):
        engine = WrinkleEngine(quad_stage(None, rotation, display), ctx=gl_context,
                               camera="/Cam")
        try:
            pixel = engine.render_frame(None, 65, 65, wrinkles=False,
                                        samples=1)["color"].pixels[32, 32, :3]
        finally:
            engine.release()
        if rotation is None:  # usdview's camera light: head-on, c = pi, ambient 0.01
            c, n_l, n_h, ambient = math.pi, 1.0, 1.0, 0.01
        else:
            c, ambient = 50000 * SUN_SOLID_ANGLE, 0.0
            n_l = math.cos(math.radians(35))
            h = np.array([0.0, -math.sin(math.radians(35)), 1 + math.cos(math.radians(35))])
            n_h = float(h[2] / np.linalg.norm(h))
        expected = 0.002 + ambient * 0.2 + c * n_l / 3.1415 * np.asarray(display) + \
            c * n_h ** 32 / 3.1415 * 0.1
        np.testing.assert_allclose(pixel, expected, rtol=2e-4)


def test_a_per_vertex_display_color_is_shaded_per_corner(gl_context):
    """A displayColor that varies over the mesh is interpolated across each triangle, as
    Storm's fallback surface does (usdwrinkle drew the first colour everywhere): red on
    the quad's left edge, blue on its right, so a pixel's colour is the linear mix at its
    x, through glf's simple lighting as in the test above."""
    stage = quad_stage(None, (35.0, 0.0, 0.0))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Quad"))
    red, blue = np.array([0.9, 0.1, 0.1]), np.array([0.1, 0.2, 0.8])
    primvar = mesh.CreateDisplayColorPrimvar(UsdGeom.Tokens.vertex)
    primvar.Set([Gf.Vec3f(*red), Gf.Vec3f(*blue), Gf.Vec3f(*blue), Gf.Vec3f(*red)])
    engine = WrinkleEngine(stage, ctx=gl_context, camera="/Cam")
    try:
        color = engine.render_frame(None, 65, 65, wrinkles=False,
                                    samples=1)["color"].pixels
    finally:
        engine.release()
    c = 50000 * SUN_SOLID_ANGLE
    n_l = math.cos(math.radians(35))
    h = np.array([0.0, -math.sin(math.radians(35)), 1 + math.cos(math.radians(35))])
    n_h = float(h[2] / np.linalg.norm(h))
    half_width = 5 * 20.955 / 2 / 50   # at the quad's distance
    for column in (10, 32, 50):
        x = ((column + 0.5) / 65 * 2 - 1) * half_width
        display = red + (blue - red) * (x + 1) / 2
        expected = 0.002 + c * n_l / 3.1415 * display + c * n_h ** 32 / 3.1415 * 0.1
        np.testing.assert_allclose(color[32, column, :3], expected, rtol=2e-3)


def test_a_time_sampled_display_color_is_read_each_frame(gl_context):
    """A displayColor with time samples (the display-colour bake layer's) is shaded
    with each frame's own values."""
    stage = quad_stage(None, (35.0, 0.0, 0.0))
    primvar = UsdGeom.Mesh(stage.GetPrimAtPath("/Quad")).CreateDisplayColorPrimvar(
        UsdGeom.Tokens.vertex)
    primvar.GetAttr().ClearDefault()  # quad_stage's one constant colour
    colours = {1.0: (0.9, 0.1, 0.1), 2.0: (0.1, 0.2, 0.8)}
    for frame, colour in colours.items():
        primvar.Set([Gf.Vec3f(*colour)] * 4, frame)
    engine = WrinkleEngine(stage, ctx=gl_context, camera="/Cam")
    try:
        pixels = {frame: engine.render_frame(frame, 65, 65, wrinkles=False,
                                             samples=1)["color"].pixels[32, 32, :3].copy()
                  for frame in (1.0, 2.0, 1.0)}
    finally:
        engine.release()
    ratio = {frame: pixels[frame][0] / pixels[frame][2] for frame in pixels}
    assert ratio[1.0] > 3.0 and ratio[2.0] < 0.6, ratio


@pytest.mark.parametrize("size", [(1, 1), (2, 1), (2, 2), (3, 5), (64, 32), (256, 128)])
def test_a_uniform_sky_lights_alike_at_any_texture_size(size):
    """Issue 54, finding 8: a 1x1 dome texture lit a scene 6.5x too bright and a 2x2 one
    0.4x, against the same uniform sky at 64x32 (the SH basis sampled at one row of texel
    centres, with sin(theta) d(theta) as its solid angle)."""
    width, height = size
    sky = np.ones((height, width, 3)) * [0.2, 0.5, 1.0]
    coefficients = project_sh9(sky, np.eye(3))
    for normal in ([0, 1, 0], [1, 0, 0], [0, -1, 0], [0.6, 0.0, 0.8], [0, 0, 1]):
        n = np.asarray(normal, float) / np.linalg.norm(normal)
        irradiance = (sh9_basis(n[None]) * IRRADIANCE_BANDS) @ coefficients
        np.testing.assert_allclose(irradiance[0], [0.2, 0.5, 1.0], rtol=2e-3)
    _, solid_angle = latlong_directions(width, height)
    assert solid_angle.sum() == pytest.approx(4 * math.pi, rel=1e-12)
