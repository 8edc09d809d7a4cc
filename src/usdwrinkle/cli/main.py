"""usdwrinkle: the console script. ``main(argv) -> int``, errors as one line on stderr.

Exit codes: 0 success, 1 findings (check), 2 user error (also out of memory), 3 internal
error, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM, SIGHUP).
"""
from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import traceback

from .. import __version__
from ..process.errors import STDERR, print_stderr, print_warning
from ..process.signals import held_here


class OneLineParser(argparse.ArgumentParser):
    """argparse with usdwrinkle's error contract: a usage error is one line,
    ``usdwrinkle: error: <what> (see 'usdwrinkle COMMAND --help')``, and exit 2, not
    argparse's usage block followed by its own error line."""

    def error(self, message: str):
        from ..process.errors import print_stderr

        print_stderr(f"usdwrinkle: error: {' '.join(message.split())} "
                     f"(see '{self.prog} --help')")
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    from . import addon, apply, bake, bench, check, demo, info, paint, render

    parser = OneLineParser(
        prog="usdwrinkle",
        description="Plausible cloth wrinkles on coarse animated USD meshes "
                    "(Loviscach 2006: skin, crush, relax, render on the GPU).")
    parser.add_argument("--version", action="version", version=f"usdwrinkle {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in (render, bake, apply, paint, check, bench, info, demo, addon):
        module.add_parser(sub)
    #: each subcommand's parser (usdwrinkle.api checks its keywords with them)
    parser.commands = dict(sub.choices)
    for command in sub.choices.values():
        # also after the subcommand; SUPPRESS: unset here must not undo it given before
        command.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                             help="show tracebacks on errors")
    return parser


#: options whose value may start with '-' (a negative frame): argparse takes such a
#: value for an option of its own unless it is attached with '='
_SIGNED_VALUES = ("--frames", "--history-start")


def _attach_signed_values(argv: list[str]) -> list[str]:
    """``--frames -5:-3`` -> ``--frames=-5:-3`` (and the same for --history-start)."""
    out: list[str] = []
    items = iter(argv)
    for item in items:
        if item in _SIGNED_VALUES:
            value = next(items, None)
            if value is not None and value.startswith("-") and value[1:2].isdigit():
                out.append(f"{item}={value}")
                continue
            out.append(item)
            if value is not None:
                out.append(value)
            continue
        out.append(item)
    return out


class Terminated(BaseException):
    """SIGTERM (a farm scheduler stopping the job) or SIGHUP (a closed terminal or ssh
    session): unwind like Ctrl-C, so that no temporary file is left behind."""


def _stop_signals() -> list:
    return [getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP")
            if hasattr(signal, name)]


#: stop signals put off by _on_stop (asked again in 20 ms): a run that ends before they come
#: back still ends as stopped, never with 0, so that a signal held in a writer thread's
#: atomic rename and put off in a fragile moment of the last frame is not lost to the exit
_DEFERRED: list = []


def _on_stop(signum, frame):
    """The first stop signal unwinds the run (its cleanup removes temporary files and
    finishes the frames handed to the writer). Later ones are ignored until the process
    exits: a second Ctrl-C a few milliseconds after the first would land in the middle of
    that cleanup, or in the GL and thread teardown after it, and abort the process
    (SIGABRT) instead of exit 130."""
    if _fragile(frame) or held_here():
        # an exception raised here would land inside a C extension's module init
        # (OpenImageIO's nanobind enums abort the process, USD's boost.python swallows
        # it), inside moderngl's wrapper of a GL object being made (a half-made object
        # whose release segfaulted, about once in 150 Ctrl-Cs), or inside a section that
        # holds the signals, which another thread took (a temporary file made and not yet
        # owned by its cleanup was left behind): ask again in 20 ms
        _DEFERRED.append(signum)
        threading.Timer(0.02, os.kill, (os.getpid(), signum)).start()
        return
    _DEFERRED.clear()
    for other in _stop_signals():
        signal.signal(other, signal.SIG_IGN)
    if signum == signal.SIGINT:
        raise KeyboardInterrupt()
    raise Terminated()


#: where a stop signal's exception must not be raised (see _on_stop)
_FRAGILE_MODULES = ("moderngl", "glcontext")


def _fragile(frame) -> bool:
    """True when ``frame`` runs inside an import (importlib's bootstrap is on its stack)
    or inside moderngl's own Python code."""
    while frame is not None:
        filename = frame.f_code.co_filename
        if filename.startswith("<frozen importlib._bootstrap") or \
                frame.f_globals.get("__name__", "").split(".")[0] in _FRAGILE_MODULES:
            return True
        frame = frame.f_back
    return False


def _install_stop_handlers() -> dict:
    """Our stop handlers on the main thread; returns the previous ones."""
    if threading.current_thread() is not threading.main_thread():
        return {}
    return {sig: signal.signal(sig, _on_stop) for sig in _stop_signals()}


#: what an interrupted command leaves behind (every output is written atomically)
_AFTER_INTERRUPT = {
    "render": "; finished frames are intact",
    "bake": "; the layer was not written",
    "apply": "; the stage was not changed",
}


def _one_line_warnings() -> None:
    """Python warnings (numpy's RuntimeWarning and the like) as our one-line warnings."""
    import warnings

    from ..process.log import warn

    def show(message, category, filename, lineno, file=None, line=None):
        warn(f"{message} ({category.__name__})")

    warnings.showwarning = show
    # numpy's floating-point warnings ("overflow encountered in multiply") tell a user
    # nothing: every value that matters is checked for NaN and Inf where it is read or
    # written, and refused there naming its prim and attribute
    import numpy

    numpy.seterr(all="ignore")


