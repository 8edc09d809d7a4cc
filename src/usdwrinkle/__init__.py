"""usdwrinkle: cloth wrinkles on coarse animated meshes in USD pipelines.

Importing the package registers the WrinkleAPI schema plugin with USD.
"""
from __future__ import annotations

import warnings

__version__ = "0.1.0"

from . import schema as _schema

if not _schema.register():
    warnings.warn(
        "usdwrinkle was imported after USD built its schema registry, so WrinkleAPI is "
        "unknown in this process; import usdwrinkle first or set PXR_PLUGINPATH_NAME="
        + _schema.schema_dir(), stacklevel=2)

from .authoring import WrinkleAPI, profile_from_curve, profile_preset  # noqa: E402

__all__ = ["WrinkleAPI", "__version__", "profile_from_curve", "profile_preset"]
