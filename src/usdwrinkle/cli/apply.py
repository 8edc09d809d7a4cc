"""usdwrinkle apply: author WrinkleAPI on meshes, with q painted from textures."""
from __future__ import annotations

import fnmatch
import os
from dataclasses import dataclass

import numpy as np

from .. import schema
from ..errors import print_stderr


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "apply", help="apply and author WrinkleAPI on meshes (q from textures, widths, profiles)",
        description="Apply WrinkleAPI to the meshes that PRIM_PATH names and author its "
                    "attributes. PRIM_PATH may be a pattern: '*' matches within a path "
                    "element, '**' matches any number of elements (/World/**/Shirt*). "
                    "Edits go to the stage's root layer, or with -o to an override layer of "
                    "sparse overs that sublayers nothing. Every value is checked with the "
                    "rules of 'usdwrinkle check'; a bad one is refused and nothing is written.")
    p.add_argument("stage", help="the USD stage")
    p.add_argument("prim_paths", nargs="+", metavar="PRIM_PATH", help="mesh paths or patterns")
    p.add_argument("-o", "--output", metavar="LAYER",
                   help="write the edits to this override layer (created or updated) instead "
                        "of the root layer")
    p.add_argument("--width", type=float, metavar="W",
                   help="rest wavelength W (scene units); without it, and with no "
                        "primvars:wrinkle:width authored, a mesh uses its cloth's fold "
                        "wavelength (--cloth) through the stage's metersPerUnit")
    p.add_argument("--cloth", choices=schema.CLOTH_TOKENS,
                   help="wrinkle:cloth, the cloth whose fold wavelength is the fallback W: "
                        + ", ".join(f"{name} {100 * metres:g} cm"
                                    for name, metres in schema.CLOTH_WIDTHS_M.items())
                        + f"; mesh: {schema.WIDTH_EDGE_MULTIPLE:g} x the mean rest edge "
                        f"length (default {schema.DEFAULT_CLOTH})")
    p.add_argument("--slack", type=float, metavar="C",
                   help="wrinkle:slack in [0, 0.9], the compression the cloth takes in-plane "
                        f"before it buckles (default {schema.DEFAULT_SLACK:g}; 0: the "
                        "paper's law)")
    p.add_argument("--crest-damping", type=float, metavar="FRAMES",
                   help="wrinkle:crestDamping, the time constant in frames with which the "
                        "compression direction follows slight turns (default "
                        f"{schema.DEFAULT_CREST_DAMPING:g}; 0: none)")
    p.add_argument("--held-from-primvar", metavar="NAME",
                   help="author primvars:wrinkle:held from this float primvar of the mesh "
                        "(a painted pin or seam weight in [0, 1], vertex interpolation)")
    p.add_argument("--amplitude-scale", type=float, metavar="S",
                   help="amplitude scale s (default 1: the amplitude law of docs/method.md)")
    p.add_argument("--biaxial", type=float, metavar="WEIGHT",
                   help="wrinkle:biaxial in [0, 1]: a second wave where the cloth is "
                        "compressed both ways (0: off, the default)")
    p.add_argument("--tension", type=float, metavar="FACTOR",
                   help="wrinkle:tension >= 0: tension wrinkles along a pull (0: off, the "
                        "default)")
    p.add_argument("--tension-threshold", type=float, metavar="STRAIN",
                   help="wrinkle:tensionThreshold in [0, 1]: the strain where tension "
                        "wrinkles begin (fallback 0.02)")
    p.add_argument("--profile", metavar="NAME|FILE",
                   help="height profile: cosine (the default), sharp, rounded, box, triangle, "
                        "or a text file of heights over one period (or 'theta height' pairs)")
    p.add_argument("--q", metavar="X,Y,Z:AMOUNT",
                   help="uniform rest-space direction, projected onto each vertex's tangent "
                        "plane, with |q| = AMOUNT")
    p.add_argument("--q-from-texture", metavar="IMAGE",
                   help="flow map: RG = tangent direction in (u, v) as 2c-1, v up")
    p.add_argument("--uv", default="st", metavar="PRIMVAR",
                   help="texture coordinates for the texture options (st)")
    p.add_argument("--amount-channel", choices=("R", "G", "B", "A"), type=str.upper,
                   help="flow map channel with the amount (default: the decoded vector's length)")
    p.add_argument("--q-from-primvar", metavar="NAME",
                   help="convert a painted vertex primvar (vector, or colour as 2c-1) into q")
    p.add_argument("--width-from-texture", metavar="IMAGE",
                   help="grey map that scales the width per vertex (width becomes vertex)")
    p.add_argument("--clear-q", action="store_true", help="remove the painted q")
    p.set_defaults(run=run)


