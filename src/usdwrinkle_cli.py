"""The ``usdwrinkle`` console script's first module, outside the package on purpose.

Importing ``usdwrinkle`` loads USD (about half a second). A Ctrl-C, SIGTERM or SIGHUP in
that time used to print a Python traceback (or, inside a USD callback, be swallowed so that
the run went on). This module takes those signals before anything heavy loads: until
usdwrinkle's own handlers replace these (cli/main.py), a stop signal ends the process at
once with the shell's code and one line. Nothing has been written yet, so there is nothing
to clean up.
"""
import os
import signal

_CODES = {"SIGINT": (130, "interrupted"), "SIGTERM": (143, "terminated"),
          "SIGHUP": (143, "terminated")}


def _stop(signum, frame):  # pragma: no cover - runs in a subprocess (tests/test_cli.py)
    name = signal.Signals(signum).name
    code, said = _CODES[name]
    try:
        os.write(2, f"usdwrinkle: {said}\n".encode())
    except OSError:
        pass
    os._exit(code)


def _standard_descriptors() -> None:
    """Open /dev/null on a closed stdin, stdout or stderr (``2>&-``): otherwise the first
    file the run opens would get that number, and what is written to "stderr" (USD's
    diagnostics, from C++) would land in it."""
    import sys

    for fd in (0, 1, 2):
        try:
            os.fstat(fd)
        except OSError:
            os.open(os.devnull, os.O_RDWR)  # the lowest free descriptor: this one
    # Python made sys.stderr (or stdout) None for a descriptor closed at start-up: give it
    # the stream on the /dev/null above, so that a flush of it never fails mid-run (a
    # refusal exited 3, an internal error, with stderr closed)
    for name, fd in (("stdin", 0), ("stdout", 1), ("stderr", 2)):
        if getattr(sys, name) is None:
            setattr(sys, name, open(fd, "r" if fd == 0 else "w", closefd=False))


def entry_point() -> None:
    _standard_descriptors()
    for name in _CODES:  # as cli/main.py does for the whole run
        if hasattr(signal, name):
            signal.signal(getattr(signal, name), _stop)
    from usdwrinkle.cli.main import entry_point as run

    run()  # exits with the command's code
