"""Wrinkle parameters from WrinkleAPI attributes, with fallbacks and validation."""
from __future__ import annotations

import numpy as np
from pxr import Usd, UsdGeom

from .. import schema
from ..profiles import cosine_profile, derive_gradient
from ..validation import parameter_findings, refuse
from ..values import static_flattened, static_value
from .records import WrinkleParams
from .topology import Topology, mean_edge_length


def _get(prim: Usd.Prim, name: str):
    """An authored WrinkleAPI value by the static rule (None if unauthored)."""
    attr = prim.GetAttribute(name)
    if not attr or not attr.HasAuthoredValue():
        return None
    return static_value(attr)


def _primvar(prim: Usd.Prim, name: str):
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar(name)
    if not primvar or not primvar.HasAuthoredValue():
        return None
    return static_flattened(primvar)


def _profile(prim, name):
    value = _get(prim, name)
    return None if value is None or len(value) == 0 else np.asarray(value, dtype=np.float32)


def read_params(prim: Usd.Prim, rest_points: np.ndarray, topology: Topology,
                relax_override: int | None = None, warn=None) -> WrinkleParams:
    """Resolve WrinkleAPI values for one mesh (also for --all-meshes, with fallbacks).

    Every value is checked as ``usdwrinkle check`` checks it, at the default time and at
    every time sample, and the first that breaks a rule is refused with a
    UsdWrinkleError naming the prim and the attribute. WrinkleAPI values do not
    animate: each is read once, at the default time, else at its first time sample; a
    value that changes over time goes to ``warn``.
    """
    n = len(rest_points)
    findings = parameter_findings(prim, n)
    refuse([f for f in findings if f.severity == "error"])
    if warn is not None:
        for finding in findings:
            warn(finding.one_line())

    q = np.zeros((n, 3), np.float32)
    value = _primvar(prim, "wrinkle:q")
    if value is not None:
        q = np.asarray(value, dtype=np.float32).reshape(-1, 3)

    value = _primvar(prim, "wrinkle:width")
    if value is not None:
        arr = np.atleast_1d(np.asarray(value, dtype=np.float32))
        width = np.broadcast_to(arr, (n,)).astype(np.float32)
    else:
        fallback = schema.WIDTH_EDGE_MULTIPLE * mean_edge_length(rest_points, topology)
        width = np.full(n, fallback if fallback > 0 else 1.0, np.float32)

    scale = _get(prim, schema.AMPLITUDE_SCALE)
    scale = 1.0 if scale is None else float(scale)

    height = _profile(prim, schema.HEIGHT_PROFILE)
    gradient = _profile(prim, schema.GRADIENT_PROFILE)
    if height is None:
        height = cosine_profile()
    if gradient is None:
        gradient = derive_gradient(height)

    iterations = _get(prim, schema.RELAX_ITERATIONS)
    if relax_override is not None:
        iterations = relax_override  # the CLI checked it
    iterations = schema.DEFAULT_RELAX_ITERATIONS if iterations is None else int(iterations)

    controls = []
    for name, fallback in ((schema.BIAXIAL, schema.DEFAULT_BIAXIAL),
                           (schema.TENSION, schema.DEFAULT_TENSION),
                           (schema.TENSION_THRESHOLD, schema.DEFAULT_TENSION_THRESHOLD)):
        value = _get(prim, name)
        controls.append(fallback if value is None else float(value))
    return WrinkleParams(q, width, scale, height, gradient, iterations, *controls)
