"""The stages painted lately (issue 57: File > Open Recent): a short list in the user's
config folder (app/presets.py config_dir), newest first. No Qt."""
from __future__ import annotations

import json
import os
from pathlib import Path

from ..process.errors import UsdWrinkleError
from .presets import config_dir, write_json

#: how many stages the list keeps
KEEP = 10
FILE_NAME = "recent.json"


def recent_path() -> Path:
    return config_dir() / FILE_NAME


def recent_stages(path: Path | None = None) -> list[str]:
    """The stages painted lately, newest first, those that still exist. An unreadable
    list is an empty one (it is only a convenience; the next open rewrites it)."""
    path = recent_path() if path is None else path
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError):
        return []
    stages = data.get("stages") if isinstance(data, dict) else None
    if not isinstance(stages, list):
        return []
    return [str(s) for s in stages if isinstance(s, str) and os.path.exists(s)][:KEEP]


def remember_stage(stage: str, path: Path | None = None) -> list[str]:
    """Put ``stage`` (made absolute) first in the list; returns the list. A list that
    cannot be written is left as it was (nothing is raised: painting goes on)."""
    path = recent_path() if path is None else path
    stage = os.path.abspath(stage)
    stages = [stage] + [s for s in recent_stages(path) if s != stage]
    stages = stages[:KEEP]
    try:
        write_json(path, {"version": 1, "stages": stages})
    except UsdWrinkleError:
        pass
    return stages
