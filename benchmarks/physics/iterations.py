"""Does the referee's solver converge on a sleeve? (issue 55) The referee block's iteration
table (referee.py, ITERATION_STUDY) has the cotton curtain: at the sweep's 10 VBD
iterations per substep its folds were 1.4-1.8x shorter than at 160. This is the same study
on the sweep's 10 cm cotton sleeve bent on its arm (sweep.sleeve), whose folds the
curvature law was fitted to: 2 cm and 1 cm grids at 10, 40 and 160 iterations.

    python -m benchmarks.physics.iterations [--write docs/physics.md] [--cache .physics-cache]
                                            [--simulate]

Without ``--simulate`` only the cached simulations are read (``not simulated`` rows
otherwise); with it the missing ones are run first, one after another on one core (here:
48 s for the 2 cm sleeve at 10 iterations, 30 minutes for the 1 cm one at 160). Needs
a Python with ``newton`` (simulate.newton_python: .venv-newton). ``--write`` replaces the
block between the "iterations" markers. A benchmark, not a test.
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from .referee import ROOT, SWEEP, iteration_rows, solver_options

#: the sleeve study: sweep shot -> {grid spacing (m): iteration counts}
SLEEVE_STUDY = {"sleeve10-cotton": {0.02: (10, 40, 160), 0.01: (10, 40, 160),
                                    0.005: (160,)}}
#: the sleeve's phases (sweep.sleeve): bent to 90 degrees over frames 10-50, then held
SLEEVE_PHASES = ("bend", "held")


def _runs():
    """(name, spacing, iterations, sweep shot) of every run of the study."""
    for name, spacings in SLEEVE_STUDY.items():
        for spacing, counts in spacings.items():
            for count in counts:
                yield name, spacing, count, SWEEP[name](spacing)


def simulate_missing(cache: Path) -> None:
    from .simulate import cached_newton, simulate_newton

    for name, spacing, count, shot in _runs():
        if cached_newton(shot, cache, solver_options(count)):
            continue
        started = time.perf_counter()
        simulate_newton(shot, cache, solver_options(count))
        print(f"simulated {name} at {100 * spacing:g} cm, {count} iterations: "
              f"{time.perf_counter() - started:.0f} s", flush=True)


def report(cache: Path) -> str:
    from ..blocks import markers
    from .simulate import cached_newton, simulate_newton

    solver = [simulate_newton(shot, cache, solver_options(count))[1]
              for _, _, count, shot in _runs()
              if cached_newton(shot, cache, solver_options(count))]
    lines = [markers("iterations")[0], "", "Made by `python -m benchmarks.physics.iterations "
             f"--write docs/physics.md` (the solver's seconds, one core here: "
             f"{', '.join(f'{s:.0f}' for s in solver) or 'none cached'}).", ""]
    lines += ["The sweep's cotton sleeve (radius 10 cm, bent to 90 degrees on its arm) with "
              "more VBD iterations per substep (the sweep runs 10): the material wavelength "
              "and fold height (RMS) at the end of the bend and of the hold, and in brackets "
              "their ratio to the row above.", "",
              "| shot | grid | iterations | " + " | ".join(SLEEVE_PHASES) + " |",
              "|---|---|---|" + "---|" * len(SLEEVE_PHASES)]
    lines += iteration_rows(cache, SLEEVE_STUDY, SLEEVE_PHASES)
    lines += ["", "usdwrinkle against each of the referee's grid (1 cm) rows, at the W matched "
              "to that simulation's mean wavelength (as the sweep's table above): the crest "
              "motion at the elbow, ours over the simulation's, with the simulation's own "
              "(rad a frame) in brackets, the amplitude-field correlation, and the height "
              "ratio (ours / sim), per phase.", "",
              "| shot | iterations | crest motion: " + " | crest motion: ".join(SLEEVE_PHASES)
              + " | correlation | height: " + " | height: ".join(SLEEVE_PHASES) + " |",
              "|---|---|" + "---|" * (2 * len(SLEEVE_PHASES) + 1)]
    lines += ours_rows(cache)
    lines += ["", markers("iterations")[1]]
    return "\n".join(lines)


def ours_rows(cache: Path) -> list[str]:
    """usdwrinkle against the study's cached simulations at the referee's grid."""
    from .referee import SPACING, simulated, sweep_row
    from .simulate import cached_newton

    rows = []
    for name, spacing, count, shot in _runs():
        if spacing != SPACING or not cached_newton(shot, cache, solver_options(count)):
            continue
        sim = simulated(shot, cache, count)
        row = sweep_row(sim)
        raw = row["compared"]
        motion = [f"{row['motion'][phase]:.2f}x ({raw[f'motion {phase} sim']:.3f})"
                  for phase in SLEEVE_PHASES]
        height = [f"{row['matched'][phase][1]:.2f}x" for phase in SLEEVE_PHASES]
        rows.append(f"| {name} | {count} | " + " | ".join(motion)
                    + f" | {row['correlation']:.2f} | " + " | ".join(height) + " |")
    return rows


def main(argv=None) -> int:
    from ..blocks import emit

    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.iterations")
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    parser.add_argument("--simulate", action="store_true",
                        help="run the simulations that are not cached (hours on 2 cores)")
    parser.add_argument("--write", type=Path, default=None,
                        help="replace the iterations block of this file (docs/physics.md)")
    args = parser.parse_args(argv)
    if args.simulate:
        simulate_missing(args.cache)
    emit(args.write, "iterations", report(args.cache))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
