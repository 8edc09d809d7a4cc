"""Locate the package's data folders: schemas/, shaders/ and sample_stages/.

In an installed wheel they sit inside the package (hatch force-include); in a
source checkout they sit at the repository's top level. importlib.resources
finds the first; the second is the fallback for editable installs.
"""
from __future__ import annotations

import importlib.resources
from pathlib import Path


def resource_dir(name: str) -> Path:
    """Return the folder ``name`` (``schemas``, ``shaders``, ``sample_stages``)."""
    packaged = importlib.resources.files("usdwrinkle").joinpath(name)
    if packaged.is_dir():
        return Path(str(packaged))
    checkout = Path(__file__).resolve().parents[3] / name
    if checkout.is_dir():
        return checkout
    raise FileNotFoundError(f"usdwrinkle data folder '{name}' is missing from the installation")
