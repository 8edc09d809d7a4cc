"""FrameSpecs (usdrecord's syntax) and '#' frame placeholders in output paths."""
from __future__ import annotations

import math
import re

from pxr import UsdUtils

from ..errors import UsdWrinkleError

_HASHES = re.compile(r"#+")


def parse_frame_spec(spec: str) -> list[float]:
    """'1:48', '101:109x2', '1,5,10' -> frames, in order, without duplicates."""
    frames: list[float] = []
    for part in spec.split(","):
        part = part.strip()
        if not part:
            raise UsdWrinkleError(f"bad FrameSpec '{spec}': empty item")
        try:
            timecodes = list(UsdUtils.TimeCodeRange.CreateFromFrameSpec(part))
        except Exception:
            timecodes = []
        if not timecodes:
            raise UsdWrinkleError(
                f"bad FrameSpec '{spec}' (use e.g. 1:48, 101:109x2 or 1,5,10)")
        for tc in timecodes:
            value = float(tc.GetValue())
            if value not in frames:
                frames.append(value)
    return frames


def add_frame_args(parser) -> None:
    parser.add_argument("--frames", metavar="SPEC",
                        help="frames to process, as usdrecord's FrameSpec: 1:48, 101:109x2, "
                             "1,5,10 (default: the stage's start..end, or the default time)")


def frame_path(pattern: str, frame: float) -> str:
    """Replace the first run of '#' by the zero-padded frame number."""
    match = _HASHES.search(pattern)
    if match is None:
        return pattern
    width = len(match.group(0))
    if math.isnan(frame):
        text = "default"
    elif float(frame).is_integer():
        text = f"{int(frame):0{width}d}" if frame >= 0 else f"-{int(-frame):0{width}d}"
    else:
        whole = int(math.floor(frame))
        text = f"{whole:0{width}d}" + f"{frame - whole:.3f}"[1:]
    return pattern[:match.start()] + text + pattern[match.end():]


def check_output_pattern(pattern: str, frames: list[float]) -> None:
    if len(frames) > 1 and "#" not in pattern:
        raise UsdWrinkleError(
            f"output '{pattern}' has no '#' frame placeholder, but {len(frames)} frames are "
            "requested (e.g. out/shot.####.exr)")
