"""What the doors show of the installation and the machine: the GL renderer, the schema's
registration, the process's one GL context."""
from __future__ import annotations

import sys
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
    from ..schema import require_schema as require

    require()


def register_schema() -> bool:
    """Register the WrinkleAPI schema with USD; whether it is usable."""
    from .. import schema

    return bool(schema.register())


def schema_dir() -> str:
    from .. import schema

    return str(schema.schema_dir())
