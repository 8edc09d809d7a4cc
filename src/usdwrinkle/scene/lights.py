"""UsdLux lights as usdview's Storm lights a surface; usdview's camera light when a stage
has none.

Storm (HdStLight, OpenUSD 25.08) approximates every light by a point or a direction
with a colour c, and so does usdwrinkle (docs/method.md, "Lights", gives the formulas and
what differs):

- c = inputs:color x blackbody(inputs:colorTemperature, when enabled) x intensity x
  2^exposure, times the light's area unless inputs:normalize: a distant light's solid
  angle 2 pi (1 - cos(angle / 2)), pi r^2 for sphere and disk lights, width x height for
  rect lights, length x radius for cylinder lights. UsdLux defines intensity as the
  radiance of the light's surface; area x radiance is what a small source gives.
- positional lights fall off as 1/d^2; rect and disk lights light the cone of
  inputs:shaping:cone:angle (default 90 degrees) about their -Z axis.
- dome lights: a textured dome's environment is projected to 9 spherical-harmonic
  coefficients (its irradiance is exact to 3% for smooth environments); a dome without a
  texture emits its colour from every direction, as UsdLux specifies (Storm ignores it).
- a stage without lights is lit as usdview lights it: its camera light, at the camera,
  c = pi (irradiance pi, so a UsdPreviewSurface shows its diffuse colour head-on), no
  falloff.
"""
from __future__ import annotations

import logging
import math
from functools import lru_cache

import numpy as np
from pxr import Usd, UsdGeom, UsdLux

from ..process.errors import UsdWrinkleError
from ..usd.values import finite_in_float32, frame_of
from .records import LightRecord

_log = logging.getLogger(__name__)

#: radiance beyond this is refused: the draw sums lights in float32 (max 3.4e38)
MAX_RADIANCE = 1e30
#: usdview's camera light (UsdAppUtilsFrameRecorder, stageView.py): colour pi, ambient 0.01
CAMERA_LIGHT_COLOR = math.pi
SCENE_AMBIENT = 0.01
#: the default shaping cone of rect and disk lights (UsdLuxShapingAPI)
DEFAULT_CONE_ANGLE = 90.0


def _value(attr, time, fallback):
    value = attr.Get(time) if attr else None
    return fallback if value is None else value


def _finite(value, path: str, name: str, time) -> None:
    if not np.all(np.isfinite(np.asarray(value, np.float64))):
        raise UsdWrinkleError(f"light {name.split(':')[-1]} is not finite", path, name,
                              frame_of(time))


def _color(light: UsdLux.LightAPI, path: str, time) -> np.ndarray:
    """colour x blackbody x intensity x 2^exposure (no area yet); a value that is not
    finite, or that overflows float32, is refused naming the light and the attribute."""
    color = np.asarray(_value(light.GetColorAttr(), time, (1.0, 1.0, 1.0)), np.float64)
    intensity = float(_value(light.GetIntensityAttr(), time, 1.0))
    exposure = float(_value(light.GetExposureAttr(), time, 0.0))
    for name, value in (("inputs:color", color), ("inputs:intensity", intensity),
                        ("inputs:exposure", exposure)):
        _finite(value, path, name, time)
    # in log2, so that a huge exposure does not overflow before the test
    peak = float(np.max(np.abs(color))) * abs(intensity)
    if peak > 0 and math.log2(peak) + min(exposure, 50.0) > math.log2(MAX_RADIANCE):
        raise UsdWrinkleError(f"light radiance color*intensity*2^exposure exceeds "
                              f"{MAX_RADIANCE:g} (intensity {intensity:g}, exposure "
                              f"{exposure:g})", path, "inputs:exposure", frame_of(time))
    if _value(light.GetEnableColorTemperatureAttr(), time, False):
        kelvin = float(_value(light.GetColorTemperatureAttr(), time, 6500.0))
        _finite(kelvin, path, "inputs:colorTemperature", time)
        color = color * blackbody_rgb(kelvin)
    # Storm clamps the exposure to +-50 stops
    return color * intensity * 2.0 ** float(np.clip(exposure, -50.0, 50.0))


def _positive(attr, time, fallback: float, path: str) -> float:
    value = float(_value(attr, time, fallback))
    if not (math.isfinite(value) and value >= 0):
        raise UsdWrinkleError(f"light {attr.GetName().split(':')[-1]} must be finite and >= 0",
                              path, attr.GetName(), frame_of(time))
    return value


