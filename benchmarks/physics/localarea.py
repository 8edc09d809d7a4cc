"""What the converged referee's bars would be if our folds drew the cloth's length in
every place (issue 55: where the area, the heights and the correlation part ways;
docs/physics.md, "Where our area goes, band by band").

    python -m benchmarks.physics.localarea [--write docs/physics.md] [--only SHOT ...]
                                           [--grid M] [--cache .physics-cache]

Below their rings the silk and cotton curtains draw more than the cloth's area, at the
rings every curtain draws less (the bands block). This takes the bake apart in numpy.
Per shot of the converged sweep, on the grid the converged table judges it on (--grid:
every shot on that one), baked at its matched W as that table matches it
(referee.matched_bakes) with the simulation's pinned points marked wrinkle:held, as the
tables bake them (the curtains' rings once more without), it prints the bars (the
heights over the phases, ours / the cloth's; the amplitude-field correlation; our area
over the rest area where compressed, referee.area_ratio; the sleeves' crest motion),
with regular folds and again with wrinkle:irregularity IRREGULAR, of:

- the bake as it is;
- **down**: our folds scaled down wherever they draw more than the rest area
  (length_scaled);
- **exact**: our folds scaled, by at most SCALE_MAX, to draw the rest area wherever the
  cloth is compressed.

Where is a neighbourhood: the areas are taken per grid point (a third of each fine
triangle's) and smoothed with the measure's Gaussian (the shot's window, 5 cm and more of
rest length), over which a posed wave draws the same length whatever its phase. The bake
scaled is the one the area is taken on (referee.area_grid: 0.5 cm on the sleeves), and
its displacement, the surface less its unfolded one, so that the deepened pleats scale
with the folds; the heights, the correlation and the crests are measured from it at the
simulation's points. It is numpy on the bake, not a law: what a law that counted the
length of its own blend could buy, and what it could not.

About 30 minutes here with the simulations cached.
"""
from __future__ import annotations

import numpy as np

from ..blocks import markers
from . import measure, referee
from .bands import CURTAINS

NAME = "referee-local-area"
#: the irregularity of the second row of every shot (docs/physics.md, "Irregular folds
#: against the referee": 0.3 brings our folds' spectral spread to the cloth's)
IRREGULAR = 0.3
#: the most our folds are scaled up (exact)
SCALE_MAX = 2.0
#: uniform scales tried, from 0 to the largest (length_scaled)
TRIALS = 81


def point_areas(shot, points: np.ndarray) -> np.ndarray:
    """(frames, n): a third of the area of each fine triangle at each of its corners."""
    from usdwrinkle.geometry.measure import triangle_areas

    from .newton_client import triangles

    tri = triangles(shot.quads())
    out = np.zeros(points.shape[:-1])
    for f in range(len(points)):
        third = triangle_areas(points[f], tri) / 3.0
        out[f] = sum(np.bincount(tri[:, i], third, out.shape[1]) for i in range(3))
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


def bars(sim, baked, base, base_baked) -> dict:
    """The heights over the phases (ours / the cloth's, at matched W), the correlation and
    the crest motion (ours / the cloth's; the sleeves) of ``baked`` (at the simulation's
    points), and our area where compressed, of ``base_baked`` on ``base``'s grid."""
    from usdwrinkle.usd import schema

    from .oracle import compare, motion_ratios, per_phase

    heights = [h for _, h in per_phase(sim, baked).values()]
    result = compare(sim, baked)
    return {"heights": (min(heights), max(heights)), "correlation": result["correlation"],
            "motion": motion_ratios(result),
            "area": referee.area_ratio(base, base_baked, schema.DEFAULT_SLACK)}


def variants(name: str) -> tuple:
    """(held, irregularity) per row of a shot: as the tables bake it, then with
    wrinkle:irregularity IRREGULAR; the curtains once more without their rings held."""
    return ((True, 0.0), (True, IRREGULAR)) + (((False, 0.0),) if name in CURTAINS else ())


