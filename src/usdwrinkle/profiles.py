"""Wrinkle profiles: one period of the height profile H over [0, 2pi), and its gradient.

The one profiles module: the scene delegate's default (the cosine), the presets that
``apply --profile`` and the Python API author, curves resampled to profiles, and the
gradient derived from a height profile.

Every preset peaks at 1 and dips to -1 like the cosine, so the amplitude keeps its
meaning (h = s (W/4) sqrt(1 - r^2) is the crest height). Gradients are derived.
"""
from __future__ import annotations

import numpy as np

from .errors import UsdWrinkleError
from .schema import PROFILE_SAMPLES

_THETA = np.arange(PROFILE_SAMPLES) * (2 * np.pi / PROFILE_SAMPLES)


def _normalise(values: np.ndarray) -> np.ndarray:
    values = np.asarray(values, np.float64)
    values = values - 0.5 * (values.max() + values.min())
    span = 0.5 * (values.max() - values.min())
    return (values / span if span > 0 else values).astype(np.float32)


def _cosine():
    return np.cos(_THETA)


def cosine_profile() -> np.ndarray:
    """The default height profile (no wrinkle:heightProfile): (PROFILE_SAMPLES,) float32."""
    return _cosine().astype(np.float32)


def derive_gradient(height: np.ndarray) -> np.ndarray:
    """dH/dtheta of a periodic profile sampled uniformly over [0, 2pi)."""
    height = np.asarray(height, dtype=np.float64)
    step = 2 * np.pi / len(height)
    return ((np.roll(height, -1) - np.roll(height, 1)) / (2 * step)).astype(np.float32)


def _sharp():
    # narrow folded ridges, broad valleys: a crest that is sharp on top
    return _normalise(np.exp(4.0 * (np.cos(_THETA) - 1.0)))


def _rounded():
    # broad rounded crests, narrow creases between them
    return _normalise(-np.exp(4.0 * (-np.cos(_THETA) - 1.0)))


def _box():
    # pleats: flat tops and bottoms, steep (but smooth) sides
    return _normalise(np.tanh(6.0 * np.cos(_THETA)))


PRESETS = {"cosine": _cosine, "sharp": _sharp, "rounded": _rounded, "box": _box}


def profile_preset(name: str) -> np.ndarray:
    """One of ``cosine``, ``sharp``, ``rounded``, ``box``: (256,) float32."""
    try:
        return np.asarray(PRESETS[name](), np.float32)
    except KeyError:
        raise UsdWrinkleError(f"unknown profile '{name}' (presets: {', '.join(PRESETS)})") \
            from None


def profile_from_curve(points, samples: int = PROFILE_SAMPLES) -> np.ndarray:
    """Resample any periodic curve to a profile.

    Parameters
    ----------
    points : (k,) heights over one period, uniformly spaced, or (k, 2) (theta, height)
        pairs with theta in any unit of one period (sorted and wrapped to [0, 1)).
    """
    arr = np.asarray(points, dtype=np.float64)
    if arr.ndim == 1:
        theta = np.arange(len(arr)) / max(len(arr), 1)
        height = arr
    elif arr.ndim == 2 and arr.shape[1] == 2:
        span = arr[:, 0].max() - arr[:, 0].min()
        period = span * len(arr) / max(len(arr) - 1, 1) if span > 0 else 1.0
        theta = ((arr[:, 0] - arr[:, 0].min()) / period) % 1.0
        height = arr[:, 1]
        order = np.argsort(theta)
        theta, height = theta[order], height[order]
    else:
        raise UsdWrinkleError("a profile curve is (k,) heights or (k, 2) (theta, height) pairs")
    if len(height) < 2 or not np.all(np.isfinite(height)) or not np.all(np.isfinite(theta)):
        raise UsdWrinkleError("a profile curve needs at least 2 finite samples")
    target = np.arange(samples) / samples
    resampled = np.interp(target, theta, height, period=1.0)
    return resampled.astype(np.float32)
