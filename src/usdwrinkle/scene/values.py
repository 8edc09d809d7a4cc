"""Reading authored values: one rule for "the value" of an attribute outside a frame,
the frame a message names, and what the GPU's float32 can hold."""
from __future__ import annotations

import numpy as np
from pxr import Usd


def static_value(attr: Usd.Attribute, time: Usd.TimeCode | None = None):
    """The value at ``time`` (default: the default time), else at the attribute's first
    time sample (an attribute authored only with samples), else None."""
    value = attr.Get(Usd.TimeCode.Default() if time is None else time)
    if value is None and attr.GetNumTimeSamples():
        value = attr.Get(attr.GetTimeSamples()[0])
    return value


def frame_of(time: Usd.TimeCode) -> float | None:
    """The frame a message names for ``time`` (None: the default time)."""
    return None if time is None or time.IsDefault() else time.GetValue()


def finite_in_float32(values) -> bool:
    """True when every value survives the GPU's float32: not NaN, not Inf, and not beyond
    3.4e38 (a double 1e39 becomes Inf there)."""
    with np.errstate(over="ignore"):
        return bool(np.all(np.isfinite(np.asarray(values, np.float64).astype(np.float32))))