def main(argv: list[str] | None = None) -> int:
    previous = _install_stop_handlers()
    try:
        code = _main(argv)
        if _DEFERRED and code not in (130, 143):  # a stop that was put off, then outrun
            said = "interrupted" if _DEFERRED[0] == signal.SIGINT else "terminated"
            print_stderr(f"usdwrinkle: {said}")
            code = 130 if said == "interrupted" else 143
            for sig in _stop_signals():  # its repeat, still on its way, changes nothing
                signal.signal(sig, signal.SIG_IGN)
    except KeyboardInterrupt:  # before the command ran (start-up: imports, parsing)
        print_stderr("usdwrinkle: interrupted")
        code = 130
    except Terminated:
        print_stderr("usdwrinkle: terminated")
        code = 143
    if code not in (130, 143):  # after a stop, the process exits: stay deaf to more
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    return code


def _main(argv: list[str] | None) -> int:
    from .. import UNUSABLE

    if UNUSABLE is not None:  # before USD, Mesa or numpy reserves anything
        print_stderr(f"usdwrinkle: error: {UNUSABLE}")
        return 2
    import os

    try:
        os.getcwd()
    except FileNotFoundError:  # relative paths (and USD's anchoring) need it
        print_stderr("usdwrinkle: error: the current folder no longer exists (it was deleted "
                     "or moved); change to an existing folder")
        return 2
    _one_line_warnings()
    parser = build_parser()
    args, extra = parser.parse_known_args(
        _attach_signed_values(sys.argv[1:] if argv is None else argv))
    if getattr(args, "forward", False):  # bench: its options are python -m benchmarks'
        args.forwarded = extra
    elif extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if not getattr(args, "command", None):
        parser.print_help(STDERR)
        return 2
    from ..process.errors import UsdWrinkleError
    from ..process.log import warnings_to
    from .flags import flagged

    try:
        # a warning names the option fields of the jobs below in backquotes: here, flags
        with warnings_to(lambda message: print_warning(flagged(message))):
            return int(args.run(args) or 0)
    except BrokenPipeError:
        # stdout closed by its reader (usdwrinkle info | head): what it read is what it
        # wanted; no traceback, and no failing flush at exit. The command's status stands
        # where it knew it before printing (check: 1 with findings), so that a pipeline
        # gating on it (set -o pipefail) is not told "clean"
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return int(getattr(args, "exit_code", 0))
    except UsdWrinkleError as exc:
        if args.debug:
            traceback.print_exc()
        from .flags import flagged  # the job named its option fields: say their flags

        exc.what = flagged(exc.what, parser.commands.get(args.command))
        print_stderr(f"usdwrinkle: error: {exc.one_line()}")
        return 2
    except KeyboardInterrupt:
        print_stderr(f"usdwrinkle: interrupted{_AFTER_INTERRUPT.get(args.command, '')}")
        return 130
    except Terminated:
        print_stderr(f"usdwrinkle: terminated{_AFTER_INTERRUPT.get(args.command, '')}")
        return 143
    except MemoryError:
        print_stderr("usdwrinkle: error: out of memory (lower --width/--height, --samples or "
                     "the number of meshes, or free memory)")
        return 2
    except Exception as exc:  # a bug in usdwrinkle: still one line, unless --debug
        stop = _stop_in_chain(exc)
        if stop is not None:  # a stop signal raised inside a library's Python callback
            said = "interrupted" if isinstance(stop, KeyboardInterrupt) else "terminated"
            print_stderr(f"usdwrinkle: {said}{_AFTER_INTERRUPT.get(args.command, '')}")
            return 130 if said == "interrupted" else 143
        if args.debug:
            traceback.print_exc()
        print_stderr(f"usdwrinkle: internal error: {type(exc).__name__}: {exc} (rerun with "
                     "--debug for a traceback, and please report it)")
        return 3


def _stop_in_chain(exc: BaseException) -> BaseException | None:
    """A KeyboardInterrupt or Terminated that ``exc`` wraps: Boost.Python (USD) turns one
    raised inside a callback into 'SystemError: ... returned a result with an exception
    set', chained as its cause."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        if isinstance(exc, (KeyboardInterrupt, Terminated)):
            return exc
        exc = exc.__cause__ or exc.__context__
    return None


def entry_point() -> None:
    code = main()
    from ..app.environment import release_context

    release_context()  # the one GL context of the process, released cleanly
    quick_exit(code)


def quick_exit(code: int) -> None:
    """End the process with ``code`` once the command is done, without the interpreter's
    finalization: tearing down USD's, numpy's and our modules was 0.18 s of garbage
    collection at the end of every run (perf, a 24-frame CesiumMan render), 6% of the
    whole process. The atexit handlers still run (logging's flush, weakref finalizers,
    coverage) and both streams are flushed. Where a thread that is not a daemon still
    runs, the ordinary exit joins it as Python does."""
    import atexit

    others = [thread for thread in threading.enumerate()
              if thread is not threading.main_thread() and not thread.daemon and
              thread.is_alive()]
    if others:
        sys.exit(code)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError, AttributeError):  # a closed or missing stream
            pass
    os._exit(code)


if __name__ == "__main__":
    entry_point()
