"""The converged referee's cloth as a height field over its own coarse surface (issue 55:
can a height field meet the height bar and the area bar at once?).

    python -m benchmarks.physics.heightfield [--write docs/physics.md] [--only SHOT ...]
                                             [--grid M] [--cache .physics-cache]

usdwrinkle displaces its fine mesh along the coarse surface's normals: a height field over
the coarse surface. The referee's coarse surface is its simulation low-passed
(coarse.lowpass, the shot's fold window), and the referee's fold height is the cloth's
offset from it along the low-pass's normals (measure.sim_height). Per shot, at the end
of each phase, over the triangles where the low-pass is compressed beyond SLACK_RAMP x
the slack (where referee.area_ratio takes the area bar), this prints:

- the cloth's area over its rest area, the low-pass's, and the area of the cloth's normal
  offsets alone (low + h n: the cloth drawn as a height field, its offsets along the
  surface dropped);
- ``s``: the scale of those offsets at which that height field holds the cloth's own area
  (scale_to_hold). A height field with the cloth's own folds that meets the area bar
  stands s times the cloth's fold height: where s is over the height bar (1.25x), the two
  bars ask that field for two things. Folds of another shape hold more or less length per
  height (docs/physics.md, "What a height field can reach"), so s is the cloth's shape's
  number, not a bound on every profile;
- ``s at the edge``: the same scale where that height field holds the area bar's lowest
  area (referee.BARS, 0.95 of the rest area): the least height at which the cloth's own
  folds, drawn as a height field, meet the area bar at all. Where it is over the height
  bar, no height field of the cloth's folds meets both bars;
- the share of points where an offset towards the low-pass's centre of curvature reaches
  its radius (h k >= 1 along a grid line; beyond it the height field would pass through
  itself): 0 says the cloth is such a height field; the largest h k towards the centre;
  and the share of points whose |h k| exceeds usdwrinkle's room (FOLD_ROOM, which
  limits a fold's height both ways, since a wave's crests and troughs take turns);
- the spectral spread sqrt(<f^2>) / <f> of the cloth's fold height and of usdwrinkle's
  (measure.spectral_spread): at the same small-slope length, folds of spread c stand 1 / c
  as high as one wave of their mean wavelength;
- usdwrinkle's fold height over the cloth's at the W matched to the simulation (baked as
  the converged table matches it: referee.matched_bakes), beside s.

Needs the cached simulations (referee.py; at the converged referee's 160 iterations), on
one grid for every shot (``--grid``, 2 cm; the converged table takes three shots at 1 cm);
about 10-20 s a shot here (two or three bakes).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..blocks import markers
from . import measure, referee
from .oracle import zones
from .referee import CONVERGED

NAME = "referee-heightfield"


def scale_to_hold(area_of, target: float, low: float = 0.0, high: float = 4.0,
                  steps: int = 48) -> float:
    """The scale s in [low, high] at which ``area_of(s)`` (increasing in s) equals
    ``target``, by bisection; ``high`` where even that holds less."""
    if area_of(high) < target:
        return high
    for _ in range(steps):
        middle = 0.5 * (low + high)
        if area_of(middle) < target:
            low = middle
        else:
            high = middle
    return 0.5 * (low + high)


def grid_curvatures(shot, surface: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """(2, n): the surface's normal curvature along its two grid lines, signed towards
    +normals (a centre of curvature on the normals' side is positive)."""
    g = surface.reshape(shot.rows, shot.cols, 3)
    nn = normals.reshape(shot.rows, shot.cols, 3)
    out = []
    for axis, periodic in ((1, shot.periodic), (0, False)):
        if periodic:
            first = 0.5 * (np.roll(g, -1, axis) - np.roll(g, 1, axis))
            second = np.roll(g, -1, axis) - 2 * g + np.roll(g, 1, axis)
        else:
            first = np.gradient(g, axis=axis)
            second = np.gradient(first, axis=axis)
        out.append(((second * nn).sum(-1) / np.maximum((first * first).sum(-1), 1e-30))
                   .ravel())
    return np.stack(out)


def phase_row(shot, points: np.ndarray, slack: float) -> dict | None:
    """One phase's end (points: (n, 3)): the areas, s and the share beyond the reach; None
    where the low-pass is compressed nowhere beyond the slack's ramp."""
    from usdwrinkle.geometry.measure import triangle_areas
    from usdwrinkle.method.contract import FOLD_ROOM, SLACK_RAMP

    from .newton_client import triangles

    tri = triangles(shot.quads())
    rest = triangle_areas(shot.rest, tri)
    low, normals, h = measure.normal_offsets(shot, points)
    inside = zones(shot)["all"]
    compressed = (inside[tri].all(axis=1)
                  & (triangle_areas(low, tri) < (1.0 - SLACK_RAMP * slack) * rest))
    if compressed.sum() < 10:
        return None

    def area(surface):
        return float(triangle_areas(surface, tri)[compressed].sum() / rest[compressed].sum())

    cloth = area(points)
    bent = (h[None] * grid_curvatures(shot, low, normals))[:, inside]
    return {"cloth": cloth, "low": area(low), "offsets": area(low + h[:, None] * normals),
            "s": scale_to_hold(lambda s: area(low + s * h[:, None] * normals), cloth),
            "s edge": scale_to_hold(lambda s: area(low + s * h[:, None] * normals),
                                    referee.BARS["area"][0]),
            "beyond": float((bent >= 1.0).any(axis=0).mean()),
            "toward": float(bent.max()),
            "past room": float((np.abs(bent) > FOLD_ROOM).any(axis=0).mean())}


def shot_rows(name: str, cache: Path, grid: float) -> dict:
    """Per phase (its name: phase_row, with the cloth's spectral spread) for the shot
    simulated on ``grid`` at the converged referee's iterations; and usdwrinkle baked on
    it at the W matched to it as the converged table matches it (referee.matched_bakes),
    with its height ratio and spectral spread per phase."""
    from usdwrinkle.usd import schema

    sim, fine = referee.referee_pair(name, cache, grid, CONVERGED[1])
    bakes = referee.matched_bakes(sim, fine, referee.cloth_attributes(sim.shot))
    width, ours, heights = bakes["width"], bakes["matched bake"], bakes["matched"]
    inside = zones(sim.shot)["all"]
    phases = {}
    for phase, (_, end) in sim.shot.phases.items():
        row = phase_row(sim.shot, sim.points[end - 1], schema.DEFAULT_SLACK)
        if row is not None:
            row["spread"] = measure.spectral_spread(sim.shot, sim.h[end - 1], inside)
            row["our spread"] = measure.spectral_spread(sim.shot, ours.h[end - 1], inside)
            row["wavelength"], row["height"] = heights[phase]
        phases[phase] = row
    return {"grid": grid, "window": sim.shot.window, "width": width, "phases": phases}


def report(rows: dict, seconds: float, grid: float) -> str:
    end = markers(NAME)[1]
    lines = referee.shot_block_head(NAME, "heightfield", seconds, grid) + [
             "At the last phase: the cloth's area over its rest area, its low-pass's, its "
             "normal offsets' alone; s; s at the area bar's edge; the cloth's spectral "
             "spread; usdwrinkle's at the "
             "matched W, and its height there (ours / sim); the share of the cloth's points "
             "whose offset |h k| exceeds usdwrinkle's room (FOLD_ROOM). Then, over every "
             "phase, the worst s, the largest h k towards the centre of curvature and the "
             "share of offsets beyond the reach (h k >= 1).", "",
             "| shot | window | matched W | cloth's area | its low-pass's | its normal "
             "offsets' | s | s at the edge | spread: cloth, ours | height (matched) "
             "| past the room "
             "| s, worst phase | h k towards the centre | beyond the reach |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    detail = []
    for name, row in rows.items():
        phases = {p: r for p, r in row["phases"].items() if r is not None}
        last = list(phases.values())[-1]
        worst_phase, worst = max(phases.items(), key=lambda item: item[1]["s"])
        edge_phase, edge = max(phases.items(), key=lambda item: item[1]["s edge"])
        beyond = max(r["beyond"] for r in phases.values())
        toward = max(r["toward"] for r in phases.values())
        lines.append(f"| {name} | {100 * row['window']:.1f} cm | {100 * row['width']:.1f} cm "
                     f"| {last['cloth']:.3f} | {last['low']:.3f} | {last['offsets']:.3f} | "
                     f"{last['s']:.2f} | {last['s edge']:.2f} | "
                     f"{last['spread']:.3f}, {last['our spread']:.3f} | "
                     f"{last['height']:.2f}x | {100 * last['past room']:.1f}% | "
                     f"{worst['s']:.2f} ({worst_phase}); at the edge {edge['s edge']:.2f} "
                     f"({edge_phase}) | {toward:.2f} | "
                     f"{100 * beyond:.1f}% |")
        detail.append(f"- {name}: " + "; ".join(
            f"{p} {r['s']:.2f} ({r['s edge']:.2f} at the edge), {r['wavelength']:.2f}x, "
            f"{r['height']:.2f}x"
            for p, r in phases.items()))
    lines += ["", "Phase by phase (s, and at the area bar's edge; our wavelength and "
              "height at matched W over the cloth's):", ""] \
        + detail + ["", end]
    return "\n".join(lines)


def main(argv=None) -> int:
    return referee.shot_block_main(argv, "heightfield", NAME, __doc__, shot_rows, report)


if __name__ == "__main__":
    raise SystemExit(main())
