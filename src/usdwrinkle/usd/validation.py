"""WrinkleAPI rules, shared by ``usdwrinkle check``, the scene delegate and authoring.

:func:`wrinkle_findings` checks one prim and returns findings; the scene delegate
refuses the first one as an error, ``check`` lists them all. The rules are also
registered with UsdValidation (keyword ``UsdWrinkleValidators``) so that other
tools that run USD's validators find them.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
from pxr import Usd, UsdGeom

from ..process.errors import UsdWrinkleError
from ..process.limits import (
    MAX_AMPLITUDE_SCALE,
    MAX_PROFILE_VALUE,
    MAX_RELAX_ITERATIONS,
    MAX_WORLD_COORDINATE,
)
from ..process.timecode import format_frame
from . import schema
from .values import (
    FLOAT3_TYPES,
    INT_TYPES,
    finite_in_float32,
    flattened,
    frame_of,
    static_flattened,
    static_time,
    static_value,
    type_problem,
)

VALIDATOR_NAME = "usdWrinkleValidators:WrinkleAPIChecker"
VALIDATOR_KEYWORD = "UsdWrinkleValidators"


@dataclass(frozen=True)
class Finding:
    prim_path: str
    attribute: str | None
    message: str
    severity: str = "error"
    #: the time sample that breaks the rule (None: the default time)
    frame: float | None = None

    def one_line(self) -> str:
        return UsdWrinkleError(self.message, self.prim_path, self.attribute,
                               self.frame).one_line()


_INTEGERS = INT_TYPES
_NUMBERS = {"float", "double", "half", "int", "uint", "int64", "uint64"}
_VECTORS3 = FLOAT3_TYPES
#: attribute -> (accepted scalar types, array?, what the message calls it). q and the
#: profiles are arrays; width may be a constant scalar; the others are scalars.
EXPECTED_TYPES = {
    schema.Q: (_VECTORS3, (True,), "a vector3f[] array"),
    schema.WIDTH: (_NUMBERS, (True, False), "a float[] array or a float"),
    schema.AMPLITUDE_SCALE: (_NUMBERS, (False,), "a float"),
    schema.HEIGHT_PROFILE: (_NUMBERS, (True,), "a float[] array"),
    schema.GRADIENT_PROFILE: (_NUMBERS, (True,), "a float[] array"),
    schema.RELAX_ITERATIONS: (_INTEGERS, (False,), "an int"),
    schema.BIAXIAL: (_NUMBERS, (False,), "a float"),
    schema.TENSION: (_NUMBERS, (False,), "a float"),
    schema.TENSION_THRESHOLD: (_NUMBERS, (False,), "a float"),
    schema.CLOTH: ({"token", "string"}, (False,), "a token"),
    schema.SLACK: (_NUMBERS, (False,), "a float"),
    schema.CREST_DAMPING: (_NUMBERS, (False,), "a float"),
    schema.IRREGULARITY: (_NUMBERS, (False,), "a float"),
    schema.HELD: (_NUMBERS, (True, False), "a float[] array or a float"),
}


def check_type(attr, path: str) -> list[Finding]:
    """A WrinkleAPI attribute authored with a type its readers cannot use."""
    name = attr.GetName()
    problem = type_problem(attr, *EXPECTED_TYPES[name])
    return [Finding(path, name, problem)] if problem else []


def _times(attr) -> list:
    times = [Usd.TimeCode.Default()]
    times.extend(Usd.TimeCode(t) for t in attr.GetTimeSamples())
    return times


def refuse(findings: list[Finding]) -> None:
    """Raise the first finding as a UsdWrinkleError (the scene delegate and authoring)."""
    if findings:
        first = findings[0]
        raise UsdWrinkleError(first.message, first.prim_path, first.attribute, first.frame)


def point_count(prim, time=None) -> int | None:
    """The mesh's point count at ``time`` (default time, else its first sample)."""
    points = static_value(UsdGeom.Mesh(prim).GetPointsAttr(), time)
    return None if points is None else len(points)


