"""Reading authored values: one rule for "the value" of an attribute outside a frame,
the frame a message names, and what the GPU's float32 can hold."""
from __future__ import annotations

import numpy as np
from pxr import Usd

from ..process.errors import UsdWrinkleError


def static_time(attr: Usd.Attribute) -> Usd.TimeCode:
    """The time at which "the value" of ``attr`` outside a frame is read: the default
    time where a default is authored, else its first time sample (EarliestTime resolves
    to it; an attribute authored only with samples has no value at the default time)."""
    source = attr.GetResolveInfo(Usd.TimeCode.Default()).GetSource()
    return Usd.TimeCode.Default() if source == Usd.ResolveInfoSourceDefault \
        else Usd.TimeCode.EarliestTime()


def static_value(attr: Usd.Attribute, time: Usd.TimeCode | None = None):
    """The value at ``time``; at the default time (or without ``time``) the value outside
    a frame (static_time): the default, else the first time sample, else None."""
    if time is None or time.IsDefault():
        time = static_time(attr)
    return attr.Get(time)


def flattened(primvar, time: Usd.TimeCode):
    """``primvar.ComputeFlattened(time)``, refusing indices outside the authored array
    with one line naming the prim and the primvar (USD prints a raw multi-line warning
    and returns nothing, so the value would silently fall back)."""
    indices = primvar.GetIndices(time) if primvar.IsIndexed() else None
    if indices is not None and len(indices):
        values = primvar.GetAttr().Get(time)
        size = 0 if values is None else len(values) // max(primvar.GetElementSize(), 1)
        idx = np.asarray(indices, dtype=np.int64)
        bad = np.flatnonzero((idx < 0) | (idx >= size))
        if len(bad):
            attr = primvar.GetAttr()
            raise UsdWrinkleError(
                f"{attr.GetName()} has {len(bad)} index(es) outside its {size} value(s) "
                f"(index {int(idx[bad[0]])} at position {int(bad[0])})",
                str(attr.GetPrim().GetPath()), f"{attr.GetName()}:indices",
                None if time.IsEarliestTime() else frame_of(time))
    return primvar.ComputeFlattened(time)


def static_flattened(primvar, time: Usd.TimeCode | None = None):
    """A primvar's flattened value by static_value's rule (None when it has none)."""
    if time is None or time.IsDefault():
        time = static_time(primvar.GetAttr())
    return flattened(primvar, time)


#: float triples any point reader takes
FLOAT3_TYPES = frozenset({"float3", "double3", "half3"} |
                         {f"{role}3{kind}" for role in ("vector", "normal", "point", "color")
                          for kind in "fdh"})
#: integer scalars
INT_TYPES = frozenset({"int", "uint", "int64", "uint64", "uchar"})
#: the mesh attributes every reader needs, with the types they may be authored with
MESH_ARRAYS = {
    "points": (FLOAT3_TYPES, "a point3f[] array"),
    "primvars:rest": (FLOAT3_TYPES, "a point3f[] array"),
    "faceVertexCounts": (INT_TYPES, "an int[] array"),
    "faceVertexIndices": (INT_TYPES, "an int[] array"),
}


def authored_type(attr: Usd.Attribute):
    """The type the layers author for ``attr`` (GetTypeName returns the schema's own
    type for a schema attribute, whatever a layer says)."""
    specs = attr.GetPropertyStack(Usd.TimeCode.Default())
    return next((spec.typeName for spec in specs if spec.typeName), attr.GetTypeName())


def type_problem(attr: Usd.Attribute, scalars, arrays, wanted: str) -> str | None:
    """'<name> must be <wanted>, not <type>' when ``attr`` is authored with a scalar type
    not in ``scalars`` or an arrayness not in ``arrays`` (True: array); else None."""
    type_name = authored_type(attr)
    if str(type_name.scalarType) in scalars and type_name.isArray in arrays:
        return None
    return f"{attr.GetName()} must be {wanted}, not {str(type_name) or 'untyped'}"


def require_mesh_array(attr: Usd.Attribute, path: str) -> None:
    """Refuse points, primvars:rest, faceVertexCounts or faceVertexIndices authored with a
    type their readers cannot use (a string, a scalar): one line, not a numpy error."""
    if not attr or not attr.HasAuthoredValue():
        return
    scalars, wanted = MESH_ARRAYS[attr.GetName()]
    problem = type_problem(attr, scalars, (True,), wanted)
    if problem:
        raise UsdWrinkleError(problem, path, attr.GetName())


def frame_of(time: Usd.TimeCode) -> float | None:
    """The frame a message names for ``time`` (None: the default time)."""
    return None if time is None or time.IsDefault() else time.GetValue()


def finite_in_float32(values) -> bool:
    """True when every value survives the GPU's float32: not NaN, not Inf, and not beyond
    3.4e38 (a double 1e39 becomes Inf there)."""
    with np.errstate(over="ignore"):
        return bool(np.all(np.isfinite(np.asarray(values, np.float64).astype(np.float32))))
