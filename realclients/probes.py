"""Probe stages for the lights and surfaces the sample stages do not exercise: a sphere
with authored normals on a floor, seen by a camera, under one kind of light each.

    python -m realclients.probes OUT_FOLDER      # write them (and the sky texture)
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

#: name -> (material inputs, light maker name, what it checks)
PROBES = {
    "rect": ({}, "rect", "a rect light: area width x height, 1/d^2, its 90-degree cone"),
    "disk_shaped": ({}, "disk_shaped", "a disk light with a 25-degree cone and focus 2"),
    "sphere_warm": ({}, "sphere_warm", "a sphere light at 3000 K (colour temperature)"),
    "sun_cool": ({}, "sun_cool", "a distant light at 9000 K"),
    "clipped": ({}, "clipped", "a camera whose near plane cuts the sphere"),
    "glossy": ({"diffuseColor": (0.8, 0.25, 0.2), "roughness": 0.2, "clearcoat": 1.0,
                "clearcoatRoughness": 0.05}, "sun", "a glossy clearcoat under a sun"),
    "metal": ({"diffuseColor": (0.9, 0.7, 0.3), "metallic": 1.0, "roughness": 0.3}, "sun",
              "a metal under a sun"),
    "sky_diffuse": ({}, "sky", "a textured dome (lat-long EXR) on a diffuse surface"),
    "sky_metal": ({"diffuseColor": (0.9, 0.7, 0.3), "metallic": 1.0, "roughness": 0.3},
                  "sky", "a textured dome reflected by a metal"),
    "translucent": ({"diffuseColor": (0.8, 0.2, 0.2), "opacity": 0.4}, "sun",
                    "a translucent sphere over an opaque floor"),
    "plain_dome": ({}, "plain_dome", "a dome without a texture (Storm ignores it)"),
    "headlight_glossy": ({"diffuseColor": (0.4, 0.2, 0.6), "roughness": 0.3}, "none",
                         "no light: usdview's head-light on a glossy preview surface"),
}


def write_sky(path: Path, height: int = 64, width: int = 128) -> None:
    """A lat-long sky (Storm's convention): blue above, warm ground, a bright sun."""
    import OpenImageIO as oiio

    from usdwrinkle.scene.lights import latlong_directions

    directions, _ = latlong_directions(width, height)
    up = directions[..., 1:2]
    sky = np.where(up > 0, np.array([0.5, 0.7, 1.0]) * (0.6 + 0.4 * up),
                   np.array([0.35, 0.25, 0.15]))
    sun = np.array([0.5, 0.6, 0.62]) / np.linalg.norm([0.5, 0.6, 0.62])
    sky = sky + 3.0 * np.exp(-8 * np.sum((directions - sun) ** 2, -1))[..., None]
    buf = oiio.ImageBuf(oiio.ImageSpec(width, height, 3, "float"))
    buf.set_pixels(oiio.ROI(), sky.astype(np.float32))
    buf.write(str(path))


def _sphere(stage, path, segments=48, rings=24):
    from pxr import UsdGeom

    mesh = UsdGeom.Mesh.Define(stage, path)
    points = []
    for j in range(rings + 1):
        theta = math.pi * j / rings
        for i in range(segments):
            phi = 2 * math.pi * i / segments
            points.append((math.sin(theta) * math.cos(phi), math.cos(theta),
                           math.sin(theta) * math.sin(phi)))
    indices = []
    for j in range(rings):
        for i in range(segments):
            a, b = j * segments + i, j * segments + (i + 1) % segments
            indices += [a, a + segments, b + segments, b]
    mesh.CreatePointsAttr(points)
    mesh.CreateFaceVertexCountsAttr([4] * (len(indices) // 4))
    mesh.CreateFaceVertexIndicesAttr(indices)
    mesh.CreateSubdivisionSchemeAttr("none")
    mesh.CreateNormalsAttr(points)  # a unit sphere's normals are its points
    mesh.SetNormalsInterpolation("vertex")
    return mesh


def _material(stage, path, inputs: dict):
    from pxr import Sdf, UsdShade

    material = UsdShade.Material.Define(stage, path)
    shader = UsdShade.Shader.Define(stage, f"{path}/Surface")
    shader.CreateIdAttr("UsdPreviewSurface")
    for name, value in inputs.items():
        kind = Sdf.ValueTypeNames.Color3f if isinstance(value, tuple) else \
            Sdf.ValueTypeNames.Int if isinstance(value, int) else Sdf.ValueTypeNames.Float
        shader.CreateInput(name, kind).Set(value)
    material.CreateSurfaceOutput().ConnectToSource(shader.ConnectableAPI(), "surface")
    return material


def _light(stage, kind: str):
    from pxr import Gf, UsdLux

    def aim(light, eye):
        look = Gf.Matrix4d().SetLookAt(Gf.Vec3d(*eye), Gf.Vec3d(0, 0, 0), Gf.Vec3d(0, 1, 0))
        light.AddTransformOp().Set(look.GetInverse())

    if kind in ("sun", "clipped", "sun_cool"):
        sun = UsdLux.DistantLight.Define(stage, "/Lights/Sun")
        sun.AddRotateXYZOp().Set(Gf.Vec3f(-50.0, 30.0, 0.0))
        if kind == "sun_cool":
            sun.CreateEnableColorTemperatureAttr(True)
            sun.CreateColorTemperatureAttr(9000.0)
    elif kind == "rect":
        rect = UsdLux.RectLight.Define(stage, "/Lights/Rect")
        rect.CreateIntensityAttr(30.0)
        rect.CreateWidthAttr(1.0)
        rect.CreateHeightAttr(0.5)
        aim(rect, (1.5, 2.5, 1.5))
    elif kind == "disk_shaped":
        disk = UsdLux.DiskLight.Define(stage, "/Lights/Disk")
        disk.CreateIntensityAttr(60.0)
        disk.CreateRadiusAttr(0.3)
        shaping = UsdLux.ShapingAPI.Apply(disk.GetPrim())
        shaping.CreateShapingConeAngleAttr(25.0)
        shaping.CreateShapingFocusAttr(2.0)
        aim(disk, (-1.0, 3.0, 1.0))
    elif kind == "sphere_warm":
        bulb = UsdLux.SphereLight.Define(stage, "/Lights/Bulb")
        bulb.CreateIntensityAttr(40.0)
        bulb.CreateRadiusAttr(0.2)
        bulb.CreateEnableColorTemperatureAttr(True)
        bulb.CreateColorTemperatureAttr(3000.0)
        bulb.AddTranslateOp().Set(Gf.Vec3d(1.2, 1.8, 1.5))
    elif kind == "sky":
        UsdLux.DomeLight.Define(stage, "/Lights/Sky").CreateTextureFileAttr("./sky.exr")
    elif kind == "plain_dome":
        UsdLux.DomeLight.Define(stage, "/Lights/Dome")
        _light(stage, "sun")
    # "none": no light at all (both renderers add the camera's head-light)


def write_probe(folder: Path, name: str) -> Path:
    """Write probe ``name`` (PROBES) into ``folder``; returns its path."""
    from pxr import Gf, Usd, UsdGeom, UsdShade

    import usdwrinkle  # noqa: F401  (the schema registry before USD builds it)

    inputs, light, _ = PROBES[name]
    folder.mkdir(parents=True, exist_ok=True)
    if light == "sky" and not (folder / "sky.exr").exists():
        write_sky(folder / "sky.exr")
    path = folder / f"{name}.usda"
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, "Y")
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    camera = UsdGeom.Camera.Define(stage, "/Camera")
    camera.CreateFocalLengthAttr(35.0)
    camera.CreateHorizontalApertureAttr(36.0)
    camera.CreateVerticalApertureAttr(24.0)
    camera.CreateClippingRangeAttr(Gf.Vec2f(4.0, 100.0) if light == "clipped"
                                   else Gf.Vec2f(0.1, 100.0))
    look = Gf.Matrix4d().SetLookAt(Gf.Vec3d(0, 1.5, 4), Gf.Vec3d(0, 0, 0), Gf.Vec3d(0, 1, 0))
    camera.AddTransformOp().Set(look.GetInverse())
    sphere = _sphere(stage, "/Ball")
    floor = UsdGeom.Mesh.Define(stage, "/Floor")
    floor.CreatePointsAttr([(-3, -1, -3), (-3, -1, 3), (3, -1, 3), (3, -1, -3)])
    floor.CreateFaceVertexCountsAttr([4])
    floor.CreateFaceVertexIndicesAttr([0, 1, 2, 3])
    floor.CreateSubdivisionSchemeAttr("none")
    look_ball = _material(stage, "/Looks/Ball", inputs or {"diffuseColor": (0.6, 0.6, 0.6)})
    look_floor = _material(stage, "/Looks/Floor", {"diffuseColor": (0.2, 0.5, 0.8)})
    UsdShade.MaterialBindingAPI.Apply(sphere.GetPrim()).Bind(look_ball)
    UsdShade.MaterialBindingAPI.Apply(floor.GetPrim()).Bind(look_floor)
    _light(stage, light)
    stage.Save()
    return path


if __name__ == "__main__":
    out = Path(sys.argv[1])
    for probe in PROBES:
        print(write_probe(out, probe))