def check_q(values, interpolation: str, point_count: int | None, path: str) -> list[Finding]:
    out = []
    arr = np.asarray(values, dtype=np.float64).reshape(-1, 3) if values is not None else None
    if arr is None:
        return out
    if interpolation not in ("vertex", "varying"):
        out.append(Finding(path, schema.Q, "q must have vertex interpolation"))
    if point_count is not None and len(arr) != point_count:
        out.append(Finding(path, schema.Q, f"q has {len(arr)} values for {point_count} points"))
    if not np.all(np.isfinite(arr)):
        out.append(Finding(path, schema.Q, "q is not finite"))
    elif len(arr) and (np.max(np.abs(arr)) > 1.0 + 1e-4  # first: no overflow in the norm
                       or np.max(np.linalg.norm(arr, axis=1)) > 1.0 + 1e-4):
        out.append(Finding(path, schema.Q, "|q| > 1"))
    return out


def _constant_or_per_point(arr, point_count: int | None, name: str, what: str,
                           path: str) -> list[Finding]:
    """A primvar value that must be one value, or one per point."""
    if arr.size != 1 and (point_count is None or arr.size != point_count):
        return [Finding(path, name, f"{what} must be constant or have one value per point "
                                    f"({point_count})")]
    return []


def check_width(values, point_count: int | None, path: str) -> list[Finding]:
    if values is None:
        return []
    arr = np.atleast_1d(np.asarray(values, dtype=np.float64))
    out = _constant_or_per_point(arr, point_count, schema.WIDTH, "width", path)
    if not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        out.append(Finding(path, schema.WIDTH, "width must be finite and > 0"))
    elif np.any(arr > MAX_WORLD_COORDINATE):
        out.append(Finding(path, schema.WIDTH,
                           f"width must be at most {MAX_WORLD_COORDINATE:g} scene units"))
    return out


def check_profile(values, name: str, path: str) -> list[Finding]:
    if values is None or len(values) == 0:
        return []
    arr = np.asarray(values, dtype=np.float64)
    if arr.size < 2 or not np.all(np.isfinite(arr)):
        return [Finding(path, name, "a profile needs at least 2 finite samples")]
    if np.max(np.abs(arr)) > MAX_PROFILE_VALUE:
        return [Finding(path, name, f"profile samples must lie within +-{MAX_PROFILE_VALUE:g} "
                                    "(a shape of order 1; the amplitude scales it)")]
    return []


def check_relax_iterations(value, path: str) -> list[Finding]:
    if value is None:
        return []
    if not 0 <= int(value) <= MAX_RELAX_ITERATIONS:
        return [Finding(path, schema.RELAX_ITERATIONS,
                        f"relax iterations must be in 0..{MAX_RELAX_ITERATIONS:,}")]
    return []


def check_amplitude_scale(value, path: str) -> list[Finding]:
    if value is None:
        return []
    if not np.isfinite(value) or value < 0:
        return [Finding(path, schema.AMPLITUDE_SCALE, "amplitude scale must be finite and >= 0")]
    if value > MAX_AMPLITUDE_SCALE:
        return [Finding(path, schema.AMPLITUDE_SCALE,
                        f"amplitude scale must be at most {MAX_AMPLITUDE_SCALE:g}")]
    return []


def _in_range(value, name: str, what: str, low: float, high: float, path: str):
    if value is None:
        return []
    if not np.isfinite(value) or not low <= value <= high:
        return [Finding(path, name, f"{what} must be in {low:g}..{high:g}")]
    return []


def check_biaxial(value, path: str) -> list[Finding]:
    """wrinkle:biaxial: the second wave system's weight, in [0, 1]."""
    return _in_range(value, schema.BIAXIAL, "biaxial weight", 0.0, 1.0, path)


def check_tension(value, path: str) -> list[Finding]:
    """wrinkle:tension: an amplitude factor, >= 0 (at most the amplitude scale's maximum)."""
    return _in_range(value, schema.TENSION, "tension factor", 0.0, MAX_AMPLITUDE_SCALE, path)


def check_tension_threshold(value, path: str) -> list[Finding]:
    """wrinkle:tensionThreshold: a strain, in [0, 1]."""
    return _in_range(value, schema.TENSION_THRESHOLD, "tension threshold", 0.0, 1.0, path)


def check_cloth(value, path: str) -> list[Finding]:
    """wrinkle:cloth: one of the cloth presets, or "mesh"."""
    if value is None or str(value) in schema.CLOTH_TOKENS:
        return []
    return [Finding(path, schema.CLOTH, f"cloth {str(value)!r} is not one of "
                                        f"{', '.join(schema.CLOTH_TOKENS)}")]


