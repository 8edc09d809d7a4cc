"""The stop signals (Ctrl-C, a scheduler's SIGTERM, a closed terminal's SIGHUP), held back
around work that must not be interrupted by their delivery. No other usdwrinkle import."""
from __future__ import annotations

import contextlib
import signal

#: the signals that stop a run
STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}


@contextlib.contextmanager
def signals_held():
    """Hold back stop signals for a critical section of the calling thread; they arrive
    when it ends. Threads started inside the section keep them blocked for good (the GL
    driver's worker threads: a stop signal delivered to one of them, or to LLVM compiling
    a shader, crashed llvmpipe with SIGSEGV about once in 150 Ctrl-Cs)."""
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    except (AttributeError, OSError, ValueError):  # no POSIX signal masks here
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
