"""The codeless WrinkleAPI schema: plugin registration, names and fallbacks.

``import usdwrinkle`` registers ``schemas/plugInfo.json`` with USD's plugin
registry. USD builds its schema registry once, the first time anything asks for
it (a typed prim, ``Usd.SchemaRegistry()``); a plugin registered after that is
not seen, and ApplyAPI fails. We detect that case and say how to fix it.
"""
from __future__ import annotations

import os

from pxr import Plug, Usd

from ._resources import resource_dir
from .errors import SchemaRegistrationError

API_NAME = "WrinkleAPI"
Q = "primvars:wrinkle:q"
WIDTH = "primvars:wrinkle:width"
AMPLITUDE_SCALE = "wrinkle:amplitudeScale"
HEIGHT_PROFILE = "wrinkle:heightProfile"
GRADIENT_PROFILE = "wrinkle:gradientProfile"
RELAX_ITERATIONS = "wrinkle:relaxIterations"
BIAXIAL = "wrinkle:biaxial"
TENSION = "wrinkle:tension"
TENSION_THRESHOLD = "wrinkle:tensionThreshold"
#: the Material interface inputs that ``bake --maps`` writes: map kind -> input name
MAP_INPUTS = {"normal": "wrinkleNormalFile", "height": "wrinkleHeightFile",
              "amplitude": "wrinkleAmplitudeFile"}
#: fallbacks of the beyond-the-paper controls: both off, onset at 2% strain
DEFAULT_BIAXIAL = 0.0
DEFAULT_TENSION = 0.0
DEFAULT_TENSION_THRESHOLD = 0.02

#: Fallback width: this multiple of the mean rest edge length of the mesh.
WIDTH_EDGE_MULTIPLE = 4.0
#: Samples of the default (cosine) profile.
PROFILE_SAMPLES = 256
DEFAULT_RELAX_ITERATIONS = 8

_state = {"registered": False, "usable": False}


def schema_dir() -> str:
    """The folder that other USD processes need in ``PXR_PLUGINPATH_NAME``."""
    return str(resource_dir("schemas"))


def register() -> bool:
    """Register the plugin; return True when WrinkleAPI is usable in this process."""
    if not _state["registered"]:
        Plug.Registry().RegisterPlugins(schema_dir())
        _state["registered"] = True
    _state["usable"] = Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(API_NAME) is not None
    return _state["usable"]


def require_schema() -> None:
    """Raise a clear error when the schema registry was built before registration."""
    if _state["usable"] or register():
        return
    raise SchemaRegistrationError(
        "the WrinkleAPI schema is not known to USD: the schema registry was built before "
        "usdwrinkle registered its plugin. Import usdwrinkle before anything else that uses "
        f"USD schemas, or set PXR_PLUGINPATH_NAME={schema_dir()}{os.pathsep}$PXR_PLUGINPATH_NAME")


def has_wrinkle_api(prim: Usd.Prim) -> bool:
    """True when WrinkleAPI is applied (works even if the schema is unknown)."""
    return API_NAME in prim.GetAppliedSchemas() or API_NAME in (
        prim.GetMetadata("apiSchemas").GetAddedOrExplicitItems()
        if prim.HasMetadata("apiSchemas") else [])
