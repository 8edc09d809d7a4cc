"""UsdLux distant, sphere and dome lights; a default key and fill when there are none."""
from __future__ import annotations

import numpy as np
from pxr import Usd, UsdGeom, UsdLux

from .records import LightRecord


def _radiance(light) -> np.ndarray:
    color = np.asarray(light.GetColorAttr().Get() or (1, 1, 1), dtype=np.float64)
    intensity = light.GetIntensityAttr().Get()
    exposure = light.GetExposureAttr().Get()
    intensity = 1.0 if intensity is None else float(intensity)
    exposure = 0.0 if exposure is None else float(exposure)
    return color * intensity * 2.0 ** exposure


def read_lights(stage: Usd.Stage, time, xform_cache: UsdGeom.XformCache) -> list[LightRecord]:
    lights = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if prim.IsA(UsdGeom.Imageable) and \
                UsdGeom.Imageable(prim).ComputeVisibility(time) == UsdGeom.Tokens.invisible:
            continue
        if prim.IsA(UsdLux.DistantLight):
            xf = np.asarray(xform_cache.GetLocalToWorldTransform(prim))
            direction = np.array([0.0, 0.0, -1.0]) @ xf[:3, :3]
            direction /= max(np.linalg.norm(direction), 1e-30)
            lights.append(LightRecord("distant", _radiance(UsdLux.DistantLight(prim)),
                                      direction=direction))
        elif prim.IsA(UsdLux.SphereLight):
            xf = np.asarray(xform_cache.GetLocalToWorldTransform(prim))
            light = UsdLux.SphereLight(prim)
            radius = light.GetRadiusAttr().Get()
            lights.append(LightRecord("sphere", _radiance(light), position=xf[3, :3].copy(),
                                      radius=0.5 if radius is None else float(radius)))
        elif prim.IsA(UsdLux.DomeLight):
            lights.append(LightRecord("dome", _radiance(UsdLux.DomeLight(prim))))
    return lights


def default_lights(view: np.ndarray) -> list[LightRecord]:
    """A key light from above-left of the camera and a dim dome fill."""
    eye_to_world = np.linalg.inv(view)
    direction = np.array([0.45, -0.6, -0.65]) @ eye_to_world[:3, :3]
    direction /= np.linalg.norm(direction)
    return [LightRecord("distant", np.array([1.25, 1.22, 1.18]), direction=direction),
            LightRecord("dome", np.array([0.18, 0.19, 0.21]))]
