"""The measurements of the cloth oracle, the same for the simulation and for usdwrinkle's
displaced mesh, at the same material points (the simulation's rest grid).

- height ``h``: the simulation's fine points minus their low-pass (coarse.lowpass), along
  the low-pass surface's normal; usdwrinkle's displaced fine points minus the undisplaced
  ones (a bake with wrinkle:amplitudeScale 0), along the undisplaced normal.
- the Gaussians (the low-pass, the detail, the amplitude field, the phase demodulation):
  the shot's window, Shot.window (5 cm; the referee widens it where the folds are long).
- amplitude field: sqrt(2 G * h^2), G a Gaussian of the window on the rest grid (the local
  amplitude of a sine); "where" is the correlation of the two fields.
- amplitude: the RMS of h over the cloth, ours over the simulation's.
- wavelength: the material (rest-space) wavelength, 1 / the power-weighted mean spatial
  frequency of h (Hann-windowed 2D spectrum of the rest grid).
- crest direction: the dominant eigenvector of the structure tensor of grad h on the rest
  grid (the wave direction, across the crests), compared modulo 180 degrees.
- held-edge energy: the share of sum h^2 within 10 cm (material) of a pinned vertex.
- crest motion: per frame, the change of the local phase arg(G * (h exp(-i k0.X))), k0
  the zone's dominant material wave vector, weighted by the local amplitude.
"""
from __future__ import annotations

import numpy as np

from .coarse import _smooth_axis, lowpass
from .shots import Shot

EDGE = 0.10       # m, "near a held edge"


def grid_normals(shot: Shot, points: np.ndarray) -> np.ndarray:
    """Unit normals of a surface given on the shot's grid: (..., n, 3)."""
    g = points.reshape(*points.shape[:-2], shot.rows, shot.cols, 3)
    dv = np.gradient(g, axis=-3)
    if shot.periodic:
        du = 0.5 * (np.roll(g, -1, axis=-2) - np.roll(g, 1, axis=-2))
    else:
        du = np.gradient(g, axis=-2)
    n = np.cross(du, dv)
    n /= np.linalg.norm(n, axis=-1, keepdims=True) + 1e-30
    return n.reshape(points.shape)


def normal_offsets(shot: Shot, points: np.ndarray, low: np.ndarray | None = None):
    """The cloth over its low-pass, (frames, n, 3) or (n, 3) points: (the low-pass, its
    normals, the points' offsets from it along them, not band-passed). ``low``:
    lowpass(shot, points), where the caller has it already."""
    low = lowpass(shot, points) if low is None else low
    normals = grid_normals(shot, low)
    return low, normals, ((points - low) * normals).sum(-1)


def sim_height(shot: Shot, points: np.ndarray, low: np.ndarray | None = None) -> np.ndarray:
    """(frames, n): the simulated fold height over the low-passed surface, band-passed
    (``low``: lowpass(shot, points), where the caller has it already)."""
    return detail(shot, normal_offsets(shot, points, low)[2])


def our_height(shot: Shot, points: np.ndarray, flat: np.ndarray,
               normals: np.ndarray) -> np.ndarray:
    """(frames, n): usdwrinkle's displacement along the undisplaced normal, band-passed."""
    return detail(shot, ((points - flat) * normals).sum(-1))


def detail(shot: Shot, h: np.ndarray) -> np.ndarray:
    """h less its own Gaussian (the shot's window) average: the folds without what the low-pass
    leaves where the surface bends on the scale of the filter (the outer elbow), applied
    alike to both."""
    return h - smooth(shot, h)


def smooth(shot: Shot, field: np.ndarray, sigma: float | None = None) -> np.ndarray:
    """A Gaussian of ``sigma`` (m; the shot's window) on the rest grid, over the last axis
    (n,)."""
    g = field.reshape(*field.shape[:-1], shot.rows, shot.cols)
    s = (shot.window if sigma is None else sigma) / shot.spacing
    g = _smooth_axis(g, g.ndim - 2, s, False)
    g = _smooth_axis(g, g.ndim - 1, s, shot.periodic)
    return g.reshape(field.shape)


def amplitude_field(shot: Shot, h: np.ndarray) -> np.ndarray:
    return np.sqrt(2.0 * np.maximum(smooth(shot, h * h), 0.0))