def check_slack(value, path: str) -> list[Finding]:
    """wrinkle:slack: a compression in [0, 0.9]."""
    return _in_range(value, schema.SLACK, "slack", 0.0, 0.9, path)


def check_crest_damping(value, path: str) -> list[Finding]:
    """wrinkle:crestDamping: a band in degrees, in [0, 45]."""
    return _in_range(value, schema.CREST_DAMPING, "crest damping", 0.0, 45.0, path)


def check_irregularity(value, path: str) -> list[Finding]:
    """wrinkle:irregularity: the folds' spread of width, in [0, IRREGULARITY_MAX]."""
    return _in_range(value, schema.IRREGULARITY, "irregularity", 0.0,
                     schema.IRREGULARITY_MAX, path)


def check_held(values, point_count: int | None, path: str) -> list[Finding]:
    """primvars:wrinkle:held: one weight in [0, 1], or one per point."""
    if values is None:
        return []
    arr = np.atleast_1d(np.asarray(values, dtype=np.float64))
    out = _constant_or_per_point(arr, point_count, schema.HELD, "held", path)
    if not np.all(np.isfinite(arr)) or np.any(arr < 0) or np.any(arr > 1):
        out.append(Finding(path, schema.HELD, "held weights must be in [0, 1]"))
    return out


def _value_check(name: str, path: str, count: int | None):
    """check(attr, time) -> findings for the value of WrinkleAPI attribute ``name``."""
    def primvar_value(attr, time):
        return flattened(UsdGeom.Primvar(attr), time)

    return {
        schema.Q: lambda attr, time: check_q(primvar_value(attr, time),
                                             UsdGeom.Primvar(attr).GetInterpolation(), count,
                                             path),
        schema.WIDTH: lambda attr, time: check_width(primvar_value(attr, time), count, path),
        schema.HEIGHT_PROFILE: lambda attr, time: check_profile(attr.Get(time), name, path),
        schema.GRADIENT_PROFILE: lambda attr, time: check_profile(attr.Get(time), name, path),
        schema.AMPLITUDE_SCALE: lambda attr, time: check_amplitude_scale(attr.Get(time), path),
        schema.RELAX_ITERATIONS: lambda attr, time: check_relax_iterations(attr.Get(time), path),
        schema.BIAXIAL: lambda attr, time: check_biaxial(attr.Get(time), path),
        schema.TENSION: lambda attr, time: check_tension(attr.Get(time), path),
        schema.CLOTH: lambda attr, time: check_cloth(attr.Get(time), path),
        schema.SLACK: lambda attr, time: check_slack(attr.Get(time), path),
        schema.CREST_DAMPING: lambda attr, time: check_crest_damping(attr.Get(time), path),
        schema.IRREGULARITY: lambda attr, time: check_irregularity(attr.Get(time), path),
        schema.HELD: lambda attr, time: check_held(primvar_value(attr, time), count, path),
        schema.TENSION_THRESHOLD: lambda attr, time: check_tension_threshold(attr.Get(time),
                                                                             path),
    }[name]


def _differs(first, other) -> bool:
    a, b = np.asarray(first), np.asarray(other)
    return a.shape != b.shape or not np.array_equal(a, b, equal_nan=a.dtype.kind == "f")


def attribute_findings(attr: Usd.Attribute, path: str, count: int | None) -> list[Finding]:
    """Every rule for one authored WrinkleAPI attribute: its type, then its value at the
    default time and at every time sample (a value that breaks a rule at frame 30 is
    refused before frame 1 is drawn). WrinkleAPI values do not animate: a value that
    changes over time gets a warning that says which one applies."""
    name = attr.GetName()
    wrong_type = check_type(attr, path)
    if wrong_type:
        return wrong_type
    check = _value_check(name, path, count)
    findings: list[Finding] = []
    values = []
    for time in _times(attr):
        try:
            findings += [dataclasses.replace(f, frame=frame_of(time))
                         for f in check(attr, time)]
            value = flattened(UsdGeom.Primvar(attr), time) \
                if name in (schema.Q, schema.WIDTH, schema.HELD) \
                else attr.Get(time)
        except UsdWrinkleError as exc:  # indices outside the array (values.flattened)
            findings.append(Finding(path, name, exc.what, frame=frame_of(time)))
            continue
        if value is not None:
            values.append(value)
    if not findings and any(_differs(values[0], other) for other in values[1:]):
        when = "the default time" if static_time(attr).IsDefault() else \
            f"its first time sample ({attr.GetTimeSamples()[0]:g})"
        findings.append(Finding(path, name, f"{name} changes over time, but WrinkleAPI values "
                                            f"do not animate: its value at {when} applies "
                                            "to every frame", "warning"))
    # one finding per distinct problem (at its first time), even when samples repeat it
    first = {}
    for finding in findings:
        first.setdefault((finding.attribute, finding.message), finding)
    return list(first.values())


