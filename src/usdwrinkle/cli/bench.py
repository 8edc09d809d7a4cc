"""usdwrinkle bench: a thin entry point to the benchmarks of a source checkout.

The benchmarks (the top-level ``benchmarks/`` package) are not installed with the wheel:
they need the checkout's sample stages, docs/ and the shared corpus. This command finds
the checkout this package was installed from (an editable install) and runs them.
"""
from __future__ import annotations

import sys
from pathlib import Path

#: the checkout's top level, for an editable install (src/usdwrinkle/cli/bench.py)
CHECKOUT = Path(__file__).resolve().parents[3]


def benchmarks():
    """The benchmarks package of the checkout, or a one-line error."""
    from ..errors import UsdWrinkleError

    if not (CHECKOUT / "benchmarks" / "__init__.py").is_file():
        raise UsdWrinkleError("usdwrinkle bench runs from a source checkout (pip install -e "
                              ".): the benchmarks/ folder is not part of the installed wheel")
    if str(CHECKOUT) not in sys.path:
        sys.path.insert(0, str(CHECKOUT))
    import benchmarks as package

    return package


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "bench", help="measure speed: the paper's table, scaling and baselines (checkout)",
        description="Measure the real pipeline: the paper's five cases, scaling in vertices "
                    "and pixels, UsdSkel's CPU skinning and a numpy crush+relax as baselines, "
                    "CesiumMan end to end, the farm rows, triangulation of hostile meshes and "
                    "the rasteriser's floors. Writes a markdown report (and JSON). Runs from "
                    "a source checkout (benchmarks/).")
    p.add_argument("--json", metavar="PATH", help="also write the results as JSON")
    p.add_argument("--markdown", metavar="PATH",
                   help="markdown report (default docs/benchmarks.md, or with --quick "
                        "bench-quick.md in the current folder, so that a smoke test never "
                        "overwrites the committed figures; '-' for stdout)")
    p.add_argument("--quick", action="store_true",
                   help="reduced sizes and frames: a smoke test, not figures to quote")
    p.add_argument("--label", metavar="TEXT",
                   help="name this run in the JSON (kept in docs/bench/ for before/after)")
    p.add_argument("--history", metavar="DIR", default="docs/bench",
                   help="folder of labelled JSON runs to tabulate (docs/bench)")
    p.add_argument("--before", metavar="CHECKOUT",
                   help="a checkout of an earlier usdwrinkle (e.g. a git worktree): the CPU "
                        "render nodes section also runs its default EXR render, in turn with "
                        "this one's, as the before row")
    p.add_argument("--from-json", metavar="PATH",
                   help="measure nothing: rewrite the markdown report from a saved run")
    p.add_argument("--corpus", metavar="DIR",
                   help="folder with usd-wg/CesiumMan.usdz (default ../shared/corpus or "
                        "$USDWRINKLE_CORPUS)")
    p.set_defaults(run=run)


def run(args) -> int:
    if args.markdown is None:
        args.markdown = "bench-quick.md" if args.quick else "docs/benchmarks.md"
    return benchmarks().run(args)
