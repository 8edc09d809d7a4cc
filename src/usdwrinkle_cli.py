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


def entry_point() -> None:
    for name in _CODES:
        if hasattr(signal, name) and signal.getsignal(getattr(signal, name)) is not \
                signal.SIG_IGN:  # a background job's ignored SIGINT stays ignored
            signal.signal(getattr(signal, name), _stop)
    from usdwrinkle.cli.main import entry_point as run

    run()  # exits with the command's code
