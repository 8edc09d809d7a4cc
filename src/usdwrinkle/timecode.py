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
