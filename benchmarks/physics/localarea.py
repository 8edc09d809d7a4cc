"""What the curtains' bars would be if our folds drew the cloth's length in every place
(issue 55: where the area, the heights and the correlation part ways; docs/physics.md,
"Where our area goes, band by band").

    python -m benchmarks.physics.localarea [--write docs/physics.md] [--only SHOT ...]
                                           [--grid M] [--cache .physics-cache]

Below their rings the silk and cotton curtains draw more than the cloth's area, at the
rings every curtain draws less (the bands block). This takes the bake apart in numpy.
Per curtain, baked at its matched W as the converged table matches it
(referee.matched_bakes), once with the simulation's pinned rings marked wrinkle:held, as
the tables bake them, and once without, it prints the bars (the heights over the phases,
ours / the cloth's; the amplitude-field correlation; our area over the rest area where
compressed, referee.area_ratio) of:

- the bake as it is;
- **down**: our folds scaled down wherever they draw more than the rest area
  (length_scaled);
- **exact**: our folds scaled, by at most SCALE_MAX, to draw the rest area wherever the
  cloth is compressed.

Where is a neighbourhood: the areas are taken per grid point (a third of each fine
triangle's) and smoothed with the measure's Gaussian (the shot's window, 5 cm or more of
rest length), over which a posed wave of the curtains' (5-7 cm at half the width) draws
the same length whatever its phase. The displacement scaled is the bake's surface less
its unfolded one, so the deepened pleats scale with the folds. It is numpy on the bake,
not a law: what a law that counted the length of its own blend could buy, and what it
could not.

About 5 minutes here with the 1 cm curtains cached (two matched bakes a curtain).
"""
from __future__ import annotations

import numpy as np

from ..blocks import markers
from . import measure, referee
from .bands import CURTAINS, GRID

NAME = "referee-local-area"
#: the most our folds are scaled up (exact)
SCALE_MAX = 2.0
#: uniform scales tried, from 0 to the largest (length_scaled)
TRIALS = 81


def point_areas(shot, points: np.ndarray) -> np.ndarray:
    """(frames, n): a third of the area of each fine triangle at each of its corners."""
    from .newton_client import triangles

    tri = triangles(shot.quads())
    out = np.zeros(points.shape[:-1])
    for f in range(len(points)):
        a, b, c = (points[f][tri[:, i]] for i in range(3))
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1) / 3.0
        out[f] = sum(np.bincount(tri[:, i], area, out.shape[1]) for i in range(3))
    return out


def length_scaled(shot, low: np.ndarray, flat: np.ndarray, points: np.ndarray,
                  exact: bool, slack: float) -> np.ndarray:
    """(frames, n): per frame and grid point, the scale of its displacement ``points -
    flat`` at which the surface draws the rest area around it (module docstring) where
    the cloth is compressed beyond SLACK_RAMP ``slack`` (``low``, the low-pass, keeps less
    than 1 - SLACK_RAMP slack of its rest area there): ``exact`` everywhere there (at most
    SCALE_MAX), else only where it draws more. The whole displacement is scaled by each of
    TRIALS uniform scales, and each point takes the one (linear between them) at which
    the area around it, less the unfolded surface's, reaches the rest area's excess over
    it: the scale is as local as the Gaussian, and a uniform fold's is exact."""
    from usdwrinkle.method.contract import SLACK_RAMP

    def smooth(field):
        return measure.smooth(shot, field)

    rest = smooth(point_areas(shot, shot.rest[None]))[0]
    compressed = smooth(point_areas(shot, low)) < (1.0 - SLACK_RAMP * slack) * rest
    unfolded = smooth(point_areas(shot, flat))
    wanted = rest - unfolded
    shift = points - flat
    top = SCALE_MAX if exact else 1.0
    trials = np.linspace(0.0, top, TRIALS)
    scale = np.full(points.shape[:-1], top)
    found = np.zeros(points.shape[:-1], bool)
    before = np.zeros(points.shape[:-1])    # the excess at the trial before
    for lo, hi in zip(trials[:-1], trials[1:], strict=True):
        excess = smooth(point_areas(shot, flat + hi * shift)) - unfolded
        crossed = ~found & (excess >= wanted)
        t = (wanted - before) / np.maximum(excess - before, 1e-30)
        scale = np.where(crossed, lo + np.clip(t, 0.0, 1.0) * (hi - lo), scale)
        found |= crossed
        before = excess
    return np.where(compressed, scale, 1.0)


