"""A candidate for the fallbacks, measured on every shot of the converged sweep on the grid
the converged table judges it on (issue 55): the rows that table would print if the
candidate were the code's.

    python -m benchmarks.physics.candidate [--write docs/physics.md] [--only SHOT ...]
        [--slack C] [--irregularity U] [--width CLOTH=CM ...] [--tube CM]
        [--gate LOW HIGH] [--profile NAME] [--cache .physics-cache]

The fallbacks the shots are baked with are set in this process for the run: the slack
and irregularity fallbacks (schema.DEFAULT_SLACK, DEFAULT_IRREGULARITY), the cloth presets
(schema.CLOTH_WIDTHS_M), the tube's width at 10 cm (schema.CURVED_WIDTH_M) and the
coarsening gate's lower window (contract.CURVED_COARSENING[:2]); nothing is authored on the
shots but their cloth, as the converged table bakes them (referee.sweep_row), and with
``--profile`` a height profile (``wrinkle:heightProfile``: a preset, or ``fold<K>``, the
fold's rounding K, fit.profile_values), which a stage would author. Per shot:
the default and the matched W, the wavelength ratios at the default W over the phases,
the heights at the matched W over the phases, the amplitude-field correlation, our area
over the rest area where compressed beyond 3 x the slack, and on the sleeves the crest
motion (bent, held), each against issue 55's bars (referee.BARS). The sample stages'
crest-stability bars are tests (tests/test_stability.py), not measured here: a candidate
the referee likes still has to pass them as the defaults.

Needs the cached simulations (a shot not cached is simulated first: minutes to hours on
one core); about 10 minutes for the ten shots here.
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from ..blocks import add_write_option, emit, markers
from ..fallbacks import fallbacks
from . import referee

NAME = "referee-candidate"


def candidate_text(settings: dict) -> str:
    """The candidate as its command's options say it (only what differs from the code)."""
    parts = []
    for key, value in settings.items():
        if key == "widths":
            parts += [f"{cloth} {100 * metres:.1f} cm" for cloth, metres in value.items()]
        elif key == "tube":
            parts.append(f"tube {100 * value:.1f} cm at 10 cm")
        elif key == "gate":
            parts.append(f"gate ({value[0]:g}, {value[1]:g})")
        elif key == "profile":
            parts.append(f"the profile {value} authored")
        else:
            parts.append(f"{key} {value:g}")
    return ", ".join(parts) or "the code's fallbacks"


def shot_row(name: str, cache, settings: dict) -> dict:
    """One shot's row under the candidate (referee.sweep_row on its judged grid)."""
    from pxr import Sdf

    from usdwrinkle.usd import schema

    from .fit import profile_values

    grid = referee.referee_grid(name, True)
    attributes = {}
    if "profile" in settings:
        attributes[schema.HEIGHT_PROFILE] = (Sdf.ValueTypeNames.FloatArray,
                                             profile_values(settings["profile"]))
    with fallbacks({key: value for key, value in settings.items() if key != "profile"}):
        sim, fine = referee.referee_pair(name, cache, grid, referee.CONVERGED[1])
        row = referee.sweep_row(sim, fine, attributes)
    return {"grid": grid, "default_width": row["default_width"], "width": row["width"],
            "wavelength": [w for w, _ in row["default"].values()],
            "heights": [h for _, h in row["matched"].values()],
            "correlation": row["correlation"], "area": row["area"], "motion": row["motion"],
            "shear": name.startswith("shear")}


def excesses(row: dict) -> dict:
    """bar -> how far the row sits from it: the factor by which it misses the bar (over 1)
    or stays inside it (1 at the bar): its worst phase's wavelength or height ratio, either
    way, over the bar's ratio; the bar's correlation over the row's; the crest motion over
    the bar; for the area, the larger of low / area and area / high (the nearer end)."""
    bars = referee.BARS
    out = {"wavelength": max(max(w, 1 / w) for w in row["wavelength"]) / bars["wavelength"],
           "height": max(max(h, 1 / h) for h in row["heights"]) / bars["amplitude_matched"],
           "correlation": bars["correlation_shear" if row["shear"] else "correlation_flat"]
           / row["correlation"]}
    if row["motion"]:
        out["motion"] = max(row["motion"].values()) / bars["motion"]
    low, high = bars["area"]
    if np.isfinite(row["area"]):
        out["area"] = max(low / row["area"], row["area"] / high)
    return out


def worst(rows: dict) -> tuple[float, str, str]:
    """The worst case over the sweep (issue 55 chooses the laws by it): (the largest
    excess of any row, its shot, its bar)."""
    return max((value, name, bar) for name, row in rows.items()
               for bar, value in excesses(row).items())


