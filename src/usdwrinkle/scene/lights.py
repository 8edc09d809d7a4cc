"""UsdLux distant, sphere and dome lights; a default key and fill when there are none."""
from __future__ import annotations

import math

import numpy as np
from pxr import Usd, UsdGeom, UsdLux

from ..errors import UsdWrinkleError
from .records import LightRecord
from .values import finite_in_float32, frame_of

#: radiance beyond this is refused: the draw sums lights in float32 (max 3.4e38)
MAX_RADIANCE = 1e30


def _radiance(light, time) -> np.ndarray:
    """color * intensity * 2^exposure; a value that is not finite (or that overflows
    float32) is refused, naming the light and the attribute."""
    path = str(light.GetPrim().GetPath())
    frame = frame_of(time)
    color = light.GetColorAttr().Get(time)
    intensity = light.GetIntensityAttr().Get(time)
    exposure = light.GetExposureAttr().Get(time)
    color = np.ones(3) if color is None else np.asarray(color, dtype=np.float64)
    intensity = 1.0 if intensity is None else float(intensity)
    exposure = 0.0 if exposure is None else float(exposure)
    for name, value in (("inputs:color", color), ("inputs:intensity", intensity),
                        ("inputs:exposure", exposure)):
        if not np.all(np.isfinite(value)):
            raise UsdWrinkleError(f"light {name.split(':')[1]} is not finite", path, name,
                                  frame)
    # in log2, so that a huge exposure does not overflow before the test
    peak = float(np.max(np.abs(color))) * abs(intensity)
    if peak > 0 and math.log2(peak) + exposure > math.log2(MAX_RADIANCE):
        raise UsdWrinkleError(f"light radiance color*intensity*2^exposure exceeds "
                              f"{MAX_RADIANCE:g} (intensity {intensity:g}, exposure "
                              f"{exposure:g})", path, "inputs:exposure", frame)
    return color * intensity * 2.0 ** max(exposure, -1074.0)


def _transform(prim, time, xform_cache) -> np.ndarray:
    xf = np.asarray(xform_cache.GetLocalToWorldTransform(prim), np.float64)
    if not finite_in_float32(xf):
        raise UsdWrinkleError("light transform is not finite", str(prim.GetPath()), "xformOp",
                              frame_of(time))
    return xf


def read_lights(stage: Usd.Stage, time, xform_cache: UsdGeom.XformCache) -> list[LightRecord]:
    lights = []
    for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
        if prim.IsA(UsdGeom.Imageable) and \
                UsdGeom.Imageable(prim).ComputeVisibility(time) == UsdGeom.Tokens.invisible:
            continue
        if prim.IsA(UsdLux.DistantLight):
            xf = _transform(prim, time, xform_cache)
            direction = np.array([0.0, 0.0, -1.0]) @ xf[:3, :3]
            direction /= max(np.linalg.norm(direction), 1e-30)
            lights.append(LightRecord("distant", _radiance(UsdLux.DistantLight(prim), time),
                                      direction=direction))
        elif prim.IsA(UsdLux.SphereLight):
            xf = _transform(prim, time, xform_cache)
            light = UsdLux.SphereLight(prim)
            radius = light.GetRadiusAttr().Get(time)
            if radius is not None and not (math.isfinite(radius) and radius >= 0):
                raise UsdWrinkleError("light radius must be finite and >= 0",
                                      str(prim.GetPath()), "inputs:radius", frame_of(time))
            lights.append(LightRecord("sphere", _radiance(light, time), position=xf[3, :3].copy(),
                                      radius=0.5 if radius is None else float(radius)))
        elif prim.IsA(UsdLux.DomeLight):
            lights.append(LightRecord("dome", _radiance(UsdLux.DomeLight(prim), time)))
    return lights


def default_lights(view: np.ndarray) -> list[LightRecord]:
    """A key light from above-left of the camera and a dim dome fill."""
    eye_to_world = np.linalg.inv(view)
    direction = np.array([0.45, -0.6, -0.65]) @ eye_to_world[:3, :3]
    direction /= np.linalg.norm(direction)
    return [LightRecord("distant", np.array([1.25, 1.22, 1.18]), direction=direction),
            LightRecord("dome", np.array([0.18, 0.19, 0.21]))]