def _split(path: str) -> list[str]:
    return [part for part in path.split("/") if part]


def _match(parts: list[str], pattern: list[str]) -> bool:
    if not pattern:
        return not parts
    head = pattern[0]
    if head == "**":
        return any(_match(parts[i:], pattern[1:]) for i in range(len(parts) + 1))
    return bool(parts) and fnmatch.fnmatchcase(parts[0], head) and _match(parts[1:], pattern[1:])


def match_prims(stage, patterns: list[str]):
    """Prims named by paths or patterns, in stage order; an error for a pattern with no match."""
    from pxr import Usd

    from ..errors import UsdWrinkleError

    prims = list(stage.Traverse(Usd.TraverseInstanceProxies()))
    chosen = {}
    for pattern in patterns:
        if not pattern.startswith("/"):
            raise UsdWrinkleError(f"prim path '{pattern}' must be absolute (start with '/')")
        parts = _split(pattern)
        found = [p for p in prims if _match(_split(str(p.GetPath())), parts)]
        if not found:
            raise UsdWrinkleError(f"no prim matches '{pattern}'")
        for prim in found:
            chosen[str(prim.GetPath())] = prim
    return list(chosen.values())


def parse_q(text: str):
    from ..errors import UsdWrinkleError

    try:
        direction, amount = text.split(":")
        vector = [float(v) for v in direction.split(",")]
        amount = float(amount)
        if len(vector) != 3:
            raise ValueError
    except ValueError:
        raise UsdWrinkleError(f"bad --q '{text}' (use X,Y,Z:AMOUNT, e.g. 1,0,0:0.5)") from None
    if not 0.0 <= amount <= 1.0:
        raise UsdWrinkleError(f"--q amount {amount} is outside [0, 1]")
    return np.array(vector), amount


def read_profile(spec: str) -> np.ndarray:
    from ..errors import UsdWrinkleError
    from ..profiles import PRESETS, profile_from_curve, profile_preset

    if spec in PRESETS:
        return profile_preset(spec)
    if not os.path.isfile(spec):
        raise UsdWrinkleError(f"--profile '{spec}' is neither a preset ({', '.join(PRESETS)}) "
                              "nor a file")
    try:
        values = np.loadtxt(spec, delimiter=None if "," not in open(spec).read() else ",",
                            ndmin=1)
    except ValueError as exc:
        raise UsdWrinkleError(f"cannot read profile file '{spec}': {exc}") from None
    return profile_from_curve(values)


def open_override_layer(path: str):
    """The -o layer: an existing USD layer to update, or a new anonymous one."""
    from pxr import Sdf

    from ..scene.inputs import open_layer, require_regular_file

    if not os.path.exists(path):
        return Sdf.Layer.CreateAnonymous(os.path.splitext(path)[1])
    require_regular_file(path, "override layer")
    return open_layer(path, f"cannot open override layer '{path}' (an existing file that is "
                            "not a USD layer?)")


@dataclass
class MeshEdit:
    """What ``apply`` will author on one mesh (every value already checked)."""

    prim: object
    q: np.ndarray | None = None
    width: np.ndarray | None = None
    clear_q: bool = False
    amplitude_scale: float | None = None
    profile: np.ndarray | None = None
    biaxial: float | None = None
    tension: float | None = None
    tension_threshold: float | None = None
    cloth: str | None = None
    slack: float | None = None
    crest_damping: float | None = None
    held: np.ndarray | None = None


def check_args(args) -> None:
    """Refuse option combinations before the stage is read."""
    from ..errors import UsdWrinkleError

    q_sources = [args.q, args.q_from_texture, args.q_from_primvar, args.clear_q]
    if sum(bool(s) for s in q_sources) > 1:
        raise UsdWrinkleError("choose one of --q, --q-from-texture, --q-from-primvar, --clear-q")
    if args.width_from_texture and args.width is None:
        raise UsdWrinkleError("--width-from-texture scales --width: give --width too")