def shot_rows(name: str, cache, grid: float | None) -> dict:
    """Per variant (held, irregularity; ``variants``): the matched W and the bars of the
    bake as it is, down and exact. The bake on the grid the area is taken on
    (referee.area_chain) is scaled, and measured at the simulation's points through every
    grid between (oracle.on_coarser_grid)."""
    from pxr import Sdf

    from usdwrinkle.usd import schema

    from .oracle import on_coarser_grid

    grid = referee.referee_grid(name, True) if grid is None else grid
    sim, fine = referee.referee_pair(name, cache, grid, referee.CONVERGED[1])
    out = {}
    for held, irregularity in variants(name):
        cloth = referee.cloth_attributes(sim.shot)
        # authored at every value, 0 too: the fallback is not regular since 2026-12-07
        cloth[schema.IRREGULARITY] = (Sdf.ValueTypeNames.Float, irregularity)
        row = referee.matched_bakes(sim, fine, cloth, held)
        width = row["width"]
        chain = referee.area_chain(sim, fine, width, referee.profile_factor_of(cloth))
        base = chain[-1]
        base_baked = referee.area_bake(chain, width, cloth, row["matched fine"], held)
        shots = [c.shot for c in chain[::-1]] + ([sim.shot] if fine is not None else [])
        entry = {"width": width, "grid": grid}
        for key in ("as is", "down", "exact"):
            scaled = base_baked if key == "as is" else scaled_bake(base, base_baked,
                                                                   key == "exact")
            at_sim = scaled
            for finer, coarser in zip(shots[:-1], shots[1:], strict=True):
                at_sim = on_coarser_grid(at_sim, finer, coarser)
            entry[key] = bars(sim, at_sim, base, scaled)
        out[held, irregularity] = entry
    return out


def report(rows: dict, seconds: float, grid: float | None) -> str:
    end = markers(NAME)[1]
    lines = referee.shot_block_head(NAME, "localarea", seconds, grid) + [
             "Per shot at its matched W, its pinned points marked `wrinkle:held` as the tables "
             f"bake them (the curtains' rings also without), with regular folds and with "
             f"`wrinkle:irregularity` {IRREGULAR:g}: the bake as it is; its folds scaled "
             "down wherever they draw more than the rest area around them; scaled to draw it "
             "wherever the cloth is compressed. Heights over the phases (ours / the cloth's), "
             "the amplitude-field correlation, our area over the rest area where compressed, "
             "and on the sleeves the crest motion (ours / the cloth's, bending and held). "
             "The bake is the one the area is taken on (on the sleeves 0.5 cm, measured at the "
             "simulation's points), so an unscaled row can differ from the converged table's "
             "by a few hundredths.", "",
             "| shot | grid | held | irregularity | matched W | as is | down | exact |",
             "|---|---|---|---|---|---|---|---|"]

    def bars_cell(b):
        low, high = b["heights"]
        motion = "".join(f", {key} {value:.2f}x" for key, value in b["motion"].items())
        return f"{low:.2f}-{high:.2f}x, {b['correlation']:.3f}, {b['area']:.3f}{motion}"

    for name, row in rows.items():
        for (held, irregularity), r in row.items():
            cells = " | ".join(bars_cell(r[key]) for key in ("as is", "down", "exact"))
            lines.append(f"| {name} | {r['grid'] * 100:g} cm | {'yes' if held else 'no'} | "
                         f"{irregularity:g} | {r['width'] * 100:.1f} cm | {cells} |")
    lines += ["", end]
    return "\n".join(lines)


def main(argv=None) -> int:
    return referee.shot_block_main(
        argv, "localarea", NAME, __doc__, shot_rows, report, shots=tuple(referee.SWEEP),
        grid=None, grid_doc="each shot's, the converged table's")


if __name__ == "__main__":
    raise SystemExit(main())
