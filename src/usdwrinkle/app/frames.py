"""FrameSpecs (usdrecord's syntax) and '#' frame placeholders in output paths: what a
job's ``frames`` and ``output`` mean."""
from __future__ import annotations

import math
import re
import typing

from pxr import Usd, UsdUtils

from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_FRAMES, MAX_TIME_CODE
from ..process.timecode import SUBFRAME_DECIMALS, frame_text

_HASHES = re.compile(r"#+")


def check_time_code(value: float, what: str) -> float:
    """Refuse a time code that is not finite or beyond ``MAX_TIME_CODE``; ``what`` names
    the option field that holds it, in backquotes."""
    if not math.isfinite(value) or abs(value) > MAX_TIME_CODE:
        raise UsdWrinkleError(f"{what} {value:g} is not a finite time code within "
                              f"+-{MAX_TIME_CODE:g}")
    return value


def range_count(start: float, end: float, stride: float) -> int:
    """Frames in start..end by stride (inclusive), without listing them."""
    return int(math.floor((end - start) / stride + 1e-9)) + 1


_SPEC_ITEM = re.compile(r"^([^:x]+)(?::([^:x]+)(?:x([^:x]+))?)?$")


def _time_code_range(part: str, spec: str) -> typing.Any:
    """One FrameSpec item (``start``, ``start:end`` or ``start:endxstride``) as a
    UsdUtils.TimeCodeRange. Parsed here, not by TimeCodeRange.CreateFromFrameSpec, which
    crashes the process on some malformed items (``1:``)."""
    bad = UsdWrinkleError(f"bad FrameSpec '{spec}' (use e.g. 1:48, 101:109x2 or 1,5,10)")
    match = _SPEC_ITEM.match(part.replace(" ", ""))
    if match is None:
        raise bad
    try:
        start = float(match.group(1))
        end = start if match.group(2) is None else float(match.group(2))
        stride = None if match.group(3) is None else float(match.group(3))
    except ValueError:
        raise bad from None
    for value in (start, end):
        check_time_code(value, f"`frames` '{part}': frame")
    if stride is None:
        stride = 1.0 if end >= start else -1.0
    if not math.isfinite(stride) or stride == 0 or (end - start) * stride < 0:
        raise UsdWrinkleError(f"`frames` '{part}': stride {stride:g} does not lead from "
                              f"{start:g} to {end:g}")
    return UsdUtils.TimeCodeRange(Usd.TimeCode(start), Usd.TimeCode(end), stride)


def parse_frame_spec(spec: str) -> list[float]:
    """'1:48', '101:109x2', '1,5,10' -> frames, in order, without duplicates.

    Refuses non-finite frames, frames beyond +-MAX_TIME_CODE and specs of more than
    MAX_FRAMES frames before listing any of them.
    """
    ranges = []
    total = 0
    for part in spec.split(","):
        part = part.strip()
        if not part:
            raise UsdWrinkleError(f"bad FrameSpec '{spec}': empty item")
        tcr = _time_code_range(part, spec)
        start, end = tcr.startTimeCode.GetValue(), tcr.endTimeCode.GetValue()
        steps = (end - start) / tcr.stride  # a tiny stride: inf, never listed
        total += range_count(start, end, tcr.stride) if steps <= MAX_FRAMES else MAX_FRAMES + 1
        if total > MAX_FRAMES:
            raise UsdWrinkleError(f"`frames` '{spec}' names more than {MAX_FRAMES:,} frames "
                                  "(the most one run renders; split the shot into chunks)")
        ranges.append(tcr)
    frames: dict[float, None] = {}  # insertion-ordered and linear: a dict, not 'in' on a list
    for tcr in ranges:
        for tc in tcr:
            frames.setdefault(float(tc.GetValue()), None)
    return list(frames)


#: decimals of a sub-frame in a file name (frame 1.25 -> 0001.250)
def frame_path(pattern: str, frame: float | None) -> str:
    """Replace the first run of '#' by the zero-padded frame number."""
    match = _HASHES.search(pattern)
    if match is None:
        return pattern
    return pattern[:match.start()] + frame_text(frame, len(match.group(0))) + \
        pattern[match.end():]


def frame_paths(pattern: str, frames: list[float | None]) -> list[str]:
    """One output path per frame; refuses frames that would share a file name (sub-frames
    closer than the file name's SUBFRAME_DECIMALS decimals)."""
    check_output_pattern(pattern, frames)
    paths = [frame_path(pattern, f) for f in frames]
    first: dict[object, tuple[float | None, str]] = {}
    for frame, path in zip(frames, paths, strict=True):
        # the same file, or files that name the same frame (1 and 1.0001: 0001, 0001.000)
        for key in (path, None if frame is None else round(frame, SUBFRAME_DECIMALS)):
            other, other_path = first.setdefault(key, (frame, path))
            if other != frame:
                where = f"written to '{path}'" if other_path == path else \
                    f"named frame {frame_text(frame, 1)} ('{other_path}', '{path}')"
                raise UsdWrinkleError(
                    f"frames {other:g} and {frame:g} would both be {where} (sub-frames are "
                    f"named to {SUBFRAME_DECIMALS} decimals); choose frames that differ there")
    return paths


def check_output_pattern(pattern: str, frames: list[float | None]) -> None:
    if len(frames) > 1 and "#" not in pattern:
        raise UsdWrinkleError(
            f"output '{pattern}' has no '#' frame placeholder, but {len(frames)} frames are "
            "requested (e.g. out/shot.####.exr)")
