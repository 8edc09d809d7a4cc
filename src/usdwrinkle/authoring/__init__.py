"""Authoring: the WrinkleAPI schema class, profile presets and painting q from textures."""
from ..method.profiles import PRESETS, profile_from_curve, profile_preset
from .api import WrinkleAPI

__all__ = ["PRESETS", "WrinkleAPI", "profile_from_curve", "profile_preset"]
