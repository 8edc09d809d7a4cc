"""Cameras: --camera by path or name, the primary camera, the first camera, or framing.

The image keeps the camera's horizontal field of view; when the image aspect
differs from the camera's aperture aspect, the vertical extent is adjusted
(as usdrecord does with the default ``--height``, the aspects agree anyway).
"""
from __future__ import annotations

import logging
import math

import numpy as np
from pxr import Gf, Sdf, Usd, UsdGeom, UsdUtils

from ..process.errors import UsdWrinkleError
from ..usd.diagnostics import usd_diagnostics
from ..usd.values import finite_in_float32, frame_of
from .records import CameraRecord


def find_camera(stage: Usd.Stage, spec: str | None) -> Usd.Prim | None:
    """Resolve ``--camera``: a prim path, or a camera name; else primary, else first."""
    cameras = [p for p in stage.Traverse(Usd.TraverseInstanceProxies())
               if p.IsA(UsdGeom.Camera)]
    if spec:
        if spec.startswith("/"):
            valid, why = Sdf.Path.IsValidPathString(spec)
            if not valid or not Sdf.Path(spec).IsPrimPath():
                raise UsdWrinkleError(f"camera '{spec}' is not a prim path"
                                      + (f" ({why.rstrip('.')})" if why else ""))
            prim = stage.GetPrimAtPath(spec)
            if not prim or not prim.IsA(UsdGeom.Camera):
                raise UsdWrinkleError(f"camera '{spec}' not found on the stage", spec)
            return prim
        for prim in cameras:
            if prim.GetName() == spec:
                return prim
        names = ", ".join(str(c.GetPath()) for c in cameras) or "none"
        raise UsdWrinkleError(f"camera '{spec}' not found on the stage (cameras: {names})")
    primary = UsdUtils.GetPrimaryCameraName()
    for prim in cameras:
        if prim.GetName() == primary:
            return prim
    return cameras[0] if cameras else None


_log = logging.getLogger(__name__)
_PROJECTIONS = ("perspective", "orthographic")
_warned_projection: set[str] = set()


def gf_camera(prim: Usd.Prim, time) -> Gf.Camera:
    """UsdGeom's Gf.Camera at ``time``; an unknown ``projection`` token (USD prints a raw
    warning per call and uses perspective) is one usdwrinkle warning, naming the prim."""
    attr = UsdGeom.Camera(prim).GetProjectionAttr()
    token = attr.Get(time) if attr else None
    if token is not None and token not in _PROJECTIONS:
        key = f"{prim.GetPath()}:{token}"
        if key not in _warned_projection:
            _warned_projection.add(key)
            _log.warning("%s.projection is '%s', which USD does not know: drawn as "
                         "perspective (use perspective or orthographic)", prim.GetPath(), token)
        with usd_diagnostics():
            return UsdGeom.Camera(prim).GetCamera(time)
    return UsdGeom.Camera(prim).GetCamera(time)


def camera_aspect(prim: Usd.Prim, time) -> float:
    cam = gf_camera(prim, time)
    aspect = cam.aspectRatio
    return aspect if math.isfinite(aspect) and 1e-3 < aspect < 1e3 else 1.0


def check_camera(prim: Usd.Prim, gf_cam: Gf.Camera, time) -> None:
    """Refuse camera values that give no image (a NaN focal length, a zero aperture, a
    transform that is not finite), naming the attribute."""
    path = str(prim.GetPath())
    frame = frame_of(time)
    near, far = gf_cam.clippingRange.min, gf_cam.clippingRange.max
    checks = (
        ("focalLength", gf_cam.focalLength, gf_cam.focalLength > 0, "finite and > 0"),
        ("horizontalAperture", gf_cam.horizontalAperture, gf_cam.horizontalAperture > 0,
         "finite and > 0"),
        ("verticalAperture", gf_cam.verticalAperture, gf_cam.verticalAperture > 0,
         "finite and > 0"),
        ("horizontalApertureOffset", gf_cam.horizontalApertureOffset, True, "finite"),
        ("verticalApertureOffset", gf_cam.verticalApertureOffset, True, "finite"),
        ("clippingRange", (near, far), 0 < near < far, "finite, with 0 < near < far"),
    )
    for name, value, ok, rule in checks:
        if not (ok and np.all(np.isfinite(value))):
            raise UsdWrinkleError(f"camera {name} {value} must be {rule}", path, name, frame)
    if not finite_in_float32(gf_cam.transform):
        raise UsdWrinkleError("camera transform is not finite", path, "xformOp", frame)


def usd_camera(prim: Usd.Prim, time, aspect: float) -> CameraRecord:
    """A UsdGeom.Camera at ``time`` as view and projection matrices (its clippingRange
    is the projection's near and far planes)."""
    gf_cam = gf_camera(prim, time)
    check_camera(prim, gf_cam, time)
    return camera_record(str(prim.GetPath()), gf_cam, aspect)


