"""A shot as every job opens it: the stage (a file, or a stage a host already holds), its
composition, the options that decide how its wrinkles are computed, and its frames."""
from __future__ import annotations

import logging
import os
from collections.abc import Callable, Sequence
from typing import Any

from ..process.errors import UsdWrinkleError
from .options import ShotOptions

_log = logging.getLogger(__name__)

#: what a progress callback gets: the items of a loop and what it does ("render",
#: "preroll", "bake"); it returns the items to iterate (a progress bar's wrapper)
Progress = Callable[[list[Any], str], Any]


def no_progress(items: list[Any], _what: str) -> list[Any]:
    return items


def progress_bars(items: list[Any], what: str) -> Any:
    """A progress bar over ``items`` (a loop of two or more), as the command line shows:
    on a terminal a bar, in a farm's log one line per step."""
    if len(items) < 2:
        return items
    from ..process.progress import wrap

    return wrap(items, what)


class Shot:
    """A USD stage as a job opens it.

    ``stage``: a file path, or a ``Usd.Stage`` a host already holds (usdview's, with its
    session layer; composition options do not apply to it). ``options``: how the stage is
    composed and its wrinkles computed (app/options.ShotOptions)."""

    def __init__(self, stage: str | os.PathLike[str] | Any,
                 options: ShotOptions | None = None):
        self.options = options if options is not None else ShotOptions()
        if not isinstance(options, (ShotOptions, type(None))):
            raise UsdWrinkleError(f"`options`={options!r} must be ShotOptions")
        if isinstance(stage, (str, os.PathLike)):
            self.path = os.fspath(stage)
            if not isinstance(self.path, str):
                raise UsdWrinkleError(f"`stage`={stage!r} must be a file path or a Usd.Stage")
            self._stage = None
        elif not callable(getattr(stage, "GetRootLayer", None)):
            raise UsdWrinkleError(f"`stage`={stage!r} must be a file path or a Usd.Stage")
        else:
            if self.options.composition():
                raise UsdWrinkleError("`sublayer`, `variant` and `mask` compose a stage that is "
                                      "opened from a file; this one is already open")
            self._stage = stage
            self.held = True
            layer = stage.GetRootLayer()
            self.path = layer.realPath or layer.identifier

    #: whether the stage came open (a host's), rather than from a file
    held = False

    def check(self) -> None:
        """What can be refused before the stage is read."""
        self.options.check()

    def open(self) -> Any:
        """The composed Usd.Stage (opened once)."""
        if self._stage is None:
            from ..scene.stage import open_stage

            composition = self.options.composition()
            self._stage = open_stage(self.path, composition or None)
        return self._stage

    def frames(self, frames: str | Sequence[float | None] | None) -> list[float | None]:
        """The frames a job runs: ``frames`` as usdrecord's FrameSpec ("1:24", "1,5",
        "1:24x2"), a list of numbers, or None for the stage's start..end (the default
        time without a range)."""
        from ..scene.stage import inherited_range_note, stage_frames
        from .frames import parse_frame_spec

        if frames is None:
            stage = self.open()
            if note := inherited_range_note(stage):
                _log.warning(note)
            return list(stage_frames(stage))
        if not isinstance(frames, str) and list(frames) == [None]:
            return [None]  # the default time (usdview's, when it shows no time)
        parsed: list[float | None] = list(parse_frame_spec(frame_spec_of(frames)))
        return parsed

    def engine_options(self, camera: str | None = None, use_baked: bool = True,
                       profile: bool = False) -> Any:
        """The engine.EngineOptions of this shot (picklable: a farm task carries them)."""
        from ..engine import EngineOptions

        composition = self.options.composition()
        return EngineOptions(os.path.abspath(self.path), all_meshes=self.options.all_meshes,
                             relax_iterations=self.options.relax_iterations, camera=camera,
                             history_start=self.options.history_start, use_baked=use_baked,
                             profile=profile, composition=composition or None)

    def start_engine(self, camera: str | None = None, use_baked: bool = True,
                     profile: bool = False, progress: Progress = no_progress,
                     ctx: Any = None, history_cache: int | None = None) -> Any:
        """The WrinkleEngine of this shot, warning about the units its cloth widths go
        through; ``progress`` wraps the preroll frames."""
        from ..scene.params import units_notes

        engine = self.engine_options(camera, use_baked, profile).create(
            self.open(), lambda steps: progress(steps, "preroll"), ctx, history_cache)
        for note in units_notes(engine.stage, {path: engine.meshes[path]
                                               for path in engine.wrinkled_paths}):
            _log.warning(note)
        return engine


class ShotJob:
    """What a job of a shot holds: the shot, what it writes (a path or pattern), the
    frames (usdrecord's FrameSpec text, a list of numbers, or None for the stage's
    range), a ``progress(items, what)`` callback that wraps each loop, ``on_start()``,
    called after every check that can refuse the job, before the frame work, and
    ``say(text)``, which prints a status line (None: silent; a farm's)."""

    def __init__(self, shot: Shot, output: str | os.PathLike[str],
                 frames: str | Sequence[float] | None = None,
                 progress: Progress = no_progress,
                 on_start: Callable[[], None] | None = None):
        if not isinstance(shot, Shot):
            raise UsdWrinkleError(f"`shot`={shot!r} must be a usdwrinkle Shot")
        if not isinstance(output, (str, os.PathLike)) or \
                not isinstance(os.fspath(output), str):
            raise UsdWrinkleError(f"`output`={output!r} must be a path")
        if frames is not None:
            frame_spec_of(frames)  # refused here, with the field's name, not mid-run
        self.shot = shot
        self.output = os.fspath(output)
        self.frames = frames
        self.progress = progress
        self.on_start = on_start
        self.say: Callable[[str], None] | None = None


def at_frame(frame: float | None) -> Any:
    """A block whose errors name ``frame`` where they named none (frameloop.at_frame)."""
    from ..frameloop import at_frame as frame_block

    return frame_block(frame)


def frame_spec_of(frames: str | Sequence[float | None]) -> str:
    """A FrameSpec text of ``frames`` (a text, or a list of numbers). Bytes are refused,
    not iterated as numbers (b"1:2" was frames 49, 58 and 50), and so are booleans."""
    import numbers

    empty = "`frames` is empty (leave it out to run the stage's time range)"
    if isinstance(frames, str):
        if not frames.strip():
            raise UsdWrinkleError(empty)
        return frames
    bad = UsdWrinkleError(f"`frames`={frames!r} must be a FrameSpec text or a list of "
                          "numbers")
    if isinstance(frames, (bytes, bytearray, memoryview)) or isinstance(frames, dict):
        raise bad
    try:
        items = list(frames)
    except TypeError:
        raise bad from None
    if any(isinstance(f, bool) or type(f).__name__ == "bool_" or
           not isinstance(f, numbers.Real) for f in items):
        raise bad
    values = [float(f) for f in items]  # type: ignore[arg-type]
    if not values:
        raise UsdWrinkleError(empty)
    return ",".join(repr(f) for f in values)
