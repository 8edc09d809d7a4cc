"""Frames as people read them: one formatting for messages, summaries and metadata."""
from __future__ import annotations

import math


def format_frame(frame: float) -> str:
    """``24`` for an integer frame, ``1.25`` for a sub-frame, ``default`` for NaN (USD's
    default time)."""
    frame = float(frame)
    if math.isnan(frame):
        return "default"
    return str(int(frame)) if frame.is_integer() else f"{frame:g}"


SUBFRAME_DECIMALS = 3


def frame_text(frame: float, width: int = 4) -> str:
    """A frame number as it appears in a file name: zero-padded, sub-frames to
    SUBFRAME_DECIMALS decimals (rounded, so 1.9996 names 0002.000), NaN as 'default'."""
    if math.isnan(frame):
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
