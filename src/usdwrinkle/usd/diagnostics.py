"""USD's own diagnostics as usdwrinkle's one-line messages.

USD prints its warnings (``Warning: in _ReportErrors at line ... -- text``) straight to
the process's stderr from C++, and raises its errors as multi-line ``Tf.ErrorException``
text. Around the calls that read user files, :func:`usd_diagnostics` captures file
descriptor 2, and :func:`usd_error_text` keeps the line that says what is wrong (with the
file:line of a syntax error).
"""
from __future__ import annotations

import contextlib
import logging
import os
import re
import sys
import tempfile

from ..process.errors import fold

_DIAGNOSTIC = re.compile(r"^(?:Warning|Error|Runtime Error|Coding Error|Status):?"
                         r"(?: in [^-]*?)?(?: at line \d+ of \S+)? -- (.*)$")
_FILE_LINE = re.compile(r"([^\s'@]+:\d+:\d+: .*)")
_CONTEXT = re.compile(r"\s*\((?:instantiating stage|in state)[^()]*<0x[0-9a-f]+>\)")
_USD_CODE = re.compile(r"^\s*Error in '[^']*' at line \d+ in file \S+ : '?(.*?)'?$")


def one_line(text: str) -> str:
    """Whitespace folded, and USD's '(instantiating stage on stage @x@ <0x...>)' dropped."""
    return _CONTEXT.sub("", fold(text))


def usd_error_text(exc: BaseException | str) -> str:
    """The informative part of a Tf.ErrorException (or captured text): a syntax error's
    'file:line:column: what', else the last message USD gave, on one line."""
    try:
        text = str(exc)
    except UnicodeDecodeError:  # USD's message quotes bytes of a file that is not UTF-8
        return "it is not UTF-8 text (a .usda file must be)"
    match = _FILE_LINE.search(text)
    if match:
        return one_line(match.group(1).rstrip("'"))
    messages = []
    for line in text.splitlines():
        line = line.strip()
        if not line:
            continue
        code = _USD_CODE.match(line) or _DIAGNOSTIC.match(line)
        messages.append(code.group(1) if code else line)
    return one_line(messages[-1]) if messages else "unreadable"


def diagnostic_messages(text: str) -> list[str]:
    """USD's diagnostics in captured stderr text, as one message each."""
    out = []
    for line in text.splitlines():
        match = _DIAGNOSTIC.match(line.strip())
        if match:
            out.append(one_line(match.group(1)))
        elif line.strip() and out:
            out[-1] += " " + one_line(line)
        elif line.strip():
            out.append(one_line(line))
    return list(dict.fromkeys(out))


@contextlib.contextmanager
def usd_diagnostics(forward: bool = False):
    """Capture what C++ prints on stderr inside the block; with ``forward`` each message
    is then logged as a warning of the caller's (one line each, usdwrinkle/process/log.py),
    otherwise dropped.

    Yields a list that holds the messages once the block has ended.
    """
    messages: list[str] = []
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to capture
        yield messages
        return
    with tempfile.TemporaryFile(mode="w+b") as capture:
        # A stop signal's handler raises at any call in here (Ctrl-C during Usd.Stage.Open
        # runs as soon as the C++ returns): wherever it lands, stderr is given back before
        # the exception leaves, or the CLI's "usdwrinkle: interrupted" went into this
        # temporary file and the run ended 130 saying nothing (CI, once in ~150 Ctrl-Cs)
        try:
            if sys.stderr is not None:
                sys.stderr.flush()
            os.dup2(capture.fileno(), 2)
            yield messages
        finally:
            try:
                if sys.stderr is not None:
                    sys.stderr.flush()
            finally:
                try:
                    os.dup2(saved, 2)
                finally:
                    os.close(saved)
            capture.seek(0)
            text = capture.read().decode("utf-8", "replace")
            messages.extend(diagnostic_messages(text))
            if forward:
                for message in messages:
                    logging.getLogger("usdwrinkle.usd").warning("%s", message)
