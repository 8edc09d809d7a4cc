"""Wrinkle parameters from WrinkleAPI attributes, with fallbacks and validation."""
from __future__ import annotations

import numpy as np
from pxr import Usd, UsdGeom

from .. import schema
from ..profiles import cosine_profile, derive_gradient
from ..validation import (
    check_amplitude_scale,
    check_biaxial,
    check_profile,
    check_q,
    check_relax_iterations,
    check_tension,
    check_tension_threshold,
    check_type,
    check_width,
    refuse,
)
from .records import WrinkleParams
from .topology import Topology, mean_edge_length


def _get(prim: Usd.Prim, name: str, time):
    """An authored WrinkleAPI value (None if unauthored); a wrong type is refused."""
    attr = prim.GetAttribute(name)
    if not attr or not attr.HasAuthoredValue():
        return None
    refuse(check_type(attr, str(prim.GetPath())))
    return attr.Get(time)


def _profile(prim, name, time, path):
    value = _get(prim, name, time)
    if value is None or len(value) == 0:
        return None
    refuse(check_profile(value, name, path))
    return np.asarray(value, dtype=np.float32)


def read_params(prim: Usd.Prim, rest_points: np.ndarray, topology: Topology,
                time: Usd.TimeCode | None = None,
                relax_override: int | None = None) -> WrinkleParams:
    """Resolve WrinkleAPI values for one mesh (also for --all-meshes, with fallbacks).

    Values that break the rules of ``usdwrinkle check`` are refused with a
    UsdWrinkleError naming the prim and the attribute.
    """
    time = Usd.TimeCode.Default() if time is None else time
    path = str(prim.GetPath())
    n = len(rest_points)
    primvars = UsdGeom.PrimvarsAPI(prim)

    q = np.zeros((n, 3), np.float32)
    q_primvar = primvars.GetPrimvar("wrinkle:q")
    if q_primvar and q_primvar.HasAuthoredValue():
        refuse(check_type(q_primvar.GetAttr(), path))
        value = q_primvar.ComputeFlattened(time)
        if value is not None:
            refuse(check_q(value, q_primvar.GetInterpolation(), n, path))
            q = np.asarray(value, dtype=np.float32).reshape(-1, 3)

    width = None
    width_primvar = primvars.GetPrimvar("wrinkle:width")
    if width_primvar and width_primvar.HasAuthoredValue():
        refuse(check_type(width_primvar.GetAttr(), path))
        value = width_primvar.ComputeFlattened(time)
        if value is not None:
            refuse(check_width(value, n, path))
            arr = np.atleast_1d(np.asarray(value, dtype=np.float32))
            width = np.broadcast_to(arr, (n,)).astype(np.float32)
    if width is None:
        fallback = schema.WIDTH_EDGE_MULTIPLE * mean_edge_length(rest_points, topology)
        width = np.full(n, fallback if fallback > 0 else 1.0, np.float32)

    scale = _get(prim, schema.AMPLITUDE_SCALE, time)
    refuse(check_amplitude_scale(scale, path))
    scale = 1.0 if scale is None else float(scale)

    height = _profile(prim, schema.HEIGHT_PROFILE, time, path)
    gradient = _profile(prim, schema.GRADIENT_PROFILE, time, path)
    if height is None:
        height = cosine_profile()
    if gradient is None:
        gradient = derive_gradient(height)

    iterations = _get(prim, schema.RELAX_ITERATIONS, time)
    if relax_override is not None:
        iterations = relax_override  # the CLI checked it
    refuse(check_relax_iterations(iterations, path))
    iterations = schema.DEFAULT_RELAX_ITERATIONS if iterations is None else int(iterations)

    controls = []
    for name, check, fallback in (
            (schema.BIAXIAL, check_biaxial, schema.DEFAULT_BIAXIAL),
            (schema.TENSION, check_tension, schema.DEFAULT_TENSION),
            (schema.TENSION_THRESHOLD, check_tension_threshold,
             schema.DEFAULT_TENSION_THRESHOLD)):
        value = _get(prim, name, time)
        refuse(check(value, path))
        controls.append(fallback if value is None else float(value))
    return WrinkleParams(q, width, scale, height, gradient, iterations, *controls)
