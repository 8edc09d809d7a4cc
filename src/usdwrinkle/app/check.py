"""CheckJob: a stage validated as render and bake would read it: USD's own validators
(UsdValidation: core, UsdGeom, UsdSkel, UsdShade), usdwrinkle's WrinkleAPI checker, the
units the cloth widths go through, meshes with controls but no WrinkleAPI, and the width
each wrinkled mesh gets. ``usdwrinkle check`` prints its result."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .shot import Shot

#: UsdValidation keywords a check runs: core, UsdGeom, UsdSkel and our own.
KEYWORDS = ("UsdCoreValidators", "UsdGeomValidators", "UsdSkelValidators",
            "UsdShadeValidators", "UsdWrinkleValidators")


@dataclass
class CheckResult:
    """What a check found: each finding a dict (prim, attribute, message, type,
    validator), and the width of each wrinkled mesh (prim, text and the figures)."""

    findings: list[dict[str, Any]] = field(default_factory=list)
    widths: list[dict[str, Any]] = field(default_factory=list)

    @property
    def clean(self) -> bool:
        return not self.findings

    def as_json(self) -> dict[str, Any]:
        """The result as strict JSON (a value that is not finite is null)."""
        return dict(_finite({"findings": self.findings, "clean": self.clean,
                             "widths": self.widths}))


class CheckJob:
    """Validate ``shot``'s stage; ``wrinkles_only``: usdwrinkle's checker alone (USD's
    own findings, such as upAxis or defaultPrim, are left to usdchecker)."""

    def __init__(self, shot: Shot, wrinkles_only: bool = False):
        self.shot = shot
        self.wrinkles_only = wrinkles_only

    def run(self) -> CheckResult:
        self.shot.check()
        stage = self.shot.open()
        findings = collect(stage, ("UsdWrinkleValidators",)) if self.wrinkles_only else \
            collect(stage)
        scene = read_scene(stage)
        findings += units_findings(stage, scene) + unapplied_findings(stage)
        return CheckResult(findings, effective_widths(scene))


def _site(error: Any) -> tuple[str, str | None]:
    for site in error.GetSites():
        if site.IsProperty():
            path = site.GetProperty().GetPath()
            return str(path.GetPrimPath()), path.name
        if site.IsPrim():
            return str(site.GetPrim().GetPath()), None
    return "/", None


def collect(stage: Any, keywords: tuple[str, ...] = KEYWORDS) -> list[dict[str, Any]]:
    """Findings of the validators of ``keywords``, as dicts (path, attribute, message,
    validator, type)."""
    from pxr import UsdValidation

    from ..usd.validation import register_validators

    register_validators()
    context = UsdValidation.ValidationContext(keywords=list(keywords))
    findings: list[dict[str, Any]] = []
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


def _finite(value: Any) -> Any:
    """``value`` with every float that is not finite replaced by None."""
    import math

    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _finite(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(item) for item in value]
    return value


def read_scene(stage: Any) -> Any:
    """The scene delegate's reading of ``stage`` (what render resolves), read once for the
    units and widths below; None where the stage cannot be read that far (the findings
    say why)."""
    from ..process.errors import UsdWrinkleError
    from ..process.log import silenced
    from ..scene.stage import StageSceneDelegate

    try:
        with silenced():  # the findings report what is wrong
            return StageSceneDelegate(stage, use_baked=False)
    except UsdWrinkleError:
        return None


def units_findings(stage: Any, scene: Any) -> list[dict[str, Any]]:
    """The stage's metersPerUnit where render and bake refuse it (an error), or where
    they warn about it (a warning: scene.params.units_notes)."""
    from ..process.errors import UsdWrinkleError
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


def unapplied_findings(stage: Any) -> list[dict[str, Any]]:
    """Meshes authoring wrinkle controls without WrinkleAPI (schema.unapplied_controls):
    render draws them unwrinkled."""
    from ..usd import schema

    return [{"prim": path, "attribute": "apiSchemas", "type": "error",
             "validator": "usdWrinkleValidators:WrinkleAPI",
             "message": "authors wrinkle controls but WrinkleAPI is not applied, so it "
                        "renders without wrinkles (USD discards an apiSchemas list that "
                        "names an item twice, with no message)"}
            for path in schema.unapplied_controls(stage)]


def effective_widths(scene: Any) -> list[dict[str, Any]]:
    """The width W each wrinkled mesh gets (authored, or its cloth's through the stage's
    metersPerUnit), as the scene delegate resolves it; none without a scene."""
    from ..scene.params import width_summary

    if scene is None:
        return []
    return [{"prim": path, **width_summary(record.params)}
            for path, record in sorted(scene.meshes.items()) if record.wrinkled]