def scaled_bake(sim, baked, exact: bool):
    """``baked`` (oracle.Baked at the simulation's points) with its folds scaled to the
    cloth's length (length_scaled)."""
    from usdwrinkle.usd import schema

    from .coarse import lowpass
    from .oracle import Baked

    shot = sim.shot
    scale = length_scaled(shot, lowpass(shot, sim.points), baked.flat, baked.points, exact,
                          schema.DEFAULT_SLACK)
    points = baked.flat + (baked.points - baked.flat) * scale[..., None]
    out = Baked(baked.label, measure.our_height(shot, points, baked.flat, baked.normals),
                baked.width)
    out.waves, out.points, out.flat, out.normals = baked.waves, points, baked.flat, baked.normals
    return out


def bars(sim, baked) -> dict:
    """The heights over the phases (ours / the cloth's, at matched W), the correlation and
    our area where compressed."""
    from usdwrinkle.usd import schema

    from .oracle import compare, per_phase

    heights = [h for _, h in per_phase(sim, baked).values()]
    return {"heights": (min(heights), max(heights)),
            "correlation": compare(sim, baked)["correlation"],
            "area": referee.area_ratio(sim, baked, schema.DEFAULT_SLACK)}


def shot_rows(name: str, cache, grid: float) -> dict:
    sim, fine = referee.referee_pair(name, cache, grid, referee.CONVERGED[1])
    if fine is not None:
        raise ValueError(f"{name} at {grid * 100:g} cm: localarea measures the bake's own grid")
    out = {}
    for held in (True, False):
        row = referee.matched_bakes(sim, None, referee.cloth_attributes(sim.shot), held)
        baked = row["matched bake"]
        out[held] = {"width": row["width"], "as is": bars(sim, baked),
                     "down": bars(sim, scaled_bake(sim, baked, False)),
                     "exact": bars(sim, scaled_bake(sim, baked, True))}
    return out


def report(rows: dict, seconds: float, grid: float) -> str:
    begin, end = markers(NAME)
    lines = [begin, "", f"Made by `python -m benchmarks.physics.localarea --write docs/physics.md"
             f"` ({seconds:.0f} s here; the simulations at {grid * 100:g} cm and 160 "
             "iterations, cached in .physics-cache).", "",
             "Per curtain at its matched W, with its rings marked `wrinkle:held` (as the "
             "tables bake them) and without: the bake as it is; its folds scaled down wherever "
             "they draw more than the rest area around them; scaled to draw it wherever the "
             "cloth is compressed. Heights over the phases (ours / the "
             "cloth's), the amplitude-field correlation, our area over the rest area where "
             "compressed.", "",
             "| shot | rings held | matched W | as is | down | exact |",
             "|---|---|---|---|---|---|"]

    def bars_cell(b):
        low, high = b["heights"]
        return f"{low:.2f}-{high:.2f}x, {b['correlation']:.3f}, {b['area']:.3f}"

    for name, row in rows.items():
        for held in (True, False):
            r = row[held]
            cells = " | ".join(bars_cell(r[key]) for key in ("as is", "down", "exact"))
            lines.append(f"| {name} | {'yes' if held else 'no'} | {r['width'] * 100:.1f} cm | "
                         f"{cells} |")
    lines += ["", end]
    return "\n".join(lines)


def main(argv=None) -> int:
    return referee.shot_block_main(
        argv, "localarea", NAME, __doc__, shot_rows, report, shots=CURTAINS, grid=GRID,
        grid_doc="the grid the converged table judges the curtains on")


if __name__ == "__main__":
    raise SystemExit(main())
