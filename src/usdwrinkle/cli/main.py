"""usdwrinkle: the console script. ``main(argv) -> int``, errors as one line on stderr.

Exit codes: 0 success, 1 findings (check), 2 user error, 3 internal error, 130 interrupted
(Ctrl-C), 143 terminated (SIGTERM).
"""
from __future__ import annotations

import argparse
import signal
import sys
import threading
import traceback

from .. import __version__


def build_parser() -> argparse.ArgumentParser:
    from . import apply, bake, bench, check, demo, info, render

    parser = argparse.ArgumentParser(
        prog="usdwrinkle",
        description="Plausible cloth wrinkles on coarse animated USD meshes "
                    "(Loviscach 2006: skin, crush, relax, render on the GPU).")
    parser.add_argument("--version", action="version", version=f"usdwrinkle {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (render, bake, apply, check, bench, info, demo):
        module.add_parser(sub)
    return parser


class Terminated(BaseException):
    """SIGTERM (a farm scheduler stopping the job): unwind like Ctrl-C, so that no
    temporary file is left behind."""


def _on_sigterm(signum, frame):
    raise Terminated()


def main(argv: list[str] | None = None) -> int:
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _on_sigterm)
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "command", None):
        parser.print_help(sys.stderr)
        return 2
    from ..errors import UsdWrinkleError

    try:
        return int(args.run(args) or 0)
    except UsdWrinkleError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"usdwrinkle: error: {exc.one_line()}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("usdwrinkle: interrupted; finished frames are intact", file=sys.stderr)
        return 130
    except Terminated:
        print("usdwrinkle: terminated; finished frames are intact", file=sys.stderr)
        return 143
    except Exception as exc:  # a bug in usdwrinkle: still one line, unless --debug
        if args.debug:
            traceback.print_exc()
        print(f"usdwrinkle: internal error: {type(exc).__name__}: {exc} (rerun with --debug "
              "for a traceback, and please report it)", file=sys.stderr)
        return 3


def entry_point() -> None:
    code = main()
    from ..render.context import release_context

    release_context()  # the one GL context of the process, released cleanly
    sys.exit(code)


if __name__ == "__main__":
    entry_point()
