"""Authoring: the WrinkleAPI schema class, profile presets and painting q from textures."""
from .api import WrinkleAPI
from .profiles import PRESETS, profile_from_curve, profile_preset

__all__ = ["PRESETS", "WrinkleAPI", "profile_from_curve", "profile_preset"]
