"""ApplyJob: author WrinkleAPI on meshes (q painted from textures or primvars, widths,
profiles, the cloth controls), every value checked with the rules of ``check`` before the
first edit, written atomically to the root layer or an override layer."""
from __future__ import annotations

import fnmatch
import logging
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..method.contract import DRAWN_SLACK  # noqa: F401  (the slack's help)
from ..process.errors import UsdWrinkleError
from ..usd.schema import (  # noqa: F401  (what the command line's help says of the fallbacks)
    CLOTH_TOKENS,
    CLOTH_WIDTHS_M,
    DEFAULT_CLOTH,
    DEFAULT_CREST_DAMPING,
    DEFAULT_IRREGULARITY,
    DEFAULT_SLACK,
    WIDTH_EDGE_MULTIPLE,
)
from .options import ApplyOptions

_log = logging.getLogger(__name__)


def _split(path: str) -> list[str]:
    return [part for part in path.split("/") if part]


def _match(parts: list[str], pattern: list[str]) -> bool:
    if not pattern:
        return not parts
    head = pattern[0]
    if head == "**":
        return any(_match(parts[i:], pattern[1:]) for i in range(len(parts) + 1))
    return bool(parts) and fnmatch.fnmatchcase(parts[0], head) and _match(parts[1:], pattern[1:])


def match_prims(stage: Any, patterns: list[str]) -> list[Any]:
    """Prims named by paths or patterns, in stage order; an error for a pattern with no match."""
    from pxr import Usd

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


def parse_q(text: str) -> tuple[np.ndarray, float]:
    try:
        direction, amount_text = text.split(":")
        vector = [float(v) for v in direction.split(",")]
        amount = float(amount_text)
        if len(vector) != 3:
            raise ValueError
    except ValueError:
        raise UsdWrinkleError(f"bad `q` '{text}' (use X,Y,Z:AMOUNT, e.g. 1,0,0:0.5)") from None
    if not 0.0 <= amount <= 1.0:
        raise UsdWrinkleError(f"`q` amount {amount} is outside [0, 1]")
    return np.array(vector), amount


def read_profile(spec: str) -> np.ndarray:
    from ..method.profiles import PRESETS, profile_from_curve, profile_preset

    if spec in PRESETS:
        return profile_preset(spec)
    if not os.path.isfile(spec):
        raise UsdWrinkleError(f"`profile` '{spec}' is neither a preset ({', '.join(PRESETS)}) "
                              "nor a file")
    try:
        values = np.loadtxt(spec, delimiter=None if "," not in open(spec).read() else ",",
                            ndmin=1)
    except ValueError as exc:
        raise UsdWrinkleError(f"cannot read profile file '{spec}': {exc}") from None
    return profile_from_curve(values)


def open_override_layer(path: str) -> Any:
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
    irregularity: float | None = None
    held: np.ndarray | None = None


def check_options(args: ApplyOptions) -> None:
    """Refuse option combinations before the stage is read."""
    q_sources = [args.q, args.q_from_texture, args.q_from_primvar, args.clear_q]
    if sum(bool(s) for s in q_sources) > 1:
        raise UsdWrinkleError("choose one of `q`, `q_from_texture`, `q_from_primvar`, `clear_q`")
    if args.width_from_texture and args.width is None:
        raise UsdWrinkleError("`width_from_texture` scales `width`: give `width` too")


def edit_target(args: ApplyOptions, stage: Any) -> tuple[Any, Any]:
    """(stage to edit, layer that receives the edits): the root layer, or the -o layer."""
    from pxr import Usd

    from ..outputs.layers import check_layer_path
    from ..scene.stage import refuse_overwriting_inputs

    if not args.output:
        target = stage.GetRootLayer()
        if not target.realPath or target.realPath.lower().endswith(".usdz"):
            raise UsdWrinkleError(f"cannot edit '{args.stage}' in place (a .usdz package); "
                                  "use `output` LAYER")
        return stage, target
    check_layer_path(args.output)
    root = stage.GetRootLayer()
    if root.realPath and _same_file(args.output, root.realPath.split("[")[0]):
        # `output` means "leave my stage alone": never the stage itself, by any spelling
        # (./, .., //, a symlink, a symlinked folder, a hard link)
        raise UsdWrinkleError(f"`output` '{args.output}' is the stage itself; leave "
                              "`output` out to edit the stage in place, or name a new "
                              "override layer")
    try:
        refuse_overwriting_inputs(args.stage, [args.output], stage)
    except UsdWrinkleError:
        # an override layer the shot already sublayers (the usual assembly: the shot's
        # own layer over a read-only package) is edited where it is
        layer = _sublayer_named(stage, args.output)
        if layer is None:
            raise UsdWrinkleError(
                f"`output` '{args.output}' is a file the stage reads but not one of its own "
                "layers (a package, a referenced layer or a texture); choose a new override "
                "layer, or name a layer of the shot's layer stack") from None
        stage.SetEditTarget(Usd.EditTarget(layer))
        return stage, layer
    override = open_override_layer(args.output)
    stage = Usd.Stage.Open(stage.GetRootLayer(), override)
    stage.SetEditTarget(Usd.EditTarget(override))
    return stage, override


