"""Irregular folds (wrinkle:irregularity; docs/method.md, "Irregular folds") against the
converged referee: every bar of issue 55, and the spectral spread, at a few irregularities.

    python -m benchmarks.physics.irregular [--write docs/physics.md] [--only SHOT ...]
                                           [--values U ...] [--grid M]
                                           [--cache .physics-cache]

Per shot (on the run the converged table judges it on, 1 cm for the curtains, the panels
and the 5 cm sleeve, 2 cm for the others, or every shot on ``--grid`` M; 2 cm for all until
2026-12-07; at the converged referee's 160 iterations) and
irregularity U (authored; 0: the paper's regular waves, the fallback until 2026-12-07,
0.15 since), usdwrinkle is baked as the
referee bakes it (referee.sweep_row with wrinkle:irregularity authored beside the
cloth's preset): at the default W the phases' wavelength ratios (ours / sim, the least and
the largest); at the W matched to the simulation, the phases' height ratios, the amplitude-field
correlation, the crest motion at the elbow (sleeves: bending, held), our wrinkled area
over the rest area where compressed; and at the last phase the spectral spread
sqrt(<f^2>) / <f> of our fold height (measure.spectral_spread; the cloth's beside it).
About 12 s a shot and value here with the simulations cached.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from ..blocks import add_write_option, emit, markers
from . import measure, referee
from .oracle import zones
from .referee import CONVERGED

NAME = "referee-irregular"
VALUES = (0.0, 0.15, 0.3)


def shot_row(name: str, cache: Path, grid: float | None, value: float) -> dict:
    """referee.sweep_row at irregularity ``value``, with the spectral spreads at the last
    phase (the cloth's, ours at the matched W); ``grid`` None: the shot's judged grid."""
    from pxr import Sdf

    from usdwrinkle.usd import schema

    grid = referee.referee_grid(name, True) if grid is None else grid
    sim, fine = referee.referee_pair(name, cache, grid, CONVERGED[1])
    # authored at every value, 0 too: the fallback is not regular since 2026-12-07
    extra = {schema.IRREGULARITY: (Sdf.ValueTypeNames.Float, value)}
    row = referee.sweep_row(sim, fine, extra)
    inside = zones(sim.shot)["all"]
    _, end = list(sim.shot.phases.values())[-1]
    row["spread"] = (measure.spectral_spread(sim.shot, sim.h[end - 1], inside),
                     measure.spectral_spread(sim.shot, row["matched bake"].h[end - 1],
                                             inside))
    row["grid"] = grid
    return row


def span(ratios: list) -> str:
    """The least and the largest of the phases' ratios, as the block prints them."""
    low, high = min(ratios), max(ratios)
    return f"{low:.2f}x" if f"{low:.2f}" == f"{high:.2f}" else f"{low:.2f}-{high:.2f}x"


def report(rows: dict, seconds: float, grid: float | None) -> str:
    end = markers(NAME)[1]
    bars = referee.BARS
    lines = referee.shot_block_head(NAME, "irregular", seconds, grid) + [
             "Per shot and irregularity: the phases' wavelength ratios at the default W, the "
             f"least and the largest (bar {bars['wavelength']}x); at the matched W the "
             f"phases' height ratios (bar {bars['amplitude_matched']}x either way; ours / sim), "
             "the amplitude-field correlation (bar "
             f"{bars['correlation_flat']}, {bars['correlation_shear']} on the shears), the "
             f"crest motion at the elbow (bar {bars['motion']}x), our area where compressed "
             f"(bar {bars['area'][0]}-{bars['area'][1]}; the simulation's own beside it); "
             "the spectral spread of the fold height at the last phase, the cloth's and "
             "ours.", "",
             "| shot | grid | irregularity | matched W | wavelengths (default W) | "
             "heights (matched) | correlation | crest motion | area: ours, sim | "
             "spread: cloth, ours |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for (name, value), row in rows.items():
        wavelengths = [w for w, _ in row["default"].values()]
        heights = [h for _, h in row["matched"].values()]
        motion = ", ".join(f"{phase} {ratio:.2f}x" for phase, ratio in row["motion"].items())
        lines.append(f"| {name} | {100 * row['grid']:g} cm | {value:g} | "
                     f"{100 * row['width']:.1f} cm | "
                     f"{span(wavelengths)} | {span(heights)} | {row['correlation']:.2f} | "
                     f"{motion or '-'} | {row['area']:.3f}, {row['sim_area']:.3f} | "
                     f"{row['spread'][0]:.3f}, {row['spread'][1]:.3f} |")
    return "\n".join(lines + ["", end])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.irregular",
                                     description=__doc__.split("\n\n")[0])
    add_write_option(parser, NAME, "docs/physics.md")
    referee.add_shot_options(parser, grid=None, grid_doc="each shot's judged grid")
    parser.add_argument("--values", nargs="*", type=float, default=list(VALUES),
                        metavar="U", help="the irregularities (default "
                                          f"{' '.join(f'{v:g}' for v in VALUES)})")
    args = parser.parse_args(argv)
    names = referee.chosen_shots(parser, args)
    from usdwrinkle.usd.schema import IRREGULARITY_MAX

    if any(not 0.0 <= v <= IRREGULARITY_MAX for v in args.values):
        parser.error(f"irregularities must be in [0, {IRREGULARITY_MAX:g}]")
    started = time.perf_counter()
    rows = {}
    for name in referee.each_shot("irregular", names):
        for value in args.values:
            rows[(name, value)] = shot_row(name, args.cache, args.grid, value)
    emit(args.write, NAME, report(rows, time.perf_counter() - started, args.grid))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
