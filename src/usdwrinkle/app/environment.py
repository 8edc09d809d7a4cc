"""What the doors show of the installation and the machine: the GL renderer, the schema's
registration, the process's one GL context, the Blender add-on's file."""
from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any


def renderer_info() -> dict[str, Any]:
    """The GL renderer and version of the process's context (made if there is none)."""
    from ..render.context import renderer_info as info

    return dict(info())


def release_context() -> None:
    """Release the process's one GL context, if it made one (a clean exit)."""
    if "usdwrinkle.render.context" in sys.modules:
        from ..render.context import release_context as release

        release()


def require_schema() -> None:
    """Refuse, in one line, when the WrinkleAPI schema cannot be used."""
    from ..usd.schema import require_schema as require

    require()


def register_schema() -> bool:
    """Register the WrinkleAPI schema with USD; whether it is usable."""
    from ..usd import schema

    return bool(schema.register())


def schema_dir() -> str:
    from ..usd import schema

    return str(schema.schema_dir())


#: the Blender add-on's module name (its file is src/usdwrinkle/blender/ADDON_MODULE.py)
ADDON_MODULE = "usdwrinkle_blender"


def blender_addon() -> Path:
    """The Blender add-on's file (it runs in Blender's Python, so it is found, never
    imported, here)."""
    path = Path(__file__).resolve().parents[1] / "blender" / f"{ADDON_MODULE}.py"
    if not path.is_file():
        raise FileNotFoundError(f"the Blender add-on {path} is missing from the installation")
    return path


def copy_blender_addon(folder: str | Path) -> Path:
    """Copy the add-on into ``folder`` (made if missing), as Blender's add-on folders
    hold it (``scripts/addons``); returns the copy's path. The copy is written beside
    and renamed into place, so a Blender reading the folder never sees half a file."""
    target_dir = Path(folder)
    target_dir.mkdir(parents=True, exist_ok=True)
    target = target_dir / f"{ADDON_MODULE}.py"
    staging = target_dir / f".{ADDON_MODULE}.py.partial"
    staging.write_bytes(blender_addon().read_bytes())
    os.replace(staging, target)
    return target
