"""usdwrinkle check STAGE [--json]: USD's own validators plus the WrinkleAPI rules."""
from __future__ import annotations

import json
import sys

#: UsdValidation keywords run by ``check``: core, UsdGeom, UsdSkel and our own.
KEYWORDS = ("UsdCoreValidators", "UsdGeomValidators", "UsdSkelValidators",
            "UsdShadeValidators", "UsdWrinkleValidators")


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "check", help="validate a stage: USD's validators and the WrinkleAPI rules",
        description="Run UsdValidation's core, UsdGeom, UsdSkel and UsdShade validators and "
                    "usdwrinkle's WrinkleAPI checker (registered with UsdValidation as "
                    "usdWrinkleValidators:WrinkleAPIChecker). Exit 0 when clean, 1 with "
                    "findings, 2 on usage errors.")
    p.add_argument("stage", help="the USD stage")
    from .common import add_composition_args

    add_composition_args(p)
    p.add_argument("--json", action="store_true", help="machine-readable output on stdout")
    p.add_argument("--wrinkles-only", action="store_true",
                   help="run only usdwrinkle's WrinkleAPI checker, so that the exit code "
                        "gates on the wrinkle attributes alone (USD's own findings, such as "
                        "upAxis or defaultPrim, are left to usdchecker)")
    p.set_defaults(run=run)


def _site(error) -> tuple[str, str | None]:
    for site in error.GetSites():
        if site.IsProperty():
            path = site.GetProperty().GetPath()
            return str(path.GetPrimPath()), path.name
        if site.IsPrim():
            return str(site.GetPrim().GetPath()), None
    return "/", None


def collect(stage, keywords=KEYWORDS) -> list[dict]:
    """Findings of the validators of ``keywords``, as dicts (path, attribute, message,
    validator, type)."""
    from pxr import UsdValidation

    from ..validation import register_validators

    register_validators()
    context = UsdValidation.ValidationContext(keywords=list(keywords))
    findings = []
    for error in context.Validate(stage):
        if error.HasNoError():
            continue
        path, attribute = _site(error)
        validator = error.GetValidator()
        findings.append({
            "prim": path, "attribute": attribute, "message": error.GetMessage(),
            "type": str(error.GetType()).rsplit(".", 1)[-1].lower(),
            "validator": str(validator.GetMetadata().name) if validator else "",
        })
    findings.sort(key=lambda f: (f["prim"], f["attribute"] or "", f["validator"], f["message"]))
    return findings


def run(args) -> int:
    from ..scene.stage import open_stage
    from .common import shot_options

    stage = open_stage(args.stage, shot_options(args).composition())
    findings = collect(stage, ("UsdWrinkleValidators",)) if args.wrinkles_only else \
        collect(stage)
    scene = read_scene(stage)
    findings += units_findings(stage, scene) + unapplied_findings(stage)
    widths = effective_widths(scene)
    if args.json:
        # strict JSON: a value that is not finite is null (NaN is not JSON)
        json.dump(_finite({"stage": args.stage, "findings": findings, "clean": not findings,
                           "widths": widths}), sys.stdout, indent=2, allow_nan=False)
        sys.stdout.write("\n")
    else:
        for f in findings:
            where = f["prim"] + (f".{f['attribute']}" if f["attribute"] else "")
            print(f"{f['type']}: {where}: {f['message']} [{f['validator']}]")
        for entry in widths:
            print(f"width: {entry['prim']}: {entry['text']}")
        print(f"usdwrinkle: {len(findings)} finding(s) in {args.stage}" if findings
              else f"usdwrinkle: {args.stage} is clean")
    return 1 if findings else 0


def _finite(value):
    """``value`` with every float that is not finite replaced by None."""
    import math

    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(item) for item in value]
    return value


def read_scene(stage):
    """The scene delegate's reading of ``stage`` (what render resolves), read once for the
    units and widths below; None where the stage cannot be read that far (the findings
    say why)."""
    from ..errors import UsdWrinkleError
    from ..log import silenced
    from ..scene.stage import StageSceneDelegate

    try:
        with silenced():  # the findings report what is wrong
            return StageSceneDelegate(stage, use_baked=False)
    except UsdWrinkleError:
        return None


def units_findings(stage, scene) -> list[dict]:
    """The stage's metersPerUnit where render and bake refuse it (an error), or where
    they warn about it (a warning: scene.params.units_notes)."""
    from ..errors import UsdWrinkleError
    from ..scene.params import stage_meters, units_notes

    try:
        stage_meters(stage)
    except UsdWrinkleError as exc:
        return [{"prim": "/", "attribute": "metersPerUnit", "message": exc.what,
                 "type": "error", "validator": "usdWrinkleValidators:Units"}]
    if scene is None:
        return []
    return [{"prim": "/", "attribute": "metersPerUnit", "message": note, "type": "warning",
             "validator": "usdWrinkleValidators:Units"}
            for note in units_notes(stage, scene.meshes)]


def unapplied_findings(stage) -> list[dict]:
    """Meshes authoring wrinkle controls without WrinkleAPI (schema.unapplied_controls):
    render draws them unwrinkled."""
    from .. import schema

    return [{"prim": path, "attribute": "apiSchemas", "type": "error",
             "validator": "usdWrinkleValidators:WrinkleAPI",
             "message": "authors wrinkle controls but WrinkleAPI is not applied, so it "
                        "renders without wrinkles (USD discards an apiSchemas list that "
                        "names an item twice, with no message)"}
            for path in schema.unapplied_controls(stage)]


def effective_widths(scene) -> list[dict]:
    """The width W each wrinkled mesh gets (authored, or its cloth's through the stage's
    metersPerUnit), as the scene delegate resolves it; none without a scene."""
    from ..scene.params import width_summary

    if scene is None:
        return []
    return [{"prim": path, **width_summary(record.params)}
            for path, record in sorted(scene.meshes.items()) if record.wrinkled]
