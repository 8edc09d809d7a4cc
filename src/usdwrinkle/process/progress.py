"""Progress of long runs: a tqdm bar on a terminal, plain log lines elsewhere.

On a terminal, tqdm redraws one line with carriage returns and cursor escapes. In a farm's
log (stderr redirected to a file or a pipe) those control characters are noise. There,
progress goes through the standard library's ``logging`` (logger ``usdwrinkle.progress``,
one handler on usdwrinkle's safe stderr; warnings have their own way, process/log.py) as whole
lines: ``usdwrinkle: render: 12/48 frame(s) (25%)``. It writes a line at every tenth of
the run, at its end, and at least once a minute in between. ``USDWRINKLE_PROGRESS``
overrides the choice: ``bar``, ``log`` or ``none``.
"""
from __future__ import annotations

import logging
import os
import time

from .errors import STDERR

LOGGER = logging.getLogger("usdwrinkle.progress")


def _handler() -> None:
    """The logger's one handler: whole lines on usdwrinkle's safe stderr."""
    if not any(getattr(h, "usdwrinkle", False) for h in LOGGER.handlers):
        handler = logging.StreamHandler(STDERR)
        handler.setFormatter(logging.Formatter("usdwrinkle: %(message)s"))
        handler.usdwrinkle = True
        LOGGER.addHandler(handler)
        LOGGER.setLevel(logging.INFO)
        LOGGER.propagate = False  # the package logger's handler is the warnings' sink


def mode() -> str:
    """"bar" (a terminal), "log" (anything else) or "none" (USDWRINKLE_PROGRESS)."""
    chosen = os.environ.get("USDWRINKLE_PROGRESS", "").strip().lower()
    if chosen in ("bar", "log", "none"):
        return chosen
    return "bar" if STDERR.isatty() else "log"


class LogProgress:
    """A counter that logs whole lines (the non-terminal form of a tqdm bar)."""

    def __init__(self, total: int, desc: str):
        _handler()
        self.total, self.desc, self.count = total, desc, 0
        self._next_tenth = 1
        self._last = time.monotonic()

    def update(self, n: int = 1) -> None:
        self.count += n
        tenth = self.count * 10 // max(self.total, 1)
        now = time.monotonic()
        if self.count >= self.total or tenth >= self._next_tenth or now - self._last >= 60:
            self._next_tenth = tenth + 1
            self._last = now
            percent = 100 * self.count // max(self.total, 1)
            LOGGER.info("%s: %d/%d frame(s) (%d%%)", self.desc, self.count, self.total,
                        percent)

    def close(self) -> None:
        pass


def counter(total: int, desc: str):
    """A progress counter (update(n), close()) over ``total`` frames."""
    chosen = mode()
    if chosen == "bar":
        from tqdm import tqdm

        return tqdm(total=total, desc=desc, unit="frame", dynamic_ncols=True, file=STDERR)
    if chosen == "log":
        return LogProgress(total, desc)
    return _Silent()


def wrap(items, desc: str):
    """``items`` with progress shown as they are consumed."""
    items = list(items)
    chosen = mode()
    if chosen == "bar":
        from tqdm import tqdm

        return tqdm(items, desc=desc, unit="frame", file=STDERR, dynamic_ncols=True)
    if chosen == "none":
        return items
    return _logged(items, LogProgress(len(items), desc))


def _logged(items, log: LogProgress):
    for item in items:
        yield item
        log.update()


class _Silent:
    def update(self, n: int = 1) -> None:
        pass

    def close(self) -> None:
        pass
