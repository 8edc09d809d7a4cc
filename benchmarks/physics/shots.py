"""The three shots of the cloth oracle, as numpy: a fine rest grid with material
coordinates, the pinned vertices and where they are at each frame.

Every shot is a regular grid of (rows, columns) fine vertices, in metres, Z up, made of
Blender's Cotton preset (sim_client.py; 10 solver steps a frame and self-collision), with
the grid spacing ``h`` about 1 cm:

- ``sheet``: a curtain 0.96 m wide and 0.64 m high, hanging under gravity from a rail along
  its top edge, its side edges pinned too; sides and rail are pushed together by 20%
  (frames 10-40, the rail's pins evenly, as curtain rings), held (40-55), pushed on to 30%
  (55-75) and held (75-90).
- ``sleeve``: a tube of radius 10 cm and length 0.80 m around an arm (a collider of
  radius 8 cm), its end rings pinned to the arm; the arm bends 90 degrees over 20 cm at
  the middle (frames 10-50, the elbow: the inside of the bend keeps about a fifth of its
  length, a pinch) and is held (50-70). No gravity.
- ``shear``: a square 0.64 m across, hanging, its top and bottom edges pinned; the bottom
  edge slides 16 cm sideways (frames 10-50, a shear of 0.25) and is held (50-65).

All at the same fine spacing: Blender's fold wavelength depends on it (docs/physics.md).
A few tenths of a millimetre of seeded noise across the cloth break the symmetry, as
weave and seams do. The coarse mesh keeps every ``STRIDE``-th grid line (coarse.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from usdwrinkle.authoring.builders import grid_faces

STRIDE = 8          # every 8th grid line makes the coarse mesh
NOISE = 3e-4        # m, the seeded out-of-plane noise
WINDOW = 0.05       # m, the measure's Gaussian (Shot.window)
SOLVER = {"quality": 10, "self_collision": True}


@dataclass
class Shot:
    name: str
    rows: int
    cols: int
    periodic: bool              # columns wrap around (the sleeve)
    rest: np.ndarray            # (rows*cols, 3) m
    material: np.ndarray        # (rows*cols, 2) m: (across, along), arc length on the tube
    pinned: np.ndarray          # (rows*cols,) bool
    frames: int
    gravity: bool
    # (frame, (rows*cols, 3) positions whose pinned entries the pins follow), in order
    keys: list = field(default_factory=list)
    # frame ranges by phase, for the tables
    phases: dict = field(default_factory=dict)
    description: str = ""
    # an animated collider: (rest points, quads, points at each key) or None
    collider: tuple | None = None
    # the coarse mesh keeps every stride-th grid line (a power of 2)
    stride: int = STRIDE
    # solver settings beyond the preset: steps a frame, and self-collision (without it
    # the elbow's folds pass through each other and crumple at the grid's scale)
    solver: dict = field(default_factory=lambda: dict(SOLVER))
    # m: the measure's Gaussian (coarse.lowpass, measure.detail, the amplitude field and
    # the phase demodulation); the referee widens it for long folds (referee.fold_window)
    window: float = WINDOW

    @property
    def spacing(self) -> float:
        m = self.material.reshape(self.rows, self.cols, 2)
        return float(abs(m[0, 1, 0] - m[0, 0, 0]))

    def quads(self) -> np.ndarray:
        _, indices = grid_faces(self.rows, self.cols, wrap_cols=self.periodic)
        return indices.reshape(-1, 4).astype(np.int64)

    def held_distance(self) -> np.ndarray:
        """Material distance (m) of each fine vertex to the nearest pinned vertex."""
        m = self.material
        held = m[self.pinned]
        out = np.empty(len(m))
        for start in range(0, len(m), 2048):
            block = m[start:start + 2048]
            delta = block[:, None, :] - held[None, :, :]
            if self.periodic:
                circumference = self.cols * self.spacing
                delta[..., 0] = (delta[..., 0] + circumference / 2) % circumference \
                    - circumference / 2
            out[start:start + 2048] = np.sqrt((delta ** 2).sum(-1)).min(1)
        return out


def _noise(n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, NOISE, n)


def _ramp(frame, start, end):
    return float(np.clip((frame - start) / (end - start), 0.0, 1.0))


def _hanging_grid(rows: int, cols: int, h: float, seed: int):
    """A vertical grid in the x-z plane, its top row at z = 0, centred on x, with the
    seeded noise across it: (rest, material)."""
    u = np.arange(cols) * h
    v = np.arange(rows) * h
    U, V = np.meshgrid(u, v)
    y = _noise(rows * cols, seed).reshape(rows, cols)
    rest = np.stack([U - u[-1] / 2, y, -V], -1).reshape(-1, 3)
    return rest, np.stack([U, V], -1).reshape(-1, 2)


def sheet(refine: int = 1) -> Shot:
    rows, cols, h = 64 * refine + 1, 96 * refine + 1, 0.01 / refine
    rest, material = _hanging_grid(rows, cols, h, 1)
    pinned = np.zeros((rows, cols), bool)
    # the sides, and the top on its rail (1 cm of each)
    pinned[:, :refine] = pinned[:, -refine:] = pinned[:refine] = True

    def push(frame):
        return 0.2 * _ramp(frame, 10, 40) + 0.1 * _ramp(frame, 55, 75)

    keys = []
    for frame in (1, 10, 40, 55, 75, 90):
        posed = rest.copy()
        posed[:, 0] *= 1.0 - push(frame)
        keys.append((frame, posed))
    shot = Shot("sheet", rows, cols, False, rest, material, pinned.ravel(), 90, True, keys,
                {"push to 20%": (10, 40), "held at 20%": (40, 55), "push to 30%": (55, 75),
                 "held at 30%": (75, 90)},
                "a curtain 0.96 x 0.64 m on a rail, its side edges and rail pushed together "
                "by 20%, then 30%")
    shot.stride = STRIDE * refine
    return shot


ELBOW = 0.20        # m, the length of arm that bends
ARM_RADIUS = 0.08   # m


def bend(points: np.ndarray, angle: float, zone: float = ELBOW) -> np.ndarray:
    """An arm along z bent by ``angle`` about the y axis over ``zone`` at z = 0: below the
    zone unchanged, inside it wrapped on a circular arc, beyond it turned rigidly; +z
    bends towards +x."""
    out = points.astype(np.float64).copy()
    if angle <= 0.0:
        return out
    rho = zone / angle                     # radius of the bent axis
    x, z = points[:, 0], points[:, 2]
    t = np.clip((z + zone / 2) / zone, 0.0, 1.0)      # through the zone
    theta = angle * t
    beyond = np.maximum(z - zone / 2, 0.0)            # past the zone, straight on
    # the axis: straight to -zone/2, then an arc of radius rho about (rho, -zone/2)
    cx = rho - rho * np.cos(theta) + beyond * np.sin(angle)
    cz = -zone / 2 + rho * np.sin(theta) + beyond * np.cos(angle)
    inside = z >= -zone / 2
    # the cross-section turns with the axis
    out[inside, 0] = cx[inside] + x[inside] * np.cos(theta[inside])
    out[inside, 2] = cz[inside] - x[inside] * np.sin(theta[inside])
    return out


def arm_mesh(angle_keys: list[float], radius: float = ARM_RADIUS
             ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """The collider: a closed tube of ``radius`` (rest points, quads, and its points at
    each key's angle)."""
    cols, rows, length = 32, 89, 0.88
    around = np.arange(cols) * (2 * np.pi / cols)
    along = np.linspace(-length / 2, length / 2, rows)
    A, L = np.meshgrid(around, along)
    rest = np.stack([radius * np.cos(A), radius * np.sin(A), L], -1).reshape(-1, 3)
    idx = np.arange(rows * cols).reshape(rows, cols)
    nxt = (np.arange(cols) + 1) % cols
    quads = np.stack([idx[:-1], idx[:-1][:, nxt], idx[1:][:, nxt], idx[1:]], -1)
    return rest, quads.reshape(-1, 4), [bend(rest, a) for a in angle_keys]


def sleeve(refine: int = 1, radius: float = 0.10) -> Shot:
    """The sleeve; ``radius`` other than 10 cm makes the held-out shot of the curvature
    law (its arm 0.8 of the radius, its grid about 1 cm around, a multiple of STRIDE)."""
    length = 0.80
    cols = int(round(2 * np.pi * radius / 0.01 / STRIDE)) * STRIDE * refine  # ~1 cm around
    rows = 80 * refine + 1             # along: 1 cm / refine
    around = np.arange(cols) * (2 * np.pi / cols)
    along = np.linspace(0.0, length, rows)
    A, L = np.meshgrid(around, along)
    rng_r = radius + _noise(rows * cols, 2).reshape(rows, cols)
    x = rng_r * np.cos(A)
    y = rng_r * np.sin(A)
    z = L - length / 2
    rest = np.stack([x, y, z], -1).reshape(-1, 3)
    material = np.stack([A * radius, L], -1).reshape(-1, 2)
    pinned = np.zeros((rows, cols), bool)
    pinned[:refine] = pinned[-refine:] = True

    def angle(frame):
        return np.pi / 2 * _ramp(frame, 10, 50)

    frames = [1] + [10 + 4 * k for k in range(11)] + [70]   # 9 degrees a key
    keys = [(frame, bend(rest, angle(frame))) for frame in frames]
    name = "sleeve" if radius == 0.10 else f"sleeve{100 * radius:.0f}"
    shot = Shot(name, rows, cols, True, rest, material, pinned.ravel(), 70, False, keys,
                {"bend": (10, 50), "held": (50, 70)},
                f"a sleeve of radius {100 * radius:.0f} cm and length 0.80 m on an arm of "
                f"radius {80 * radius:.0f} cm, its end rings pinned, the arm bent 90 degrees "
                "over 20 cm (the elbow)")
    shot.collider = arm_mesh([angle(f) for f in frames],
                             ARM_RADIUS if radius == 0.10 else 0.8 * radius)
    shot.stride = STRIDE * refine
    return shot


def shear() -> Shot:
    rows, cols, h = 65, 65, 0.01
    rest, material = _hanging_grid(rows, cols, h, 3)
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
    return Shot("shear", rows, cols, False, rest, material, pinned.ravel(), 65, True, keys,
                {"shear": (10, 50), "held": (50, 65)},
                "a hanging square 0.64 m across, its bottom edge slid 16 cm sideways")


SHOTS = {"sheet": sheet, "sleeve": sleeve, "shear": shear}
