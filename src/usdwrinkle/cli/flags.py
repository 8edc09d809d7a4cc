"""The command line's names for the application layer's option fields.

The jobs (app/) say what is wrong in the names a Python caller passed, in backquotes
(`` `width` ``, `` `map_size` ``). The command line prints the same messages, errors and
warnings, with each such field named by its flag (``--width``, ``--map-size``), as
usdrecord maps FrameRecorder's errors to its options.
"""
from __future__ import annotations

import argparse
import re

#: fields whose flag is not the field's name with '-' for '_' (several flags set one)
SPECIAL = {"exr_half": "--exr-half"}

_FIELD = re.compile(r"`([a-z][a-z0-9_]*)`")


def flag_of(field: str, parser: argparse.ArgumentParser | None = None) -> str:
    """The flag that sets ``field`` in ``parser`` (the subcommand's), else the field's
    name written as a flag."""
    if field in SPECIAL:
        return SPECIAL[field]
    if parser is not None:
        for action in parser._actions:  # argparse has no public list of them
            if action.dest == field and action.option_strings:
                longs = [s for s in action.option_strings if s.startswith("--")]
                return (longs or action.option_strings)[0]
    return "--" + field.replace("_", "-")


def flagged(message: str, parser: argparse.ArgumentParser | None = None) -> str:
    """``message`` with each backquoted field named by its flag."""
    return _FIELD.sub(lambda match: flag_of(match.group(1), parser), message)
