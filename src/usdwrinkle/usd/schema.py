"""The codeless WrinkleAPI schema: plugin registration, names and fallbacks.

``import usdwrinkle`` registers ``schemas/plugInfo.json`` with USD's plugin
registry. USD builds its schema registry once, the first time anything asks for
it (a typed prim, ``Usd.SchemaRegistry()``); a plugin registered after that is
not seen, and ApplyAPI fails. We detect that case and say how to fix it.
"""
from __future__ import annotations

import os

from pxr import Plug, Tf, Usd

from ..process._resources import resource_dir
from ..process.errors import SchemaRegistrationError

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
CLOTH = "wrinkle:cloth"
SLACK = "wrinkle:slack"
HELD = "primvars:wrinkle:held"
CREST_DAMPING = "wrinkle:crestDamping"
IRREGULARITY = "wrinkle:irregularity"
#: the Material interface inputs that ``bake --maps`` writes: map kind -> input name
#: the baked wave fields on disk (bake writes them, a render reads them back): primvar ->
#: (WrinkleFields/BakedFields attribute, components), vertex interpolation, one time
#: sample per frame; in the order the layer writes them
BAKED_PRIMVARS = {
    "primvars:wrinkle:amplitude": ("amplitude", 1),
    "primvars:wrinkle:compression": ("compression", 1),
    "primvars:wrinkle:waveVector": ("wave_vector", 3),
    "primvars:wrinkle:phase": ("phase", 1),
    "primvars:wrinkle:direction": ("direction", 3),
    # the deepened pleats' offset along the normal (method/deepen.py); optional: a bake
    # made before it was drawn has none, and draws none
    "primvars:wrinkle:offset": ("offset", 1),
    # the second wave system (wrinkle:biaxial): all three, or none
    "primvars:wrinkle:amplitude2": ("amplitude2", 1),
    "primvars:wrinkle:waveVector2": ("wave_vector2", 3),
    "primvars:wrinkle:phase2": ("phase2", 1),
    # its rest direction and compression, which the irregular blend reads for it (since
    # 2026-12-07; a bake made before has none, and draws zeros and ones there)
    "primvars:wrinkle:direction2": ("direction2", 3),
    "primvars:wrinkle:compression2": ("compression2", 1),
}
#: what a mesh's bake must hold to be drawn from it
BAKED_REQUIRED = ("primvars:wrinkle:amplitude", "primvars:wrinkle:waveVector",
                  "primvars:wrinkle:phase")
BAKED_SECOND_REQUIRED = ("primvars:wrinkle:amplitude2", "primvars:wrinkle:waveVector2",
                         "primvars:wrinkle:phase2")
BAKED_SECOND_SYSTEM = (*BAKED_SECOND_REQUIRED, "primvars:wrinkle:direction2",
                       "primvars:wrinkle:compression2")


def baked_names_text() -> str:
    """The baked primvars as bake's help names them."""
    def short(names):
        return ", ".join(name.rsplit(":", 1)[-1] for name in names)
    first = [n for n in BAKED_PRIMVARS if n not in BAKED_SECOND_SYSTEM]
    return (f"primvars:wrinkle:{short(first)}; with wrinkle:biaxial also "
            f"{short(BAKED_SECOND_SYSTEM)}")


#: the wrinkle maps' own texture coordinates (bake --map-layout islands; faceVarying):
#: one island per face, maps/islands.py
MAP_ST = "wrinkleMapST"
MAP_INPUTS = {"normal": "wrinkleNormalFile", "height": "wrinkleHeightFile",
              "amplitude": "wrinkleAmplitudeFile",
              # the texture deformation's inputs (bake --maps parallax; maps/material.py)
              "parallaxN": "wrinkleParallaxNormalFile", "parallaxS": "wrinkleParallaxSFile",
              "parallaxT": "wrinkleParallaxTFile"}
