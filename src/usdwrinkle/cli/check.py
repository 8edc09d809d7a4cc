"""usdwrinkle check STAGE [--json]: USD's own validators plus the WrinkleAPI rules."""
from __future__ import annotations

import json
import sys

from ..app.check import CheckJob


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "check", help="validate a stage: USD's validators and the WrinkleAPI rules",
        description="Run UsdValidation's core, UsdGeom, UsdSkel and UsdShade validators and "
                    "usdwrinkle's WrinkleAPI checker (registered with UsdValidation as "
                    "usdWrinkleValidators:WrinkleAPIChecker). Exit 0 when clean, 1 with "
                    "findings, 2 on usage errors.")
    p.add_argument("stage", help="the USD stage")
    from .common import add_composition_args

    add_composition_args(p)
    p.add_argument("--json", action="store_true", help="machine-readable output on stdout")
    p.add_argument("--wrinkles-only", action="store_true",
                   help="run only usdwrinkle's WrinkleAPI checker, so that the exit code "
                        "gates on the wrinkle attributes alone (USD's own findings, such as "
                        "upAxis or defaultPrim, are left to usdchecker)")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..app.shot import Shot
    from .common import shot_options

    result = CheckJob(Shot(args.stage, shot_options(args)), args.wrinkles_only).run()
    # the status is known before anything is printed: a reader that closes the pipe early
    # (check --json | head) still gets it (cli/main.py)
    args.exit_code = 1 if result.findings else 0
    if args.json:
        json.dump({"stage": args.stage, **result.as_json()}, sys.stdout, indent=2,
                  allow_nan=False)
        sys.stdout.write("\n")
    else:
        for f in result.findings:
            where = f["prim"] + (f".{f['attribute']}" if f["attribute"] else "")
            print(f"{f['type']}: {where}: {f['message']} [{f['validator']}]")
        for entry in result.widths:
            print(f"width: {entry['prim']}: {entry['text']}")
        print(f"usdwrinkle: {len(result.findings)} finding(s) in {args.stage}"
              if result.findings else f"usdwrinkle: {args.stage} is clean")
    return 1 if result.findings else 0
