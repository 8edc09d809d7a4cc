"""usdwrinkle: cloth wrinkles on coarse animated meshes in USD pipelines.

Importing the package registers the WrinkleAPI schema plugin with USD.
"""
from __future__ import annotations

import warnings

__version__ = "0.1.0"

from .process._address_space import lean_usd as _lean_usd  # noqa: E402
from .process._address_space import prepare as _prepare_address_space  # noqa: E402

#: why usdwrinkle cannot run in this process (None: it can); checked before USD loads
UNUSABLE = _prepare_address_space()

__all__ = ["UsdWrinkleError", "WrinkleAPI", "__version__", "log", "profile_from_curve",
           "profile_preset"]

# the warning handler (standard library only), and the module a host configures it by:
# usdwrinkle.log.use_default_handler, collect, silenced
from .process import log  # noqa: E402
from .process.errors import UsdWrinkleError  # noqa: E402  (standard library only)

if UNUSABLE is None:
    _lean_usd()
    from .usd import schema as _schema

    if not _schema.register():
        warnings.warn(
            "usdwrinkle was imported after USD built its schema registry, so WrinkleAPI is "
            "unknown in this process; import usdwrinkle first or set PXR_PLUGINPATH_NAME="
            + _schema.schema_dir(), stacklevel=2)

    def __getattr__(name: str):
        # the authoring API loads on first use: importing usdwrinkle (the usdview plugin
        # does) needs only the standard library and pxr, not numpy
        if name in ("WrinkleAPI", "profile_from_curve", "profile_preset"):
            from . import authoring

            return getattr(authoring, name)
        raise AttributeError(f"module 'usdwrinkle' has no attribute '{name}'")
else:
    def __getattr__(name: str):
        if name in __all__:
            raise UsdWrinkleError(UNUSABLE)
        raise AttributeError(name)
