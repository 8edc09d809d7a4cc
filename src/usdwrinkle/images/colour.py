"""sRGB transfer functions (IEC 61966-2-1), the one place they are written.

8-bit images are sRGB encoded (UsdUVTexture's ``sourceColorSpace = auto``); usdwrinkle
computes in linear light. ``displayColor`` is linear too.
"""
from __future__ import annotations

import numpy as np


def srgb_encode(linear) -> np.ndarray:
    """Linear [0, 1] -> sRGB-encoded [0, 1] (clipped)."""
    c = np.clip(np.asarray(linear), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def srgb_decode(encoded) -> np.ndarray:
    """sRGB-encoded [0, 1] -> linear [0, 1]."""
    c = np.asarray(encoded)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


#: the 256 linear values of 8-bit sRGB codes
_DECODE_8BIT = srgb_decode(np.arange(256, dtype=np.float64) / 255.0).astype(np.float32)


def srgb_decode_8bit(encoded: np.ndarray) -> np.ndarray:
    """sRGB decode of values that came from 8-bit codes (k / 255): a table lookup, the same
    numbers as srgb_decode, several times faster on a 2048² texture."""
    codes = np.rint(np.asarray(encoded, np.float32) * 255.0).clip(0, 255).astype(np.uint8)
    return _DECODE_8BIT[codes]