def failures(row: dict) -> list[str]:
    """The bars of referee.BARS the row misses (those whose excess is over 1)."""
    return [bar for bar, value in excesses(row).items() if value > 1.0]


def report(rows: dict, seconds: float, settings: dict, argv: list[str]) -> str:
    def span(values):
        low, high = f"{min(values):.2f}", f"{max(values):.2f}"
        return f"{low}x" if low == high else f"{low}-{high}x"

    options = " ".join(argv)
    lines = [markers(NAME)[0], "", "Made by `python -m benchmarks.physics.candidate "
             f"{options}{' ' if options else ''}--write docs/physics.md` ({seconds:.0f} s "
             "here; the simulations at 160 iterations on the grids the converged table "
             "judges them on, cached in .physics-cache).", "",
             f"The candidate: {candidate_text(settings)}.", "",
             "| shot | grid | W default, matched | wavelength (default W) | heights (matched) "
             "| correlation | area | crest motion (bent, held) | misses | worst |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for name, row in rows.items():
        motion = ", ".join(f"{value:.2f}x" for value in row["motion"].values()) or "-"
        lines.append(
            f"| {name} | {100 * row['grid']:g} cm | {100 * row['default_width']:.1f}, "
            f"{100 * row['width']:.1f} cm | {span(row['wavelength'])} | "
            f"{span(row['heights'])} | {row['correlation']:.3f} | {row['area']:.3f} | "
            f"{motion} | {', '.join(failures(row)) or '-'} | {_worst_text(row)} |")
    value, shot, bar = worst(rows)
    lines += ["", f"Worst over these shots: {value:.3f} ({shot}, {bar}). \"worst\": the "
              "largest factor by which the row misses a bar, or under 1 how near it comes to "
              "one (excesses)."]
    lines += ["", markers(NAME)[1]]
    return "\n".join(lines)


def _worst_text(row: dict) -> str:
    bar, value = max(excesses(row).items(), key=lambda item: item[1])
    return f"{value:.3f} ({bar})"


def _width(text: str) -> tuple[str, float]:
    from usdwrinkle.usd import schema

    cloth, _, cm = text.partition("=")
    if cloth not in schema.CLOTH_WIDTHS_M or not cm:
        raise argparse.ArgumentTypeError(
            f"{text!r}: expected CLOTH=CM, CLOTH one of {', '.join(schema.CLOTH_WIDTHS_M)}")
    return cloth, float(cm) / 100.0


def main(argv=None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.candidate",
                                     description=__doc__.split("\n\n")[0])
    add_write_option(parser, NAME, "docs/physics.md")
    referee.add_shot_options(parser, grid=None, grid_doc="each shot's judged grid")
    parser.add_argument("--slack", type=float, default=None, metavar="C",
                        help="the wrinkle:slack fallback (default: the code's)")
    parser.add_argument("--irregularity", type=float, default=None, metavar="U",
                        help="the wrinkle:irregularity fallback (default: the code's)")
    parser.add_argument("--width", type=_width, nargs="*", default=[], metavar="CLOTH=CM",
                        help="cloth presets' flat widths in cm (e.g. cotton=8.1)")
    parser.add_argument("--tube", type=float, default=None, metavar="CM",
                        help="the tube's width at a rest radius of 10 cm, in cm")
    parser.add_argument("--gate", type=float, nargs=2, default=None, metavar=("LOW", "HIGH"),
                        help="the coarsening gate's window, in W over the tube's width")
    parser.add_argument("--profile", default=None, metavar="NAME",
                        help="a height profile authored on every shot: a preset (fold, "
                             "triangle, ...) or foldK, the fold with rounding K (fold0.97)")
    args = parser.parse_args(argv)
    if args.grid is not None:
        parser.error("--grid: the candidate is measured on each shot's judged grid")
    if args.profile is not None:  # refused before the first shot, not after minutes
        from usdwrinkle.process.errors import UsdWrinkleError

        from .fit import profile_values
        try:
            profile_values(args.profile)
        except (UsdWrinkleError, ValueError) as error:
            parser.error(f"--profile: {error}")
    settings = {key: value for key, value in (
        ("slack", args.slack), ("irregularity", args.irregularity),
        ("widths", dict(args.width) or None),
        ("tube", None if args.tube is None else args.tube / 100),
        ("gate", None if args.gate is None else tuple(args.gate)),
        ("profile", args.profile)) if value is not None}
    names = referee.chosen_shots(parser, args)
    # the command as the block names it: its options but --write
    shown = list(argv)
    if "--write" in shown:
        index = shown.index("--write")
        del shown[index:index + 2]
    started = time.perf_counter()
    rows = {name: shot_row(name, args.cache, settings)
            for name in referee.each_shot("candidate", names)}
    emit(args.write, NAME, report(rows, time.perf_counter() - started, settings, shown))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