#: the WrinkleAPI attributes, in the order their findings are reported
ATTRIBUTES = schema.CONTROL_ATTRIBUTES


def parameter_findings(prim: Usd.Prim, count: int | None) -> list[Finding]:
    """attribute_findings of every authored WrinkleAPI attribute of ``prim``."""
    path = str(prim.GetPath())
    findings: list[Finding] = []
    for name in ATTRIBUTES:
        attr = prim.GetAttribute(name)
        if attr and attr.HasAuthoredValue():
            findings += attribute_findings(attr, path, count)
    return findings


def rest_findings(prim: Usd.Prim, count: int | None) -> list[Finding]:
    """primvars:rest: its type, its length against the points, finite values."""
    path = str(prim.GetPath())
    rest = UsdGeom.PrimvarsAPI(prim).GetPrimvar("rest")
    if not rest or not rest.HasAuthoredValue():
        return []
    problem = type_problem(rest.GetAttr(), FLOAT3_TYPES, (True,), "a point3f[] array")
    if problem:
        return [Finding(path, "primvars:rest", problem)]
    value = static_flattened(rest)
    if value is None:
        return []
    findings = []
    if count is not None and len(value) != count:
        findings.append(Finding(path, "primvars:rest",
                                f"primvars:rest has {len(value)} values for {count} points"))
    if not finite_in_float32(value):
        findings.append(Finding(path, "primvars:rest", "points are not finite (NaN or Inf)"))
    return findings


def wrinkle_findings(prim: Usd.Prim) -> list[Finding]:
    """Every rule of ``usdwrinkle check`` on one prim with WrinkleAPI (else no findings)."""
    if not schema.has_wrinkle_api(prim):
        return []
    path = str(prim.GetPath())
    if not prim.IsA(UsdGeom.Mesh):
        return [Finding(path, None, f"WrinkleAPI is applied to a {prim.GetTypeName() or 'typeless'}"
                                    " prim, not a Mesh")]
    count = point_count(prim)
    return parameter_findings(prim, count) + rest_findings(prim, count)


_registered = {"done": False}


def register_validators() -> None:
    """Register the WrinkleAPI checker with UsdValidation (once per process)."""
    if _registered["done"]:
        return
    from pxr import UsdValidation

    registry = UsdValidation.ValidationRegistry()
    if not registry.HasValidator(VALIDATOR_NAME):
        metadata = UsdValidation.ValidatorMetadata(
            name=VALIDATOR_NAME,
            doc="WrinkleAPI values: on a Mesh; q of the points' length, vertex, finite, "
                "|q| <= 1; width finite, > 0 and <= 1e15, constant or per point; profiles "
                "with >= 2 finite samples within +-1000; primvars:rest of the points' length; "
                "amplitude scale in 0..1000; relax iterations in 0..10,000; every attribute "
                "of its schema type.",
            keywords=[VALIDATOR_KEYWORD])

        def task(prim, time_range):
            errors = []
            for finding in wrinkle_findings(prim):
                site_path = prim.GetPath()
                if finding.attribute:
                    site_path = site_path.AppendProperty(finding.attribute)
                kind = UsdValidation.ValidationErrorType.Warn if finding.severity == "warning" \
                    else UsdValidation.ValidationErrorType.Error
                errors.append(UsdValidation.ValidationError(
                    "WrinkleAPIValue", kind,
                    [UsdValidation.ValidationErrorSite(prim.GetStage(), site_path)],
                    finding.message if finding.frame is None else
                    f"{finding.message} (at frame {format_frame(finding.frame)})"))
            return errors

        registry.RegisterPrimValidator(metadata, task)
    _registered["done"] = True