def correlation(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a.ravel() - a.mean(), b.ravel() - b.mean()
    return float((a * b).sum() / np.sqrt((a * a).sum() * (b * b).sum() + 1e-300))


def rms(h: np.ndarray, mask=None) -> float:
    values = h if mask is None else h[..., mask]
    return float(np.sqrt(np.mean(values ** 2)))


def _spectrum(shot: Shot, h: np.ndarray, mask=None):
    """Power and spatial frequency (cycles/m) of h on the rest grid, Hann-windowed."""
    g = h.reshape(shot.rows, shot.cols).copy()
    if mask is not None:
        g *= mask.reshape(shot.rows, shot.cols)
    window = np.hanning(shot.rows)[:, None]
    if not shot.periodic:
        window = window * np.hanning(shot.cols)[None, :]
    rows_h = shot.material[shot.cols, 1] - shot.material[0, 1]
    power = np.abs(np.fft.fft2(g * window)) ** 2
    fv = np.fft.fftfreq(shot.rows, rows_h)[:, None]
    fu = np.fft.fftfreq(shot.cols, shot.spacing)[None, :]
    return power, fu, fv


def _folds_spectrum(shot: Shot, h: np.ndarray, mask=None):
    """The folds' part of _spectrum: (power weights summing to 1, spatial frequency
    (cycles/m)), frequencies below 1 / 0.4 m (the low-pass's own range) left out."""
    power, fu, fv = _spectrum(shot, h, mask)
    f = np.hypot(fu, fv)
    keep = f > 2.5
    return power[keep] / power[keep].sum(), f[keep]


def wavelength(shot: Shot, h: np.ndarray, mask=None) -> float:
    """Material wavelength (m): 1 / the power-weighted mean spatial frequency
    (_folds_spectrum)."""
    weights, f = _folds_spectrum(shot, h, mask)
    return float(1.0 / (weights * f).sum())


def spectral_spread(shot: Shot, h: np.ndarray, mask=None) -> float:
    """sqrt(<f^2>) / <f> of h's power spectrum (power-weighted; the frequencies
    ``wavelength`` reads): 1 for one plane wave. At small slopes a fold pattern holds
    extra length (1/2)<|grad h|^2> = 2 pi^2 <f^2> <h^2>: for the same length, one of
    unequal waves stands 1 / spread as high as a single wave of its mean wavelength."""
    weights, f = _folds_spectrum(shot, h, mask)
    return float(np.sqrt((weights * f ** 2).sum()) / (weights * f).sum())


def structure_direction(shot: Shot, h: np.ndarray, mask=None) -> np.ndarray:
    """The dominant wave direction (unit, material (u, v)): across the crests."""
    g = h.reshape(shot.rows, shot.cols)
    rows_h = shot.material[shot.cols, 1] - shot.material[0, 1]
    dv = np.gradient(g, rows_h, axis=0)
    if shot.periodic:
        du = (np.roll(g, -1, axis=1) - np.roll(g, 1, axis=1)) / (2 * shot.spacing)
    else:
        du = np.gradient(g, shot.spacing, axis=1)
    w = np.ones_like(g) if mask is None else mask.reshape(g.shape).astype(float)
    J = np.array([[(w * du * du).sum(), (w * du * dv).sum()],
                  [(w * du * dv).sum(), (w * dv * dv).sum()]])
    values, vectors = np.linalg.eigh(J)
    return vectors[:, -1]


def angle_between(a: np.ndarray, b: np.ndarray) -> float:
    """Degrees between two directions, modulo 180."""
    c = abs(float(np.dot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b) + 1e-300))
    return float(np.degrees(np.arccos(min(c, 1.0))))


def local_phase(shot: Shot, h: np.ndarray, k0: np.ndarray) -> np.ndarray:
    """arg of the demodulated signal G * (h exp(-i k0 . X)), complex (n,)."""
    carrier = np.exp(-1j * (shot.material @ k0))
    z = h * carrier
    return smooth(shot, z.real) + 1j * smooth(shot, z.imag)


def crest_motion(shot: Shot, h: np.ndarray, mask: np.ndarray, frames: range) -> float:
    """Mean |phase change| per frame (rad) over ``frames`` (pairs f, f+1, 0-based), the
    carrier of each pair from frame f's dominant direction and wavelength in ``mask``,
    weighted by the local amplitude."""
    total, weight = 0.0, 0.0
    for f in frames:
        if not np.any(h[f][mask]) or not np.any(h[f + 1][mask]):
            continue  # no wave yet (or none left): no phase to follow
        d = structure_direction(shot, h[f], mask)
        lam = wavelength(shot, h[f], mask)
        k0 = 2 * np.pi / lam * d
        z0 = local_phase(shot, h[f], k0)[mask]
        z1 = local_phase(shot, h[f + 1], k0)[mask]
        step = np.abs(np.angle(z1 * np.conj(z0)))
        w = np.abs(z0) * np.abs(z1)
        total += float((step * w).sum())
        weight += float(w.sum())
    return total / max(weight, 1e-300)
