"""Wrinkle profiles: one period of the height profile H over [0, 2pi), and its gradient.

The one profiles module: the scene delegate's default (the cosine), the presets that
``apply --profile`` and the Python API author, curves resampled to profiles, and the
gradient derived from a height profile.

Every preset peaks at 1 and dips to -1, so the amplitude is the crest height. The default
is ``fold``: straight flanks between rounded crests and creases, as cloth folds (a
triangle wave's corners rounded); the fold law restores the cloth's length exactly for
whichever profile a mesh uses (folds.slope_table). Gradients are derived.
"""
from __future__ import annotations

import numpy as np

from ..process.errors import UsdWrinkleError
from ..usd.schema import PROFILE_SAMPLES

_THETA = np.arange(PROFILE_SAMPLES) * (2 * np.pi / PROFILE_SAMPLES)


def _normalise(values: np.ndarray) -> np.ndarray:
    values = np.asarray(values, np.float64)
    values = values - 0.5 * (values.max() + values.min())
    span = 0.5 * (values.max() - values.min())
    return (values / span if span > 0 else values).astype(np.float32)


def _cosine(theta=_THETA):
    return np.cos(theta)


def _fold(theta=_THETA, rounding=None):
    # cloth's folds: the triangle's straight flanks with rounded crests and creases,
    # asin(K cos theta) / asin(K) with K = ``rounding`` (FOLD_ROUNDING; 1: the triangle)
    k = FOLD_ROUNDING if rounding is None else rounding
    return np.arcsin(k * np.cos(theta)) / np.arcsin(k)


#: how rounded the fold preset's crests are: 0.97 rounds about a seventh of a period (0.9
#: until 2026-12-08, a fifth: its folds stood taller than the cloth referee's for the
#: length they hold; docs/decisions.md, "The fold's rounding is 0.97")
FOLD_ROUNDING = 0.97


def default_profile() -> np.ndarray:
    """The default height profile (no wrinkle:heightProfile), ``fold``: (256,) float32.
    Chosen against the converging cloth referee (docs/physics.md): its folds store their
    length at the simulated height, where the cosine's stood 1.2-1.4x too high."""
    return fold_profile(FOLD_ROUNDING)


def fold_profile(rounding: float) -> np.ndarray:
    """The fold with crests rounded by ``rounding`` (K in (0, 1]): (256,) float32."""
    return _fold(rounding=rounding).astype(np.float32)


def turning_phase(height) -> float:
    """max|H'| / max|H''| of a periodic profile sampled uniformly over [0, 2pi): the phase
    (radians) over which its slope turns, what a mesh that draws it must resolve (the
    fold 0.44, the cosine 1, ``sharp`` 0.29, ``box`` 0.22, the triangle's kink about a
    sample); inf for a flat profile."""
    h = np.asarray(height, np.float64)
    step = 2 * np.pi / len(h)
    slope = np.abs(np.roll(h, -1) - np.roll(h, 1)).max() / (2 * step)
    bend = np.abs(np.roll(h, -1) - 2 * h + np.roll(h, 1)).max() / step ** 2
    return float(slope / bend) if bend > 0 else float("inf")


def cosine_profile() -> np.ndarray:
    """The cosine: (PROFILE_SAMPLES,) float32 (the paper's profile; a preset)."""
    return _cosine().astype(np.float32)


def derive_gradient(height: np.ndarray) -> np.ndarray:
    """dH/dtheta of a periodic profile sampled uniformly over [0, 2pi)."""
    height = np.asarray(height, dtype=np.float64)
    step = 2 * np.pi / len(height)
    return ((np.roll(height, -1) - np.roll(height, 1)) / (2 * step)).astype(np.float32)


def _sharp(theta=_THETA):
    # narrow folded ridges, broad valleys: a crest that is sharp on top
    return _normalise(np.exp(4.0 * (np.cos(theta) - 1.0)))


def _rounded(theta=_THETA):
    # broad rounded crests, narrow creases between them
    return _normalise(-np.exp(4.0 * (-np.cos(theta) - 1.0)))


def _box(theta=_THETA):
    # pleats: flat tops and bottoms, steep (but smooth) sides
    return _normalise(np.tanh(6.0 * np.cos(theta)))


def _triangle(theta=_THETA):
    # straight flanks between sharp crests and creases: 1 - 2|theta|/pi over (-pi, pi],
    # the profile whose length the amplitude law restores exactly (docs/method.md)
    return (2.0 / np.pi) * np.arcsin(np.cos(theta))


PRESETS = {"fold": _fold, "cosine": _cosine, "sharp": _sharp, "rounded": _rounded,
           "box": _box, "triangle": _triangle}


def profile_preset(name: str) -> np.ndarray:
    """One of ``fold`` (the default), ``cosine``, ``sharp``, ``rounded``, ``box``,
    ``triangle``: (256,) float32."""
    try:
        return np.asarray(PRESETS[name](), np.float32)
    except KeyError:
        raise UsdWrinkleError(f"unknown profile '{name}' (presets: {', '.join(PRESETS)})") \
            from None


def preset_at(name: str, theta: np.ndarray) -> np.ndarray:
    """A preset evaluated at any phases (float64): what docs/method.md integrates."""
    return np.asarray(PRESETS[name](np.asarray(theta, np.float64)), np.float64)


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