def edit_target(args, stage):
    """(stage to edit, layer that receives the edits): the root layer, or the -o layer."""
    from pxr import Usd

    from ..errors import UsdWrinkleError
    from ..outputs.layers import check_layer_path
    from ..scene.stage import refuse_overwriting_inputs

    if not args.output:
        target = stage.GetRootLayer()
        if not target.realPath or target.realPath.lower().endswith(".usdz"):
            raise UsdWrinkleError(f"cannot edit '{args.stage}' in place (a .usdz package); "
                                  "use -o LAYER")
        return stage, target
    check_layer_path(args.output)
    root = stage.GetRootLayer()
    if root.realPath and os.path.realpath(args.output) == os.path.realpath(root.realPath):
        if root.realPath.lower().endswith(".usdz"):
            raise UsdWrinkleError(f"cannot edit '{args.stage}' in place (a .usdz package); "
                                  "use -o LAYER")
        return stage, root  # -o the stage itself: edited in place, as without -o
    try:
        refuse_overwriting_inputs(args.stage, [args.output], stage)
    except UsdWrinkleError:
        # an override layer the shot already sublayers (the usual assembly: the shot's
        # own layer over a read-only package) is edited where it is
        layer = _sublayer_named(stage, args.output)
        if layer is None:
            raise UsdWrinkleError(
                f"-o '{args.output}' is a file the stage reads but not one of its own "
                "layers (a package, a referenced layer or a texture); choose a new override "
                "layer, or name a layer of the shot's layer stack") from None
        stage.SetEditTarget(Usd.EditTarget(layer))
        return stage, layer
    override = open_override_layer(args.output)
    stage = Usd.Stage.Open(stage.GetRootLayer(), override)
    stage.SetEditTarget(Usd.EditTarget(override))
    return stage, override


def _sublayer_named(stage, path: str):
    """The layer of the stage's local layer stack at ``path`` (not the root layer, not
    inside a package), or None."""
    import os

    wanted = os.path.realpath(path)
    for layer in stage.GetLayerStack(includeSessionLayers=False)[1:]:
        real = layer.realPath
        if real and "[" not in real and not real.lower().endswith(".usdz") and \
                os.path.realpath(real) == wanted:
            return layer
    return None


def target_meshes(stage, patterns: list[str]) -> list:
    """The Mesh prims named by ``patterns``; an error for a non-mesh named literally, or a
    mesh inside an instance."""
    from pxr import UsdGeom

    from ..errors import UsdWrinkleError

    prims = match_prims(stage, patterns)
    meshes = [p for p in prims if p.IsA(UsdGeom.Mesh)]
    if not meshes:
        raise UsdWrinkleError(f"no Mesh among the prims named ({', '.join(patterns)})")
    literal = [p for p in prims if not p.IsA(UsdGeom.Mesh) and str(p.GetPath()) in patterns]
    if literal:
        raise UsdWrinkleError("WrinkleAPI applies to Mesh prims only", str(literal[0].GetPath()))
    for prim in meshes:
        if prim.IsInstanceProxy():
            raise UsdWrinkleError("a mesh inside an instance cannot be edited; edit its "
                                  "prototype's source", str(prim.GetPath()))
    return meshes


def plan_edits(args, meshes: list, q_spec=None, profile=None) -> list[MeshEdit]:
    """Compute and check every value before the first edit (nothing is authored here), so
    that a refusal writes nothing. ``q_spec``: parse_q(--q); ``profile``: read_profile."""
    from ..authoring.paint import (
        MeshSurface,
        q_from_flow_map,
        q_from_primvar,
        q_uniform,
        width_from_texture,
    )
    from ..validation import (
        check_amplitude_scale,
        check_biaxial,
        check_cloth,
        check_crest_damping,
        check_held,
        check_q,
        check_slack,
        check_tension,
        check_tension_threshold,
        check_width,
        point_count,
        refuse,
    )

    needs_surface = q_spec is not None or args.q_from_texture or args.q_from_primvar \
        or args.width_from_texture
    plans = []
    for prim in meshes:
        surface = MeshSurface(prim) if needs_surface else None
        plan = MeshEdit(prim, clear_q=bool(args.clear_q),
                        amplitude_scale=args.amplitude_scale, profile=profile,
                        biaxial=args.biaxial, tension=args.tension,
                        tension_threshold=args.tension_threshold, cloth=args.cloth,
                        slack=args.slack, crest_damping=args.crest_damping)
        if args.held_from_primvar:
            plan.held = held_from_primvar(prim, args.held_from_primvar)
        if q_spec is not None:
            plan.q = q_uniform(surface, *q_spec)
        elif args.q_from_texture:
            plan.q = q_from_flow_map(surface, args.q_from_texture, args.uv, args.amount_channel)
        elif args.q_from_primvar:
            plan.q = q_from_primvar(surface, args.q_from_primvar)
        if args.width_from_texture:
            plan.width = width_from_texture(surface, args.width_from_texture, args.width,
                                            args.uv)
        elif args.width is not None:
            plan.width = np.array([args.width], np.float32)
        path, count = str(prim.GetPath()), point_count(prim)
        findings = []
        if plan.q is not None:
            findings += check_q(plan.q, "vertex", count, path)
        if plan.width is not None:
            findings += check_width(plan.width, count, path)
        findings += check_amplitude_scale(plan.amplitude_scale, path)
        findings += check_biaxial(plan.biaxial, path)
        findings += check_tension(plan.tension, path)
        findings += check_tension_threshold(plan.tension_threshold, path)
        findings += check_cloth(plan.cloth, path)
        findings += check_slack(plan.slack, path)
        findings += check_crest_damping(plan.crest_damping, path)
        findings += check_held(plan.held, count, path)
        refuse(findings)
        from pxr import UsdGeom

        from ..errors import print_warning

        if plan.cloth is not None and plan.width is None and \
                UsdGeom.PrimvarsAPI(prim).GetPrimvar("wrinkle:width").HasAuthoredValue():
            print_warning(f"--cloth {plan.cloth} sets no width on {path}: it authors "
                          "primvars:wrinkle:width, which wins over the cloth preset (pass "
                          "--width too, or remove that primvar)")
        plans.append(plan)
    return plans