def _area(prim: Usd.Prim, time, path: str) -> float:
    """What Storm multiplies a light's radiance by when inputs:normalize is off."""
    if prim.IsA(UsdLux.DistantLight):
        angle = _positive(UsdLux.DistantLight(prim).GetAngleAttr(), time, 0.53, path)
        return 2.0 * math.pi * (1.0 - math.cos(math.radians(angle) / 2.0))
    if prim.IsA(UsdLux.SphereLight):
        radius = _positive(UsdLux.SphereLight(prim).GetRadiusAttr(), time, 0.5, path)
        return math.pi * radius * radius
    if prim.IsA(UsdLux.DiskLight):
        radius = _positive(UsdLux.DiskLight(prim).GetRadiusAttr(), time, 0.5, path)
        return math.pi * radius * radius
    if prim.IsA(UsdLux.RectLight):
        light = UsdLux.RectLight(prim)
        return _positive(light.GetWidthAttr(), time, 1.0, path) * \
            _positive(light.GetHeightAttr(), time, 1.0, path)
    if prim.IsA(UsdLux.CylinderLight):
        light = UsdLux.CylinderLight(prim)
        return _positive(light.GetLengthAttr(), time, 1.0, path) * \
            _positive(light.GetRadiusAttr(), time, 0.5, path)
    return 1.0


def _transform(prim, time, xform_cache) -> np.ndarray:
    xf = np.asarray(xform_cache.GetLocalToWorldTransform(prim), np.float64)
    if not finite_in_float32(xf):
        raise UsdWrinkleError("light transform is not finite", str(prim.GetPath()), "xformOp",
                              frame_of(time))
    return xf


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / max(float(np.linalg.norm(vector)), 1e-30)


LIGHT_TYPES = (UsdLux.DistantLight, UsdLux.SphereLight, UsdLux.DiskLight, UsdLux.RectLight,
               UsdLux.CylinderLight, UsdLux.DomeLight)


def light_prims(stage: Usd.Stage) -> list[Usd.Prim]:
    """The prims with UsdLux's LightAPI (one walk of the stage; valid until a resync)."""
    return [prim for prim in stage.Traverse(Usd.TraverseInstanceProxies())
            if prim.HasAPI(UsdLux.LightAPI)]


def read_lights(stage: Usd.Stage, time, xform_cache: UsdGeom.XformCache,
                prims: list[Usd.Prim] | None = None) -> list[LightRecord]:
    """The stage's visible UsdLux lights at ``time``, as Storm approximates them.
    ``prims``: its light_prims, when the caller keeps them (else the stage is walked)."""
    lights = []
    for prim in light_prims(stage) if prims is None else prims:
        if prim.IsA(UsdGeom.Imageable) and \
                UsdGeom.Imageable(prim).ComputeVisibility(time) == UsdGeom.Tokens.invisible:
            continue
        if not any(prim.IsA(kind) for kind in LIGHT_TYPES):
            _log.warning(f"{prim.GetTypeName() or 'this'} light is not supported; ignored "
                         f"({prim.GetPath()})")
            continue
        lights.append(_light(prim, time, xform_cache))
    return lights


def _light(prim: Usd.Prim, time, xform_cache) -> LightRecord:
    path = str(prim.GetPath())
    api = UsdLux.LightAPI(prim)
    color = _color(api, path, time)
    diffuse = float(_value(api.GetDiffuseAttr(), time, 1.0))
    specular = float(_value(api.GetSpecularAttr(), time, 1.0))
    xf = _transform(prim, time, xform_cache)
    if prim.IsA(UsdLux.DomeLight):
        sh, texture, key = dome_environment(UsdLux.DomeLight(prim), time, xf)
        return LightRecord("dome", color * diffuse, color * specular, dome_sh=sh * color,
                           dome_texture=texture, world_to_dome=_rotation(xf).T,
                           dome_key=key)
    if not _value(api.GetNormalizeAttr(), time, False):
        color = color * _area(prim, time, path)
    if prim.IsA(UsdLux.DistantLight):
        towards = _unit(np.array([0.0, 0.0, 1.0]) @ xf[:3, :3])  # the light shines along -Z
        return LightRecord("directional", color * diffuse, color * specular, vector=towards)
    kwargs = {}
    if prim.IsA(UsdLux.RectLight) or prim.IsA(UsdLux.DiskLight):
        shaping = UsdLux.ShapingAPI(prim)
        kwargs = {"spot_direction": _unit(np.array([0.0, 0.0, -1.0]) @ xf[:3, :3]),
                  "spot_cutoff": float(_value(shaping.GetShapingConeAngleAttr(), time,
                                              DEFAULT_CONE_ANGLE)),
                  "spot_falloff": max(0.0, float(_value(shaping.GetShapingFocusAttr(), time,
                                                        0.0)))}
    return LightRecord("positional", color * diffuse, color * specular,
                       vector=xf[3, :3].copy(), attenuate=True, **kwargs)