#: UsdPreviewSurface's inputs that a bake's MaterialX network copies from the look
#: (scene/material.look_inputs, maps/mtlx.py), with their MaterialX types
PREVIEW_SURFACE_TYPES = {"diffuseColor": "color3", "emissiveColor": "color3",
                         "useSpecularWorkflow": "integer", "specularColor": "color3",
                         "metallic": "float", "roughness": "float", "clearcoat": "float",
                         "clearcoatRoughness": "float", "opacity": "float",
                         "opacityThreshold": "float", "ior": "float", "occlusion": "float"}
#: fallbacks of the beyond-the-paper controls: both off, onset at 2% strain
DEFAULT_BIAXIAL = 0.0
DEFAULT_TENSION = 0.0
DEFAULT_TENSION_THRESHOLD = 0.02

#: Fallback width: the cloth's (wrinkle:cloth) onset fold wavelength in metres on flat
#: cloth (W: the posed wavelength folds keep while they coarsen, docs/method.md), from
#: the cloth referee's curtains and sheared panels at its solver's convergence (Newton's
#: VBD at 160 iterations on a 2 cm grid, 1 cm where a 1 cm run differs: the three curtains
#: and both panels; benchmarks/physics/referee.py CONVERGED, CONVERGED_FINER;
#: docs/physics.md): for silk, cotton and leather (bending 2.5e-6, 1e-5 and 1.6e-4 N m)
#: the W whose worst wavelength ratio over the cloth's flat shots (its curtain's phases
#: from 8% to 48% compression and, for cotton and leather, its sheared panel's, and for
#: cotton the 25 cm sleeve's, whose W is the flat one) is smallest (cotton 1.23x, leather
#: 1.19x: 16.8 cm until its curtain's 1 cm run, which folds 0.7x as long as its 2 cm one).
#: Denim (4e-5 N m) between cotton and leather by their power law in D (the geometric
#: mean).
#: Converted to scene units through the stage's metersPerUnit.
CLOTH_WIDTHS_M = {"silk": 0.072, "cotton": 0.095, "denim": 0.107, "leather": 0.120}
#: On curved cloth (a sleeve, a trouser leg) the fallback width is the tube's, whatever the
#: cloth: CURVED_WIDTH_M at a rest radius of curvature of CURVED_RADIUS_M, as (R /
#: CURVED_RADIUS_M) ** CURVED_EXPONENT (R the point's smallest radius of curvature, never
#: taken below CURVED_RADIUS_MIN_M), and never wider than the cloth's flat width. Shell
#: buckling theory's 1/2 (an axially compressed cylinder's 3.5 sqrt(R t)); W_c from the
#: converged referee's sleeves, whose cotton and silk fold alike and whose folds do not
#: coarsen (their matched W 7.0-7.8 cm at 10 cm; 6 cm while the law coarsened them;
#: docs/physics.md)
CURVED_WIDTH_M = 0.077
CURVED_RADIUS_M = 0.10
CURVED_EXPONENT = 0.5
CURVED_RADIUS_MIN_M = 0.02
DEFAULT_CLOTH = "cotton"
#: wrinkle:cloth = "mesh": the width follows the mesh, this multiple of its mean rest edge
#: length (the fallback before the cloth oracle)
MESH_CLOTH = "mesh"
WIDTH_EDGE_MULTIPLE = 4.0
CLOTH_TOKENS = (*CLOTH_WIDTHS_M, MESH_CLOTH)
#: wrinkle:slack fallback: the compression before the crests settle (the relaxation weighs
#: the folds beyond it); the folds are drawn from contract.DRAWN_SLACK of it on, the share
#: the cloth takes in-plane. 0: the Newton referee's cloth keeps its area
#: (docs/physics.md), and with the inextensible law a slack c leaves the wrinkled surface
#: 1 - DRAWN_SLACK c of its rest area
DEFAULT_SLACK = 0.05
#: wrinkle:crestDamping fallback: the band (degrees) within which the compression
#: direction holds where the cloth folds, followed beyond it (docs/method.md: crest
#: damping). 0.5-3 degrees hold the converged referee's held sleeves' crests alike
#: (docs/physics.md); within 1 degree a trembling input's turn comes through
DEFAULT_CREST_DAMPING = 1.5
#: wrinkle:irregularity fallback: folds of unequal width (method/contract.py,
#: IRREGULARITY_*; docs/method.md, "Irregular folds"). 0.15 since 2026-12-07 (0 before:
#: the paper's regular waves): every referee shot's area where compressed comes into
#: issue 55's bar and no bar that held breaks (docs/physics.md, the irregularity block);
#: 0.3, the cloth's own spread, lengthens the measured folds past the presets' fit
DEFAULT_IRREGULARITY = 0.15
#: and its largest value (check refuses more): at 0.5 the local wave number's variation
#: is half its mean, and its wave sometimes turns back
IRREGULARITY_MAX = 0.5
#: wrinkle:held: waves reach full amplitude this many widths W away from a held point
HELD_REACH = 2.0
#: Samples of a height profile over one period (the default: profiles.default_profile).
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
    try:
        registry = Usd.SchemaRegistry()
    except Tf.ErrorException as exc:
        # a plugInfo.json on PXR_PLUGINPATH_NAME that cannot be read: USD raises once,
        # skips that plugin, and the registry it built serves every later call
        from ..process.log import warn
        from .diagnostics import usd_error_text

        warn(f"USD skipped a plugin ({usd_error_text(exc)}); check "
             "PXR_PLUGINPATH_NAME")
        registry = Usd.SchemaRegistry()
    _state["usable"] = registry.FindAppliedAPIPrimDefinition(API_NAME) is not None
    return _state["usable"]


