"""Wrinkle parameters from WrinkleAPI attributes, with fallbacks and validation."""
from __future__ import annotations

import numpy as np
from pxr import Usd, UsdGeom

from .. import schema
from ..errors import UsdWrinkleError
from .records import WrinkleParams
from .topology import Topology, mean_edge_length


def cosine_profile(samples: int = schema.PROFILE_SAMPLES) -> np.ndarray:
    theta = np.arange(samples) * (2 * np.pi / samples)
    return np.cos(theta).astype(np.float32)


def derive_gradient(height: np.ndarray) -> np.ndarray:
    """dH/dtheta of a periodic profile sampled uniformly over [0, 2pi)."""
    height = np.asarray(height, dtype=np.float64)
    step = 2 * np.pi / len(height)
    return ((np.roll(height, -1) - np.roll(height, 1)) / (2 * step)).astype(np.float32)


def _get(prim: Usd.Prim, name: str, time):
    attr = prim.GetAttribute(name)
    if not attr or not attr.HasAuthoredValue():
        return None
    return attr.Get(time)


def _profile(prim, name, time, path):
    value = _get(prim, name, time)
    if value is None or len(value) == 0:
        return None
    arr = np.asarray(value, dtype=np.float32)
    if arr.size < 2 or not np.all(np.isfinite(arr)):
        raise UsdWrinkleError("a profile needs at least 2 finite samples", path, name)
    return arr


def read_params(prim: Usd.Prim, rest_points: np.ndarray, topology: Topology,
                time: Usd.TimeCode | None = None,
                relax_override: int | None = None) -> WrinkleParams:
    """Resolve WrinkleAPI values for one mesh (also for --all-meshes, with fallbacks)."""
    time = Usd.TimeCode.Default() if time is None else time
    path = str(prim.GetPath())
    n = len(rest_points)
    primvars = UsdGeom.PrimvarsAPI(prim)

    q = np.zeros((n, 3), np.float32)
    q_primvar = primvars.GetPrimvar("wrinkle:q")
    if q_primvar and q_primvar.HasAuthoredValue():
        value = q_primvar.ComputeFlattened(time)
        arr = np.asarray(value, dtype=np.float32).reshape(-1, 3) if value is not None else None
        if arr is None or len(arr) != n:
            raise UsdWrinkleError(
                f"q has {0 if arr is None else len(arr)} values for {n} points", path, schema.Q)
        if q_primvar.GetInterpolation() not in ("vertex", "varying"):
            raise UsdWrinkleError("q must have vertex interpolation", path, schema.Q)
        if not np.all(np.isfinite(arr)):
            raise UsdWrinkleError("q is not finite", path, schema.Q)
        if np.any(np.linalg.norm(arr, axis=1) > 1.0 + 1e-4):
            raise UsdWrinkleError("|q| > 1", path, schema.Q)
        q = arr

    width_primvar = primvars.GetPrimvar("wrinkle:width")
    width = None
    if width_primvar and width_primvar.HasAuthoredValue():
        value = width_primvar.ComputeFlattened(time)
        arr = np.atleast_1d(np.asarray(value, dtype=np.float32)) if value is not None else None
        if arr is None or arr.size not in (1, n):
            raise UsdWrinkleError(
                f"width must be constant or have one value per point ({n})", path, schema.WIDTH)
        if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
            raise UsdWrinkleError("width must be finite and > 0", path, schema.WIDTH)
        width = np.broadcast_to(arr, (n,)).astype(np.float32)
    if width is None:
        fallback = schema.WIDTH_EDGE_MULTIPLE * mean_edge_length(rest_points, topology)
        width = np.full(n, fallback if fallback > 0 else 1.0, np.float32)

    scale = _get(prim, schema.AMPLITUDE_SCALE, time)
    scale = 1.0 if scale is None else float(scale)
    if not np.isfinite(scale) or scale < 0:
        raise UsdWrinkleError("amplitude scale must be finite and >= 0", path,
                              schema.AMPLITUDE_SCALE)

    height = _profile(prim, schema.HEIGHT_PROFILE, time, path)
    gradient = _profile(prim, schema.GRADIENT_PROFILE, time, path)
    if height is None:
        height = cosine_profile()
    if gradient is None:
        gradient = derive_gradient(height)

    iterations = _get(prim, schema.RELAX_ITERATIONS, time)
    iterations = schema.DEFAULT_RELAX_ITERATIONS if iterations is None else int(iterations)
    if relax_override is not None:
        iterations = relax_override
    if iterations < 0:
        raise UsdWrinkleError("relax iterations must be >= 0", path, schema.RELAX_ITERATIONS)
    return WrinkleParams(q, width, scale, height, gradient, iterations)
