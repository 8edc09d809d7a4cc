"""Brush presets (issue 57): named BrushSettings kept in one small JSON file in the
user's config folder, so that an artist's brushes survive the session and reach the next
window. No Qt: the paint window is one door onto it.

The file is ``$USDWRINKLE_CONFIG_DIR/brushes.json``, else
``$XDG_CONFIG_HOME/usdwrinkle/brushes.json`` (``~/.config`` without it; ``%APPDATA%`` on
Windows)::

    {"version": 1, "presets": {"fine comb": {"mode": "comb", "radius": 0.05, ...}}}

Every preset is checked as a brush is (BrushSettings): a file edited by hand with a bad
value is refused in one line naming the preset, and the others still load. Writes are
atomic (a temporary file renamed over the old one).
"""
from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path

from ..brush.stamp import BrushSettings
from ..process.errors import UsdWrinkleError

VERSION = 1
FILE_NAME = "brushes.json"


def config_dir() -> Path:
    """The folder that holds usdwrinkle's user files."""
    if explicit := os.environ.get("USDWRINKLE_CONFIG_DIR"):
        return Path(explicit)
    if os.name == "nt" and os.environ.get("APPDATA"):
        return Path(os.environ["APPDATA"]) / "usdwrinkle"
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "usdwrinkle"


def presets_path() -> Path:
    return config_dir() / FILE_NAME


def _read(path: Path) -> dict[str, object]:
    if not path.exists():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise UsdWrinkleError(f"brush presets {path}: cannot be read ({exc}); move it "
                              "aside and save a preset again") from None
    presets = data.get("presets") if isinstance(data, dict) else None
    if not isinstance(presets, dict):
        raise UsdWrinkleError(f"brush presets {path}: no \"presets\" object; move it aside "
                              "and save a preset again")
    return presets


def load_presets(path: Path | None = None) -> tuple[dict[str, BrushSettings], list[str]]:
    """The presets in the file (none where there is no file), and one line for each
    preset that is not a valid brush (left out)."""
    path = presets_path() if path is None else path
    brushes, refused = {}, []
    fields = {f.name for f in dataclasses.fields(BrushSettings)}
    for name, values in _read(path).items():
        try:
            if not isinstance(values, dict):
                raise UsdWrinkleError("not an object of brush settings")
            unknown = sorted(set(values) - fields)
            if unknown:
                raise UsdWrinkleError(f"unknown setting {unknown[0]!r}")
            brushes[str(name)] = BrushSettings(**values)
        except (UsdWrinkleError, TypeError) as exc:
            refused.append(f"brush preset {name!r} in {path}: {exc}")
    return brushes, refused


def save_preset(name: str, brush: BrushSettings, path: Path | None = None) -> Path:
    """Add (or replace) the preset ``name``; the file's other presets are kept as they
    are. Returns the file written."""
    name = str(name).strip()
    if not name:
        raise UsdWrinkleError("a brush preset needs a name")
    path = presets_path() if path is None else path
    presets = _read(path)
    presets[name] = dataclasses.asdict(brush)
    _write(path, presets)
    return path


def delete_preset(name: str, path: Path | None = None) -> None:
    path = presets_path() if path is None else path
    presets = _read(path)
    if name not in presets:
        raise UsdWrinkleError(f"no brush preset {name!r} in {path}")
    del presets[name]
    _write(path, presets)


def write_json(path: Path, data: dict[str, object]) -> None:
    """``data`` as JSON at ``path``, atomically (outputs.atomic.atomic_path: the folder
    made, never a half-written file); a failure is the one-line UsdWrinkleError."""
    from ..outputs.atomic import atomic_path

    text = json.dumps(data, indent=1, sort_keys=True) + "\n"
    with atomic_path(str(path)) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")


def _write(path: Path, presets: dict[str, object]) -> None:
    write_json(path, {"version": VERSION, "presets": presets})