def camera_record(path: str, gf_cam: Gf.Camera, aspect: float) -> CameraRecord:
    """A Gf.Camera as view and projection: the horizontal field of view kept, the
    vertical one fitted to the image's ``aspect`` (as usdrecord's default --height
    does, the aspects agree anyway)."""
    frustum = gf_cam.frustum
    window = frustum.window
    width = window.GetMax()[0] - window.GetMin()[0]
    center_y = 0.5 * (window.GetMax()[1] + window.GetMin()[1])
    half_h = 0.5 * width / aspect
    frustum.window = Gf.Range2d(Gf.Vec2d(window.GetMin()[0], center_y - half_h),
                                Gf.Vec2d(window.GetMax()[0], center_y + half_h))
    view = np.asarray(frustum.ComputeViewMatrix(), dtype=np.float64)
    projection = np.asarray(frustum.ComputeProjectionMatrix(), dtype=np.float64)
    position = np.asarray(frustum.position, dtype=np.float64)
    near_far = frustum.nearFar
    return CameraRecord(path, view, projection, position, aspect,
                        (float(near_far.min), float(near_far.max)))


def framing_camera(bounds_min, bounds_max, up_axis: str, aspect: float,
                   fov_degrees: float = 30.0) -> CameraRecord:
    """A perspective camera that frames an axis-aligned box from the front, 3/4 high
    (usdrecord looks straight down -Z, or along +Y for Z up, which shows a sheet lying
    in the ground plane edge-on; this view shows any shape)."""
    lo, hi = np.asarray(bounds_min, float), np.asarray(bounds_max, float)
    if not np.all(np.isfinite(lo)) or not np.all(np.isfinite(hi)) or np.any(hi < lo):
        lo, hi = -np.ones(3), np.ones(3)
    center = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-3)
    if up_axis == "Z":
        up, front = np.array([0.0, 0.0, 1.0]), np.array([0.25, -1.0, 0.3])
    else:
        up, front = np.array([0.0, 1.0, 0.0]), np.array([0.25, 0.3, 1.0])
    front /= np.linalg.norm(front)
    fov_v = math.radians(fov_degrees)
    fov_min = min(fov_v, 2 * math.atan(math.tan(fov_v / 2) * aspect))
    distance = radius / math.sin(fov_min / 2) * 1.05
    eye = center + front * distance
    frustum = Gf.Frustum()
    near, far = max(distance - radius * 2, distance * 1e-3), distance + radius * 2
    frustum.SetPerspective(fov_degrees, aspect, near, far)
    look = Gf.Matrix4d().SetLookAt(Gf.Vec3d(*eye), Gf.Vec3d(*center), Gf.Vec3d(*up))
    frustum.Transform(look.GetInverse())
    view = np.asarray(frustum.ComputeViewMatrix(), dtype=np.float64)
    projection = np.asarray(frustum.ComputeProjectionMatrix(), dtype=np.float64)
    return CameraRecord("<framing>", view, projection, eye, aspect, (near, far))


def framing_gf_camera(bounds_min, bounds_max, up_axis: str, aspect: float) -> Gf.Camera:
    """framing_camera as a Gf.Camera (a real client can look through the same view)."""
    record = framing_camera(bounds_min, bounds_max, up_axis, aspect)
    camera = Gf.Camera()
    camera.transform = Gf.Matrix4d(*np.linalg.inv(record.view).reshape(-1).tolist())
    camera.SetPerspectiveFromAspectRatioAndFieldOfView(aspect, 30.0, Gf.Camera.FOVVertical)
    near = float(record.projection[3, 2] / (record.projection[2, 2] - 1.0))
    far = float(record.projection[3, 2] / (record.projection[2, 2] + 1.0))
    camera.clippingRange = Gf.Range1f(near, far)
    return camera


def towards_eye(record: CameraRecord, width: int, height: int) -> np.ndarray:
    """(height, width, 3) unit world-space vectors from each pixel centre's surface
    toward the eye (row 0 at the top), through the camera as the engine draws with it:
    the pixel's ray from its far-plane point to its near-plane point (parallel rays for
    an orthographic camera)."""
    ys, xs = np.mgrid[0:height, 0:width]
    x = (xs + 0.5) / width * 2.0 - 1.0
    y = 1.0 - (ys + 0.5) / height * 2.0
    ones = np.ones((height, width))
    to_world = np.linalg.inv(np.asarray(record.view) @ np.asarray(record.projection))
    near, far = (np.stack([x, y, z * ones, ones], -1) @ to_world for z in (-1.0, 1.0))
    ray = near[..., :3] / near[..., 3:] - far[..., :3] / far[..., 3:]
    return ray / np.linalg.norm(ray, axis=-1, keepdims=True)
