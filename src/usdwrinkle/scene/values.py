"""Reading authored values: one rule for "the value" of an attribute outside a frame."""
from __future__ import annotations

from pxr import Usd


def static_value(attr: Usd.Attribute, time: Usd.TimeCode | None = None):
    """The value at ``time`` (default: the default time), else at the attribute's first
    time sample (an attribute authored only with samples), else None."""
    value = attr.Get(Usd.TimeCode.Default() if time is None else time)
    if value is None and attr.GetNumTimeSamples():
        value = attr.Get(attr.GetTimeSamples()[0])
    return value
