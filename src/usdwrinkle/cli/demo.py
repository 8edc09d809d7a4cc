"""usdwrinkle demo [OUTDIR]: render the bundled shirt sample to PNGs."""
from __future__ import annotations

import argparse
import os

from ..process.errors import UsdWrinkleError


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "demo", help="render the bundled shirt sample stage to PNGs",
        description="Render the bundled shirt sample (sample_stages/shirt.usda, 24 frames) "
                    "to OUTDIR/shirt.####.png with render's defaults: the quickest check "
                    "that usdwrinkle works on this machine.")
    p.add_argument("outdir", nargs="?", default="usdwrinkle_demo",
                   help="output folder (default: ./usdwrinkle_demo)")
    p.add_argument("--width", type=int, default=640, metavar="PX", help="image width (640)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar and no closing line (errors are still printed)")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..process._resources import resource_dir
    from . import render

    stage = str(resource_dir("sample_stages") / "shirt.usda")
    if os.path.exists(args.outdir) and not os.path.isdir(args.outdir):
        raise UsdWrinkleError(f"cannot write the demo into '{args.outdir}': it is a file, "
                              "not a folder")
    # the render subcommand's own parser fills in every option's default, so the demo
    # stays in step with render's options
    parser = argparse.ArgumentParser(prog="usdwrinkle")
    render.add_parser(parser.add_subparsers(dest="command"))
    argv = ["render", stage, os.path.join(args.outdir, "shirt.####.png"),
            "--width", str(args.width)] + (["--quiet"] if args.quiet else [])
    ns = parser.parse_args(argv)
    code = render.run(ns)
    if code == 0 and not args.quiet:
        print(f"usdwrinkle: demo frames are in {os.path.abspath(args.outdir)}")
    return code
