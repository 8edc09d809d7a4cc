"""Choosing the fold law's constants over the sweep (issue 55): each candidate baked on
every shot of the referee, and the worst case over the sweep of the phase-by-phase
wavelength ratio, the amplitude ratio and the amplitude-field correlation.

    python -m benchmarks.physics.fit [--only NAME ...] [--converged] [--grid M] [--matched]
                                     [--exponent ...] [--profile ...] ...

The law's constants are #defines of the crush pass (method/contract.py): a candidate is compiled
in, baked and measured in this process. Not a test: it chose the defaults that
docs/physics.md tabulates.
"""
from __future__ import annotations

import argparse
import itertools
from pathlib import Path

import numpy as np

from . import measure
from .oracle import compare, motion_ratios, per_phase, zones
from .referee import (
    CONVERGED,
    ROOT,
    SWEEP,
    bake_on,
    cloth_attributes,
    matched_width,
    our_area,
    referee_grid,
    referee_pair,
)


def set_law(exponent: float, most: float, room: float | None = None) -> None:
    from usdwrinkle.method import contract
    from usdwrinkle.render import bindings

    for table in (contract.SHADER_DEFINES, bindings.COMMON):
        table["COARSENING_EXPONENT"] = contract.glsl_literal(float(exponent))
        table["COARSENING_MAX"] = contract.glsl_literal(float(most))
        table["FOLD_ROOM"] = contract.glsl_literal(float(room if room is not None
                                                         else contract.FOLD_ROOM))


def profile_values(name: str) -> list[float]:
    """A preset's samples, or ``fold<K>``: asin(K cos theta) / asin(K), a triangle whose
    crests are rounded (K < 1; the fold preset's K is profiles.FOLD_ROUNDING)."""
    from usdwrinkle.method.profiles import fold_profile, profile_preset

    if name.startswith("fold") and name != "fold":
        return fold_profile(float(name[4:])).tolist()
    return profile_preset(name).tolist()


def evaluate(sim, width: float, slack: float, profile: str = "fold", fine=None) -> dict:
    """``fine``: the simulation resampled at half its spacing, which the bake's fine mesh
    follows (referee.bake_on)."""
    from pxr import Sdf

    attributes = {"wrinkle:slack": (Sdf.ValueTypeNames.Float, float(slack)),
                  "wrinkle:heightProfile": (Sdf.ValueTypeNames.FloatArray,
                                            profile_values(profile))}
    ours, on_fine = bake_on(sim, fine, "fit", width, attributes)
    result = compare(sim, ours)
    result["phases"] = per_phase(sim, ours)
    result["area"] = our_area(sim, fine, width, attributes, slack, on_fine)
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.fit")
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    parser.add_argument("--only", nargs="*", default=None)
    from usdwrinkle.method import contract
    from usdwrinkle.usd import schema

    parser.add_argument("--exponent", type=float, nargs="*",
                        default=[contract.COARSENING_EXPONENT])
    parser.add_argument("--most", type=float, nargs="*", default=[contract.COARSENING_MAX])
    parser.add_argument("--slack", type=float, nargs="*", default=[schema.DEFAULT_SLACK])
    parser.add_argument("--profile", nargs="*", default=["fold"],
                        help="presets (fold, cosine, ...) or fold<K>")
    parser.add_argument("--room", type=float, nargs="*", default=[None])
    parser.add_argument("--onset", type=float, nargs="*", default=[1.0],
                        help="W as a share of the simulation's first phase's wavelength")
    parser.add_argument("--converged", action="store_true",
                        help="against the referee at its solver's convergence (referee."
                             "CONVERGED: 2 cm, 160 iterations; 1 cm for CONVERGED_FINER) "
                             "instead of the sweep's")
    parser.add_argument("--grid", type=float, default=None, metavar="M",
                        help="the simulations' spacing in metres instead of the referee's "
                             "(e.g. 0.02 for a curtain judged at 1 cm: a proxy, 25 minutes "
                             "of solver instead of 25-80)")
    parser.add_argument("--matched", action="store_true",
                        help="W matched to each simulation as the referee's table matches "
                             "it (referee.matched_width of the default bake) instead of "
                             "--onset")
    args = parser.parse_args(argv)
    iterations = CONVERGED[1] if args.converged else None
    names = args.only or list(SWEEP)
    pairs = {name: referee_pair(name, args.cache,
                                args.grid or referee_grid(name, args.converged), iterations)
             for name in names}
    sims = {name: pair[0] for name, pair in pairs.items()}
    fines = {name: pair[1] for name, pair in pairs.items()}
    matched = {name: matched_width(sim.shot, per_phase(sim, bake_on(
                   sim, fines[name], "default", None, cloth_attributes(sim.shot))[0]))
               for name, sim in sims.items()} if args.matched else {}
    for exponent, most, slack, onset, profile, room in itertools.product(
            args.exponent, args.most, args.slack, args.onset, args.profile, args.room):
        set_law(exponent, most, room)
        worst = {"wavelength": 1.0, "amplitude": 1.0, "correlation": 1.0, "area": 1.0}
        print(f"exponent {exponent} most {most} slack {slack} onset {onset} {profile} "
              f"room {room}")
        for name, sim in sims.items():
            first = min(sim.shot.phases.values())[1] - 1
            inner = zones(sim.shot)["all"]
            width = matched.get(name) or \
                onset * measure.wavelength(sim.shot, sim.h[first], inner)
            result = evaluate(sim, width, slack, profile, fines[name])
            phases = result["phases"]
            text = " ".join(f"{w:.2f}/{a:.2f}" for w, a in phases.values())
            motion = " ".join(f"{key} {ratio:.2f}x"
                              for key, ratio in motion_ratios(result).items())
            print(f"  {name:16s} W {100 * width:.1f} cm corr {result['correlation']:.3f} "
                  f"area {result['area']:.3f} "
                  f"amp {result['amplitude_ratio']:.2f} per phase (wavelength/height): "
                  f"{text} {motion}")
            for w, a in phases.values():
                worst["wavelength"] = max(worst["wavelength"], w, 1 / w)
                worst["amplitude"] = max(worst["amplitude"], a, 1 / a)
            worst["correlation"] = min(worst["correlation"], result["correlation"])
            if np.isfinite(result["area"]):
                worst["area"] = max(worst["area"], result["area"], 1 / result["area"])
        print("  worst:", {k: round(v, 3) for k, v in worst.items()})
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
