"""usdwrinkle: the console script. ``main(argv) -> int``, errors as one line on stderr.

Exit codes: 0 success, 1 findings (check), 2 user error (also out of memory), 3 internal
error, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM, SIGHUP).
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
    """SIGTERM (a farm scheduler stopping the job) or SIGHUP (a closed terminal or ssh
    session): unwind like Ctrl-C, so that no temporary file is left behind."""


def _on_sigterm(signum, frame):
    raise Terminated()


#: what an interrupted command leaves behind (every output is written atomically)
_AFTER_INTERRUPT = {
    "render": "; finished frames are intact",
    "bake": "; the layer was not written",
    "apply": "; the stage was not changed",
}


def _one_line_warnings() -> None:
    """Python warnings (numpy's RuntimeWarning and the like) as our one-line warnings."""
    import warnings

    from ..errors import print_warning

    def show(message, category, filename, lineno, file=None, line=None):
        print_warning(f"{message} ({category.__name__})")

    warnings.showwarning = show


def main(argv: list[str] | None = None) -> int:
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGTERM, _on_sigterm)
        if hasattr(signal, "SIGHUP"):
            signal.signal(signal.SIGHUP, _on_sigterm)
    _one_line_warnings()
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
        print(f"usdwrinkle: interrupted{_AFTER_INTERRUPT.get(args.command, '')}",
              file=sys.stderr)
        return 130
    except Terminated:
        print(f"usdwrinkle: terminated{_AFTER_INTERRUPT.get(args.command, '')}",
              file=sys.stderr)
        return 143
    except MemoryError:
        print("usdwrinkle: error: out of memory (lower --width/--height, --samples or the "
              "number of meshes, or free memory)", file=sys.stderr)
        return 2
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
