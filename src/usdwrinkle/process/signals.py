"""The stop signals (Ctrl-C, a scheduler's SIGTERM, a closed terminal's SIGHUP), held back
around work that must not be interrupted by their delivery. No other usdwrinkle import."""
from __future__ import annotations

import contextlib
import signal
import threading

#: the signals that stop a run
STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM, signal.SIGHUP}

#: per thread, how many held sections it is inside
_HELD = threading.local()


def held_here() -> bool:
    """Whether the calling thread is inside signals_held. A signal handler (which Python
    runs on the main thread) asks it: the kernel gives a process-wide signal to any thread
    that does not block it (OpenBLAS's, a timer's), and Python then runs the handler on
    the main thread at once, held section or not (usdwrinkle's CLI puts the stop off)."""
    return getattr(_HELD, "depth", 0) > 0


@contextlib.contextmanager
def signals_held():
    """Hold back stop signals for a critical section of the calling thread; they arrive
    when it ends. Threads started inside the section keep them blocked for good (the GL
    driver's worker threads: a stop signal delivered to one of them, or to LLVM compiling
    a shader, crashed llvmpipe with SIGSEGV about once in 150 Ctrl-Cs). A signal that
    another thread takes is not held by the mask: held_here() says so to the handler."""
    _HELD.depth = getattr(_HELD, "depth", 0) + 1
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    except (AttributeError, OSError, ValueError):  # no POSIX signal masks here
        old = None
    try:
        yield
    finally:
        # out of the section before the held signals arrive: their handler may raise
        _HELD.depth -= 1
        if old is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, old)