def author(plans: list[MeshEdit]) -> None:
    """Author the planned edits on the stage's edit target (in memory)."""
    from ..authoring import WrinkleAPI

    for plan in plans:
        api = WrinkleAPI.Apply(plan.prim)
        if plan.q is not None:
            api.set_q(plan.q)
        if plan.clear_q:
            api.clear_q()
        if plan.width is not None:
            api.CreateWidthPrimvar(plan.width)
        if plan.profile is not None:
            api.set_profile(plan.profile)
        for field, create in _AUTHORED:
            value = getattr(plan, field)
            if value is not None:
                getattr(api, create)(value)


#: MeshEdit fields that author one WrinkleAPI property each, and the method that does
_AUTHORED = (("amplitude_scale", "CreateAmplitudeScaleAttr"), ("biaxial", "CreateBiaxialAttr"),
             ("tension", "CreateTensionAttr"),
             ("tension_threshold", "CreateTensionThresholdAttr"),
             ("cloth", "CreateClothAttr"), ("slack", "CreateSlackAttr"),
             ("crest_damping", "CreateCrestDampingAttr"), ("held", "CreateHeldPrimvar"))


def held_from_primvar(prim, name: str) -> np.ndarray:
    """A mesh's float primvar as held weights, one per point (refused when it is not one
    value per point or a constant)."""
    from pxr import UsdGeom

    from ..errors import UsdWrinkleError

    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar(name)
    if not primvar or not primvar.HasValue():
        raise UsdWrinkleError(f"no primvar {name!r} to read held weights from",
                              str(prim.GetPath()))
    if primvar.GetInterpolation() not in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying,
                                          UsdGeom.Tokens.constant):
        raise UsdWrinkleError(f"primvar {name!r} must have vertex or constant interpolation "
                              "to give held weights per point", str(prim.GetPath()))

    # held edges are a rest-pose property: the default value, else the first time sample
    # (a primvar authored only as time samples has no default)
    from ..values import static_flattened

    value = static_flattened(primvar)
    try:
        return np.atleast_1d(np.asarray(value, np.float32)).ravel()
    except (TypeError, ValueError) as exc:
        raise UsdWrinkleError(f"primvar {name!r} is not a float array ({exc})",
                              str(prim.GetPath())) from None


def export(layer, destination: str) -> None:
    """Write the edited layer atomically; a symlinked stage is edited in its real file."""
    from ..outputs.atomic import atomic_path, check_writable
    from ..outputs.layers import export_layer

    destination = os.path.realpath(destination)
    check_writable([destination])
    with atomic_path(destination) as tmp:
        export_layer(layer, tmp, destination)


def run(args) -> int:
    from ..scene.stage import open_stage
    from ..schema import require_schema

    require_schema()
    check_args(args)
    # a malformed --q or --profile is refused before the stage is read
    q_spec = parse_q(args.q) if args.q else None
    profile = read_profile(args.profile) if args.profile else None
    stage, target = edit_target(args, open_stage(args.stage))
    plans = plan_edits(args, target_meshes(stage, args.prim_paths), q_spec, profile)
    author(plans)
    destination = args.output or target.realPath
    export(target, destination)
    print_stderr(f"usdwrinkle: applied WrinkleAPI to {len(plans)} mesh(es) in "
          f"{os.path.realpath(destination)}")
    return 0