def camera_light(eye_position: np.ndarray) -> LightRecord:
    """usdview's default camera light (what it shows for a stage without lights)."""
    color = np.full(3, CAMERA_LIGHT_COLOR)
    return LightRecord("positional", color, color, vector=np.asarray(eye_position, float),
                       ambient=np.full(3, SCENE_AMBIENT))


def default_lights(view: np.ndarray) -> list[LightRecord]:
    """The lights of a stage without any: usdview's camera light."""
    return [camera_light(np.linalg.inv(view)[3, :3])]


# -- colour temperature ----------------------------------------------------------------------
def _cie_cmf(wavelength_nm: np.ndarray) -> np.ndarray:
    """CIE 1931 2-degree colour matching functions, by the multi-lobe Gaussian fit of
    Wyman, Sloan and Shirley (JCGT 2013): (n, 3) x-bar, y-bar, z-bar."""
    w = np.asarray(wavelength_nm, np.float64)

    def g(mu, s1, s2):
        s = np.where(w < mu, s1, s2)
        return np.exp(-0.5 * ((w - mu) / s) ** 2)

    x = 1.056 * g(599.8, 37.9, 31.0) + 0.362 * g(442.0, 16.0, 26.7) - 0.065 * g(501.1, 20.4, 26.2)
    y = 0.821 * g(568.8, 46.9, 40.5) + 0.286 * g(530.9, 16.3, 31.1)
    z = 1.217 * g(437.0, 11.8, 36.0) + 0.681 * g(459.0, 26.0, 13.8)
    return np.stack([x, y, z], axis=1)


@lru_cache(maxsize=256)
def _blackbody(kelvin: float) -> tuple:
    wavelengths = np.arange(360.0, 831.0, 1.0)
    metres = wavelengths * 1e-9
    h, c, k = 6.62607015e-34, 2.99792458e8, 1.380649e-23
    planck = 1.0 / (metres ** 5 * (np.exp(h * c / (metres * k * kelvin)) - 1.0))
    xyz = planck @ _cie_cmf(wavelengths)
    to_rec709 = np.array([[3.2404542, -1.5371385, -0.4985314],
                          [-0.9692660, 1.8760108, 0.0415560],
                          [0.0556434, -0.2040259, 1.0572252]])
    rgb = to_rec709 @ xyz
    rgb = rgb / float(np.dot(rgb, [0.2126, 0.7152, 0.0722]))  # the luminance of (1, 1, 1)
    return tuple(np.maximum(rgb, 0.0))


def blackbody_rgb(kelvin: float) -> np.ndarray:
    """Linear Rec.709 colour of a black body at ``kelvin`` (clamped to 1000..10000 K, as
    Storm does), normalised to the luminance of white."""
    return np.asarray(_blackbody(float(np.clip(kelvin, 1000.0, 10000.0))))


# -- dome lights -------------------------------------------------------------------------------
#: SH9 irradiance band weights A_l / pi (Ramamoorthi and Hanrahan 2001): E(n)/pi from the
#: radiance's coefficients, so that a constant environment of radiance L gives L
IRRADIANCE_BANDS = np.array([1.0, 2.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0, 0.25, 0.25, 0.25, 0.25,
                             0.25])


def sh9_basis(directions: np.ndarray) -> np.ndarray:
    """The real SH basis Y_lm (l <= 2) at unit ``directions`` (n, 3): (n, 9)."""
    x, y, z = directions[:, 0], directions[:, 1], directions[:, 2]
    return np.stack([np.full_like(x, 0.282095), 0.488603 * y, 0.488603 * z, 0.488603 * x,
                     1.092548 * x * y, 1.092548 * y * z, 0.315392 * (3 * z * z - 1),
                     1.092548 * x * z, 0.546274 * (x * x - y * y)], axis=1)


