"""Warnings: every module logs them, one sink shows them.

A module warns with ``logging.getLogger(__name__).warning(message)`` (the ``usdwrinkle``
logger and its children); nothing threads a ``warn`` callback through the layers any
more. Each warning then reaches:

- the innermost ``warnings_to(sink)`` block (any thread): the CLI's reporter prints each
  message once, a farm worker sends them to its client, ``collect()`` gathers them in a
  list, ``silenced()`` drops them (usdview's plugin and ``check``, whose status line and
  findings say what matters);
- outside every block, stderr, as usdwrinkle's one line
  ``usdwrinkle: warning: <message>`` (errors.print_warning);
- and in both cases the host's own logging, if it configured any (the records propagate
  as usual: a farm's log collector sees them). ``logging.getLogger("usdwrinkle")
  .setLevel(logging.ERROR)`` silences them everywhere; ``use_default_handler(False)``
  leaves them to the host's logging alone.

``import usdwrinkle`` installs the handler, so a warning of the Python API reads as the
CLI's, never bare (Python's last-resort handler printed it without the prefix).

Messages are made one line (whitespace runs become one space) before a sink sees them.
"""
from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Callable, Iterator

from .errors import fold, print_warning

LOGGER = logging.getLogger("usdwrinkle")

_SINKS: list[Callable[[str], None]] = []
_LOCK = threading.Lock()


class _SinkHandler(logging.Handler):
    """Hands each warning of the ``usdwrinkle`` loggers to the innermost sink."""

    def __init__(self):
        super().__init__(logging.WARNING)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            message = fold(record.getMessage())
        except (TypeError, ValueError):  # a malformed %-format: logging's own report
            self.handleError(record)
            return
        with _LOCK:
            sink = _SINKS[-1] if _SINKS else print_warning
        sink(message)


# once per process, also if this module is reloaded; a handler on the package logger
# sees its children's records, and keeps Python's lastResort from printing them again.
# ``import usdwrinkle`` imports this module, so every door (the API included) has it.
HANDLER: logging.Handler = next((h for h in LOGGER.handlers
                                 if type(h).__name__ == "_SinkHandler"), None) \
    or _SinkHandler()
if HANDLER not in LOGGER.handlers:
    LOGGER.addHandler(HANDLER)


def use_default_handler(enabled: bool = True) -> None:
    """Turn usdwrinkle's own warning handler (``usdwrinkle: warning: ...`` on stderr, or
    the innermost ``warnings_to`` sink) on or off. Off, the records only propagate to the
    host's logging configuration (a pipeline that formats its own log lines)."""
    if enabled and HANDLER not in LOGGER.handlers:
        LOGGER.addHandler(HANDLER)
    elif not enabled and HANDLER in LOGGER.handlers:
        LOGGER.removeHandler(HANDLER)


def warn(message: str) -> None:
    """A warning of usdwrinkle itself (not of a module that has its own logger)."""
    LOGGER.warning("%s", message)


@contextlib.contextmanager
def warnings_to(sink: Callable[[str], None]) -> Iterator[None]:
    """Inside the block, usdwrinkle's warnings go to ``sink`` (one line each) instead of
    stderr. Blocks nest: the innermost sink gets them."""
    with _LOCK:
        _SINKS.append(sink)
    try:
        yield
    finally:
        with _LOCK:
            # remove this block's own entry (by identity: a sink may be pushed twice)
            for index in range(len(_SINKS) - 1, -1, -1):
                if _SINKS[index] is sink:
                    del _SINKS[index]
                    break


@contextlib.contextmanager
def collect() -> Iterator[list[str]]:
    """The warnings of the block, in a list (also the block's result afterwards)."""
    messages: list[str] = []
    with warnings_to(messages.append):
        yield messages


def silenced() -> contextlib.AbstractContextManager[None]:
    """A block whose warnings are dropped (the host's logging still gets them)."""
    return warnings_to(_drop)


def _drop(message: str) -> None:
    return None
