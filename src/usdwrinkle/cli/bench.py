"""usdwrinkle bench: ``python -m benchmarks`` of the source checkout, in a child process.

The benchmarks (the top-level ``benchmarks/`` package) are not installed with the wheel:
they need the checkout's sample stages, docs/ and the shared corpus, and they import
usdwrinkle as a user would. Nothing here imports them: for an editable install this
command runs ``python -m benchmarks ARGS`` with the checkout on the child's PYTHONPATH.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from ..process.errors import UsdWrinkleError

#: the checkout's top level, for an editable install (src/usdwrinkle/cli/bench.py)
CHECKOUT = Path(__file__).resolve().parents[3]


def add_parser(subparsers) -> None:
    # every option belongs to python -m benchmarks; main() hands them over unparsed
    p = subparsers.add_parser(
        "bench", add_help=False,
        help="measure speed (source checkout): runs python -m benchmarks; "
             "'usdwrinkle bench --help' for its options",
        description="Run the checkout's benchmarks: python -m benchmarks ARGS.")
    p.set_defaults(run=run, forward=True)


def command(forwarded: list[str]) -> tuple[list[str], dict]:
    """The child's argv and environment, or a one-line error outside a checkout."""
    if not (CHECKOUT / "benchmarks" / "__init__.py").is_file():
        raise UsdWrinkleError("usdwrinkle bench runs from a source checkout (pip install -e "
                              ".): the benchmarks/ folder is not part of the installed wheel")
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        part for part in (str(CHECKOUT), env.get("PYTHONPATH", "")) if part)
    return [sys.executable, "-m", "benchmarks", *forwarded], env


def run(args) -> int:
    argv, env = command(args.forwarded)
    return subprocess.call(argv, env=env)