def _same_file(a: str, b: str) -> bool:
    """Whether two paths name one file: by real path, or by inode (a hard link)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _sublayer_named(stage: Any, path: str) -> Any:
    """The layer of the stage's local layer stack at ``path`` (not the root layer, not
    inside a package), or None."""

    for layer in stage.GetLayerStack(includeSessionLayers=False)[1:]:
        real = layer.realPath
        if real and "[" not in real and not real.lower().endswith(".usdz") and \
                _same_file(real, path):
            return layer
    return None


def target_meshes(stage: Any, patterns: list[str]) -> list[Any]:
    """The Mesh prims named by ``patterns``; an error for a non-mesh named literally, or a
    mesh inside an instance."""
    from pxr import UsdGeom

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


def plan_edits(args: ApplyOptions, meshes: list[Any], q_spec: Any = None,
               profile: Any = None) -> list[MeshEdit]:
    """Compute and check every value before the first edit (nothing is authored here), so
    that a refusal writes nothing. ``q_spec``: parse_q(--q); ``profile``: read_profile."""
    from ..authoring.qsources import (
        MeshSurface,
        q_from_flow_map,
        q_from_primvar,
        q_uniform,
        width_from_texture,
    )
    from ..usd.validation import (
        check_amplitude_scale,
        check_biaxial,
        check_cloth,
        check_crest_damping,
        check_held,
        check_irregularity,
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
        surface: Any = MeshSurface(prim) if needs_surface else None
        plan = MeshEdit(prim, clear_q=bool(args.clear_q),
                        amplitude_scale=args.amplitude_scale, profile=profile,
                        biaxial=args.biaxial, tension=args.tension,
                        tension_threshold=args.tension_threshold, cloth=args.cloth,
                        slack=args.slack, crest_damping=args.crest_damping,
                        irregularity=args.irregularity)
        if args.held_from_primvar:
            plan.held = held_from_primvar(prim, args.held_from_primvar)
        if q_spec is not None:
            plan.q = q_uniform(surface, *q_spec)
        elif args.q_from_texture:
            plan.q = q_from_flow_map(surface, args.q_from_texture, args.uv, args.amount_channel)
        elif args.q_from_primvar:
            plan.q = q_from_primvar(surface, args.q_from_primvar)
        if args.width_from_texture:
            # check_options: width_from_texture comes with width
            plan.width = width_from_texture(surface, args.width_from_texture,
                                            float(args.width or 0.0), args.uv)
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
        findings += check_irregularity(plan.irregularity, path)
        findings += check_held(plan.held, count, path)
        refuse(findings)
        from pxr import UsdGeom


        if plan.cloth is not None and plan.width is None and \
                UsdGeom.PrimvarsAPI(prim).GetPrimvar("wrinkle:width").HasAuthoredValue():
            _log.warning(f"`cloth` {plan.cloth} sets no width on {path}: it authors "
                         "primvars:wrinkle:width, which wins over the cloth preset (pass "
                         "`width` too, or remove that primvar)")
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
            api.CreateWidthPrimvar(plan.width)  # type: ignore[no-untyped-call]
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
             ("crest_damping", "CreateCrestDampingAttr"),
             ("irregularity", "CreateIrregularityAttr"), ("held", "CreateHeldPrimvar"))


def held_from_primvar(prim: Any, name: str) -> np.ndarray:
    """A mesh's float primvar as held weights, one per point (refused when it is not one
    value per point or a constant)."""
    from pxr import UsdGeom

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
    from ..usd.values import static_flattened

    value = static_flattened(primvar)
    try:
        return np.atleast_1d(np.asarray(value, np.float32)).ravel()
    except (TypeError, ValueError) as exc:
        raise UsdWrinkleError(f"primvar {name!r} is not a float array ({exc})",
                              str(prim.GetPath())) from None


def export(layer: Any, destination: str) -> None:
    """Write the edited layer atomically; a symlinked stage is edited in its real file."""
    from ..outputs.atomic import atomic_path, check_writable
    from ..outputs.layers import export_layer

    destination = os.path.realpath(destination)
    check_writable([destination])
    with atomic_path(destination) as tmp:
        export_layer(layer, tmp, destination)


@dataclass(frozen=True)
class ApplyResult:
    """How many meshes were edited, and the layer the edits went to."""

    meshes: int
    layer: str


class ApplyJob:
    """Apply and author WrinkleAPI as ``options`` say; nothing is written unless every
    value passes."""

    def __init__(self, options: ApplyOptions):
        self.options = options

    def run(self) -> ApplyResult:
        from ..scene.stage import open_stage
        from ..usd.schema import require_schema

        options = self.options
        require_schema()
        check_options(options)
        # a malformed q or profile is refused before the stage is read
        q_spec = parse_q(options.q) if options.q else None
        profile = read_profile(options.profile) if options.profile else None
        stage, target = edit_target(options, open_stage(options.stage))
        plans = plan_edits(options, target_meshes(stage, list(options.prim_paths)), q_spec,
                           profile)
        author(plans)
        destination = options.output or target.realPath
        export(target, destination)
        return ApplyResult(len(plans), os.path.realpath(destination))
