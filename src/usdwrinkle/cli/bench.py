"""usdwrinkle bench: the paper's table, scaling and baselines (see usdwrinkle.bench)."""
from __future__ import annotations


def add_parser(subparsers) -> None:
    from ..bench import add_arguments

    p = subparsers.add_parser(
        "bench", help="measure speed: the paper's table, scaling and baselines",
        description="Measure the real pipeline: the paper's five cases, scaling in vertices "
                    "and pixels, UsdSkel's CPU skinning and a numpy crush+relax as baselines, "
                    "and CesiumMan end to end. Writes a markdown report (and JSON).")
    add_arguments(p)
    p.set_defaults(run=run)


def run(args) -> int:
    from ..bench import run as run_bench

    return run_bench(args)
