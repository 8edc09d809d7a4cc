"""The sweep of the Newton referee (issue 55; meant to converge, docs/physics.md says how
far it does): Newton's VBD cloth (newton_client.py) on shots with a length scale of their
own (gravity, an arm, clamps), over fabrics whose bending is stated in N m, at any grid
spacing.

- ``FABRICS``: silk to leather, bending D over 64x, one areal density and membrane.
- ``curtain(fabric, spacing)``: a curtain 0.96 x 0.64 m hanging from a rail, its sides and
  rail pushed together from 0 to 48% (frames 10-90) and held (90-100): compression from
  before the onset to beyond 40%, the folds' wavelength read at every 8% of the push.
- ``sleeve(fabric, spacing, radius)``: a sleeve 0.80 m long on an arm of 0.8 its radius
  (capsules, in contact), its end rings pinned, the arm bent 90 degrees over 20 cm (over
  twice the radius beyond 10 cm, so that the bent arm's inner side keeps the 10 cm
  sleeve's proportions instead of passing through itself).
- ``shear(fabric, spacing)``: a hanging square 0.64 m, its bottom edge slid 16 cm.

Every shot is the same cloth at every spacing: the grid halves, D, the density and the
membrane stay (newton_client.py turns D into per-hinge stiffness). The noise that breaks
the symmetry is a smooth field (a few centimetres long, 0.3 mm high), sampled at the grid's
points, so a finer grid starts from the same shape.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .shots import Shot, _ramp, bend

#: fabrics in physical units: bending D (N m); one areal density (kg/m^2) and membrane
#: stiffness (N/m) for all, so that D alone moves the fold length (theory: D^(1/4))
FABRICS = {"silk": 2.5e-6, "cotton": 1.0e-5, "denim": 4.0e-5, "leather": 1.6e-4}
DENSITY = 0.15
MEMBRANE = 2.0e3
THICKNESS = 0.002          # m, self-contact distance
NOISE = 3e-4               # m, the smooth symmetry-breaking field's height

#: m, the curtain's rings along its rail
RING_SPACING = 0.06
#: the fewest coarse points around a sleeve (its coarse mesh keeps every stride-th line)
SLEEVE_AROUND = 8
#: the compression steps at which the curtain's folds are read (share of the width)
CURTAIN_PUSH = 0.48
CURTAIN_STEPS = (0.08, 0.16, 0.24, 0.32, 0.40, 0.48)


@dataclass
class SweepShot:
    shot: Shot
    fabric: str
    clean: np.ndarray            # the cloth's own (noise-free) rest shape
    capsules: list | None = None  # the arm: per key, [(p0, p1, radius)]

    @property
    def bending(self) -> float:
        return FABRICS[self.fabric]


def _smooth_noise(material: np.ndarray, seed: int, scale: float = 0.03) -> np.ndarray:
    """A smooth random field over material coordinates (m): a sum of 48 plane waves of
    wavelength about ``scale``, the same at every grid spacing, RMS NOISE."""
    rng = np.random.default_rng(seed)
    angles = rng.uniform(0, np.pi, 48)
    lengths = scale * rng.uniform(0.7, 1.5, 48)
    phases = rng.uniform(0, 2 * np.pi, 48)
    k = (2 * np.pi / lengths)[:, None] * np.stack([np.cos(angles), np.sin(angles)], 1)
    field = np.cos(material @ k.T + phases).sum(1)
    return NOISE * field / np.sqrt(np.mean(field ** 2))


def _grid(width: float, height: float, spacing: float):
    cols = int(round(width / spacing)) + 1
    rows = int(round(height / spacing)) + 1
    u = np.arange(cols) * spacing
    v = np.arange(rows) * spacing
    U, V = np.meshgrid(u, v)
    material = np.stack([U, V], -1).reshape(-1, 2)
    clean = np.stack([U - u[-1] / 2, np.zeros_like(U), -V], -1).reshape(-1, 3)
    return rows, cols, material, clean


def _band(count: int, spacing: float, width: float = 0.01) -> int:
    """Grid lines in a band ``width`` wide (at least one)."""
    return max(1, int(round(width / spacing)))


def curtain(fabric: str = "cotton", spacing: float = 0.01) -> SweepShot:
    rows, cols, material, clean = _grid(0.96, 0.64, spacing)
    rest = clean.copy()
    rest[:, 1] = _smooth_noise(material, 1)
    pinned = np.zeros((rows, cols), bool)
    band = _band(cols, spacing)
    pinned[:, :band] = pinned[:, -band:] = True
    # curtain rings every RING_SPACING along the rail (material), the same at any grid:
    # a rail pinned along its whole length compressed the top row in-plane at the grid's
    # own scale
    ring = np.abs((material[:cols, 0] / RING_SPACING) - np.round(
        material[:cols, 0] / RING_SPACING)) * RING_SPACING < 0.5 * spacing + 1e-9
    pinned[0, ring] = True

    def push(frame):
        return CURTAIN_PUSH * _ramp(frame, 10, 90)

    keys = []
    for frame in (1, 10, 90, 100):
        posed = rest.copy()
        posed[:, 0] *= 1.0 - push(frame)
        keys.append((frame, posed))
    phases = {f"push to {round(100 * s)}%": (10 + round((s - 0.08) / CURTAIN_PUSH * 80),
                                             10 + round(s / CURTAIN_PUSH * 80))
              for s in CURTAIN_STEPS}
    phases["held at 48%"] = (90, 100)
    shot = Shot(f"curtain-{fabric}", rows, cols, False, rest, material, pinned.ravel(), 100,
                True, keys, phases,
                f"a {fabric} curtain 0.96 x 0.64 m on a rail, its sides and rail pushed "
                f"together by 48%")
    shot.stride = max(1, int(round(0.08 / spacing)))
    return SweepShot(shot, fabric, clean)


def shear(fabric: str = "cotton", spacing: float = 0.01) -> SweepShot:
    rows, cols, material, clean = _grid(0.64, 0.64, spacing)
    rest = clean.copy()
    rest[:, 1] = _smooth_noise(material, 3)
    pinned = np.zeros((rows, cols), bool)
    pinned[0] = pinned[-1] = True
    bottom = np.zeros((rows, cols), bool)
    bottom[-1] = True
    bottom = bottom.ravel()
    keys = []
    for frame in (1, 10, 50, 65):
        posed = rest.copy()
        posed[bottom, 0] += 0.16 * _ramp(frame, 10, 50)
        keys.append((frame, posed))
    shot = Shot(f"shear-{fabric}", rows, cols, False, rest, material, pinned.ravel(), 65, True,
                keys, {"shear": (10, 50), "held": (50, 65)},
                f"a hanging {fabric} square 0.64 m across, its bottom edge slid 16 cm")
    shot.stride = max(1, int(round(0.08 / spacing)))
    return SweepShot(shot, fabric, clean)


ELBOW = 0.20


def elbow_length(radius: float) -> float:
    """The length of arm that bends: ELBOW, or twice the radius on sleeves wider than
    10 cm. A 90-degree bend over z bends the axis at the radius 2 z / pi, and the arm's
    inner side (0.8 of the sleeve's radius) would pass through itself where that falls
    under it; at 2 R every sleeve's bent axis lies 1.27 R from its centre, as the 10 cm
    sleeve's does."""
    return max(ELBOW, 2.0 * radius)


#: the spacing (m) at which a sleeve's ring count is rounded to a multiple of 8 (sleeve)
AROUND_SPACING = 0.02


def sleeve(fabric: str = "cotton", spacing: float = 0.01, radius: float = 0.10
           ) -> SweepShot:
    length = 0.80
    # points around: a multiple of 8 at 2 cm, doubled with each halving of the spacing
    # (sweep.resample needs it; rounding at 0.5 cm gave the 25 cm sleeve 312, not 320)
    coarse = max(spacing, AROUND_SPACING)
    cols = max(8, int(round(2 * np.pi * radius / coarse / 8)) * 8) * max(
        1, int(round(coarse / spacing)))
    rows = int(round(length / spacing)) + 1
    around = np.arange(cols) * (2 * np.pi / cols)
    along = np.linspace(0.0, length, rows)
    A, L = np.meshgrid(around, along)
    material = np.stack([A * radius, L], -1).reshape(-1, 2)
    # the noise on the unrolled sleeve, periodic around it: sampled on the circle's
    # arc length through a field that wraps (two copies blended would not be smooth)
    noise = _smooth_noise(np.stack([radius * np.cos(A).ravel(), radius * np.sin(A).ravel(),
                                    L.ravel()], 1)[:, [0, 2]], 2) \
        + _smooth_noise(np.stack([radius * np.sin(A).ravel(), L.ravel()], 1), 4)
    noise *= NOISE / np.sqrt(np.mean(noise ** 2))
    r = radius + noise.reshape(rows, cols)
    rest = np.stack([r * np.cos(A), r * np.sin(A), L - length / 2], -1).reshape(-1, 3)
    clean = np.stack([radius * np.cos(A), radius * np.sin(A), L - length / 2],
                     -1).reshape(-1, 3)
    pinned = np.zeros((rows, cols), bool)
    band = _band(rows, spacing)
    pinned[:band] = pinned[-band:] = True

    def angle(frame):
        return np.pi / 2 * _ramp(frame, 10, 50)

    zone = elbow_length(radius)
    frames = [1] + [10 + 4 * k for k in range(11)] + [70]
    keys = [(frame, bend(rest, angle(frame), zone)) for frame in frames]
    arm = 0.8 * radius
    # the arm as capsules along its bent axis: 2 straight ones and 10 through the elbow
    capsules = []
    for frame in frames:
        a = angle(frame)
        zs = np.concatenate([[-length / 2 - 0.04], np.linspace(-zone / 2, zone / 2, 11),
                             [length / 2 + 0.04]])
        axis = bend(np.stack([np.zeros_like(zs), np.zeros_like(zs), zs], 1), a, zone)
        capsules.append([(axis[k], axis[k + 1], arm) for k in range(len(zs) - 1)])
    name = f"sleeve{round(100 * radius)}-{fabric}"
    shot = Shot(name, rows, cols, True, rest, material, pinned.ravel(), 70, False, keys,
                {"bend": (10, 50), "held": (50, 70)},
                f"a {fabric} sleeve of radius {100 * radius:.0f} cm on an arm of radius "
                f"{80 * radius:.0f} cm, its end rings pinned, bent 90 degrees over "
                f"{100 * zone:.0f} cm")
    # coarse lines 8 cm apart, as on the flat shots, but at least SLEEVE_AROUND of them
    # around the sleeve (4 around the 5 cm sleeve made its coarse mesh a square tube)
    shot.stride = max(1, int(round(0.08 / spacing)))
    while shot.stride > 1 and cols // shot.stride < SLEEVE_AROUND:
        shot.stride //= 2
    return SweepShot(shot, fabric, clean, capsules)


def spec(sweep_shot: SweepShot, solver: dict | None = None) -> dict:
    """The arrays newton_client.py reads."""
    shot = sweep_shot.shot
    out = dict(rest=shot.rest, clean=sweep_shot.clean, quads=shot.quads(), pinned=shot.pinned,
               key_frames=np.array([f for f, _ in shot.keys]),
               key_points=np.stack([p for _, p in shot.keys]), frames=np.array(shot.frames),
               gravity=np.array(shot.gravity), bending=np.array(sweep_shot.bending),
               density=np.array(DENSITY), stretch=np.array(MEMBRANE),
               thickness=np.array(THICKNESS))
    if sweep_shot.capsules is not None:
        caps = np.array([[np.concatenate([p0, p1, [r]]) for p0, p1, r in key]
                         for key in sweep_shot.capsules])
        out["capsules"] = caps   # (keys, capsules, 7)
    out.update({k: np.array(v) for k, v in (solver or {}).items()})
    return out


def _midpoints(grid: np.ndarray, axis: int, periodic: bool) -> np.ndarray:
    """``grid`` with a point half-way between each pair of neighbours along ``axis`` (the
    four-point cubic (-1, 9, 9, -1) / 16, exact for cubics; an open border extended
    linearly), the originals kept: n points become 2n - 1 (open) or 2n (periodic)."""
    g = np.moveaxis(grid, axis, 0)
    if periodic:
        padded = np.concatenate([g[-1:], g, g[:2]])
    else:
        padded = np.concatenate([2 * g[:1] - g[1:2], g, 2 * g[-1:] - g[-2:-1]])
    mid = (-padded[:-3] + 9 * padded[1:-2] + 9 * padded[2:-1] - padded[3:]) / 16
    count = len(g)
    out = np.empty((2 * count - (0 if periodic else 1), *g.shape[1:]), g.dtype)
    out[0::2] = g
    out[1::2] = mid
    return np.moveaxis(out, 0, axis)


def resample(points: np.ndarray, coarse: SweepShot, fine: SweepShot) -> np.ndarray:
    """A simulation's points (frames, n, 3) on ``coarse``'s grid, on ``fine``'s grid of half
    its spacing (the same shot): a smooth surface through the simulated points, so that
    usdwrinkle's bake, whose fine mesh is the grid it is measured on, is not band-limited
    by the simulation's grid (its displacement fades under 2-3 edges a wavelength)."""
    a, b = coarse.shot, fine.shot
    if not a.periodic and (b.rows, b.cols) != (2 * a.rows - 1, 2 * a.cols - 1) or \
            a.periodic and (b.rows, b.cols) != (2 * a.rows - 1, 2 * a.cols):
        raise ValueError(f"{b.name}'s grid {b.rows} x {b.cols} is not {a.rows} x {a.cols} "
                         "at half the spacing")
    grid = points.reshape(len(points), a.rows, a.cols, 3)
    grid = _midpoints(_midpoints(grid, 2, a.periodic), 1, False)
    return grid.reshape(len(points), -1, 3)