def latlong_directions(width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Unit directions (h, w, 3) of a lat-long map's pixel centres, in the dome's own
    space, with Storm's convention (ProjectToLatLong: u = (atan2(z, x) + pi/2) / 2pi,
    v = acos(y) / pi, row 0 at v = 0), and each pixel's solid angle (h, w)."""
    v = (np.arange(height) + 0.5) / height
    u = (np.arange(width) + 0.5) / width
    theta = np.pi * v[:, None]
    phi = 2.0 * np.pi * u[None, :] - 0.5 * np.pi
    directions = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.cos(theta),
                                              np.sin(theta) * np.sin(phi)), axis=-1)
    # each row's exact band, 2 pi (cos theta0 - cos theta1) / width: the whole sphere is
    # 4 pi at any size (sin(theta) d(theta) at the centre gave 2 pi^2 for a 1x1 map)
    edges = np.cos(np.pi * np.arange(height + 1) / height)
    band = (2.0 * np.pi / width) * (edges[:-1] - edges[1:])
    solid_angle = band[:, None] * np.ones_like(phi)
    return directions, solid_angle


#: a lat-long map is projected at this many columns and rows at least (its texels
#: repeated): the basis is sampled at texel centres, and one row at the equator read a
#: uniform 1x1 sky 6.5x too bright and a 2x2 one 0.4x
SH_MIN_SIZE = (64, 32)


def project_sh9(radiance: np.ndarray, to_world: np.ndarray) -> np.ndarray:
    """SH9 coefficients (9, 3) of a lat-long radiance map (h, w, 3), in world directions
    (``to_world``: the dome's row-vector 3x3)."""
    height, width = radiance.shape[:2]
    repeat_x = -(-SH_MIN_SIZE[0] // width)
    repeat_y = -(-SH_MIN_SIZE[1] // height)
    if repeat_x > 1 or repeat_y > 1:  # each texel covers its whole area (as a lookup does)
        radiance = np.repeat(np.repeat(radiance, repeat_y, axis=0), repeat_x, axis=1)
        height, width = radiance.shape[:2]
    directions, solid_angle = latlong_directions(width, height)
    world = directions.reshape(-1, 3) @ to_world
    world /= np.maximum(np.linalg.norm(world, axis=1, keepdims=True), 1e-30)
    basis = sh9_basis(world) * solid_angle.reshape(-1, 1)
    return basis.T @ radiance.reshape(-1, 3).astype(np.float64)


#: a dome without a texture: radiance 1 in every direction (times its colour)
CONSTANT_SH = np.zeros((9, 3))
CONSTANT_SH[0] = 1.0 / 0.282095


def _rotation(xf: np.ndarray) -> np.ndarray:
    """The rotation of a row-vector transform (its rows normalised)."""
    rotation = np.asarray(xf[:3, :3], np.float64)
    return rotation / np.maximum(np.linalg.norm(rotation, axis=1, keepdims=True), 1e-30)


def dome_environment(light: UsdLux.DomeLight, time, xf: np.ndarray):
    """(SH9 (9, 3) of the dome's radiance in world directions, its texture or None, the
    texture's key), without the light's colour. A dome without a texture (or with one
    that cannot be read: a warning) is a constant radiance of 1."""
    attr = light.GetTextureFileAttr()
    asset = attr.Get(time) if attr else None
    if asset is None or not asset.path:
        return CONSTANT_SH, None, None
    path = str(light.GetPrim().GetPath())
    if not asset.resolvedPath:
        _log.warning(f"dome light texture '{asset.path}' not found; lit as a constant dome "
                     f"({path})")
        return CONSTANT_SH, None, None
    rotation = _rotation(xf)
    from .material import load_texture

    try:
        texture = load_texture(asset.resolvedPath, "auto")
        sh = _texture_sh(asset.resolvedPath, rotation.tobytes())
    except OSError as exc:
        _log.warning(f"{exc}; lit as a constant dome ({path})")
        return CONSTANT_SH, None, None
    return sh, texture, asset.resolvedPath


@lru_cache(maxsize=16)
def _texture_sh(resolved_path: str, rotation: bytes) -> np.ndarray:
    """project_sh9 of a lat-long texture (cached: the file and the dome's rotation)."""
    from .material import load_texture

    image = load_texture(resolved_path, "auto")
    pixels = image.linear()[::-1, :, :3]  # TextureImage rows run bottom-up; row 0: v = 0
    return project_sh9(np.asarray(pixels, np.float64),
                       np.frombuffer(rotation, np.float64).reshape(3, 3))
