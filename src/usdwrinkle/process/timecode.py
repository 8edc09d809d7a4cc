"""Frames: what a frame is, and how people read one (messages, summaries, file names).

A frame is a time code (a float), or None for USD's default time
(``Usd.TimeCode.Default()``): the stage's unanimated values, what a stage without a time
range renders. None, not NaN: a comparison or sum with None fails loudly, where NaN
silently compares false.
"""
from __future__ import annotations

from typing import TypeAlias

#: a time code, or None for the default time
Frame: TypeAlias = "float | None"


def format_frame(frame: float | None) -> str:
    """``24`` for an integer frame, ``1.25`` for a sub-frame, ``default`` for None (USD's
    default time)."""
    if frame is None:
        return "default"
    frame = float(frame)
    return str(int(frame)) if frame.is_integer() else f"{frame:g}"


SUBFRAME_DECIMALS = 3


def frame_text(frame: float | None, width: int = 4) -> str:
    """A frame number as it appears in a file name: zero-padded, sub-frames to
    SUBFRAME_DECIMALS decimals (rounded, so 1.9996 names 0002.000), None as 'default'."""
    if frame is None:
        return format_frame(frame)
    rounded = round(frame, SUBFRAME_DECIMALS)
    sign = "-" if rounded < 0 else ""
    whole, fraction = divmod(abs(rounded), 1.0)
    text = f"{sign}{int(whole):0{width}d}"
    if round(fraction, SUBFRAME_DECIMALS):
        text += f"{fraction:.{SUBFRAME_DECIMALS}f}"[1:]
    elif not float(frame).is_integer():
        text += "." + "0" * SUBFRAME_DECIMALS
    return text