def require_schema() -> None:
    """Raise a clear error when the schema registry was built before registration."""
    if _state["usable"] or register():
        return
    raise SchemaRegistrationError(
        "the WrinkleAPI schema is not known to USD: the schema registry was built before "
        "usdwrinkle registered its plugin. Import usdwrinkle before anything else that uses "
        f"USD schemas, or set PXR_PLUGINPATH_NAME={schema_dir()}{os.pathsep}$PXR_PLUGINPATH_NAME")


#: the artist's controls, WrinkleAPI's attributes (a prim authoring one is meant to be
#: wrinkled), in the order check reports their findings
CONTROL_ATTRIBUTES = (Q, WIDTH, HEIGHT_PROFILE, GRADIENT_PROFILE, AMPLITUDE_SCALE,
                      RELAX_ITERATIONS, BIAXIAL, TENSION, TENSION_THRESHOLD, CLOTH, SLACK,
                      HELD, CREST_DAMPING, IRREGULARITY)


def unapplied_controls(stage: Usd.Stage) -> list[str]:
    """Meshes that author WrinkleAPI's controls without WrinkleAPI applied.

    The usual cause is an ``apiSchemas`` list op that names an item twice: USD drops
    such a list whole when it reads the layer, with no message, so the mesh loses every
    API schema it listed (WrinkleAPI, MaterialBindingAPI, SkelBindingAPI)."""
    found = []
    for prim in stage.Traverse():
        if prim.GetTypeName() != "Mesh" or has_wrinkle_api(prim):
            continue
        if any(prim.GetAttribute(name).HasAuthoredValue() for name in CONTROL_ATTRIBUTES
               if prim.HasAttribute(name)):
            found.append(str(prim.GetPath()))
    return found


def unapplied_message(paths: list[str]) -> str:
    """One sentence naming the meshes of :func:`unapplied_controls`."""
    shown = ", ".join(paths[:3]) + (f" and {len(paths) - 3} more" if len(paths) > 3 else "")
    return (f"{shown} author{'s' if len(paths) == 1 else ''} wrinkle controls but "
            "WrinkleAPI is not applied: USD discards an apiSchemas list that names an item "
            "twice, with no message; list WrinkleAPI once (or run usdwrinkle apply)")


def has_wrinkle_api(prim: Usd.Prim) -> bool:
    """True when WrinkleAPI is applied (works even if the schema is unknown)."""
    return API_NAME in prim.GetAppliedSchemas() or API_NAME in (
        prim.GetMetadata("apiSchemas").GetAddedOrExplicitItems()
        if prim.HasMetadata("apiSchemas") else [])
