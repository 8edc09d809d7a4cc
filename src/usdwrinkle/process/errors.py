"""Errors that usdwrinkle reports to its users.

Every user-facing problem is a :class:`UsdWrinkleError`. The CLI prints it as
one line, ``usdwrinkle: error: <what> (<prim path>[.<attribute>][ at frame F])``,
and exits with code 2. Anything else that escapes is a bug in usdwrinkle.
"""
from __future__ import annotations


def fold(text) -> str:
    """``text`` as one line: every run of whitespace (newlines too) becomes one space."""
    return " ".join(str(text).split())


class UsdWrinkleError(Exception):
    """A problem with the user's input or environment, reported as one line."""

    def __init__(self, what: str, prim_path: str | None = None,
                 attribute: str | None = None, frame: float | None = None):
        self.what = what
        self.prim_path = prim_path
        self.attribute = attribute
        self.frame = frame
        super().__init__(self.one_line())

    def one_line(self) -> str:
        where = ""
        if self.prim_path:
            where = str(self.prim_path)
            if self.attribute:
                where += "." + self.attribute
        if self.frame is not None:
            from .timecode import format_frame

            frame = format_frame(self.frame)
            where = f"{where} at frame {frame}" if where else f"at frame {frame}"
        what = fold(self.what)  # one line, whatever a library said
        return f"{what} ({where})" if where else what


class _SafeStderr:
    """sys.stderr for messages about a run (warnings, errors, progress): a write that
    fails (a closed or full stderr, ``2>/dev/full``) is dropped, and stderr becomes
    /dev/null for the rest of the process, so that a message that cannot be shown never
    fails the run it reports on, nor Python's final flush (exit 120)."""

    def write(self, text: str) -> int:
        import sys

        try:
            written = sys.stderr.write(text)
            sys.stderr.flush()
            return written
        except (OSError, ValueError, AttributeError):  # AttributeError: started with fd 2
            self._silence()                           # closed, Python's sys.stderr is None
            return len(text)

    def flush(self) -> None:
        import sys

        try:
            sys.stderr.flush()
        except (OSError, ValueError, AttributeError):
            self._silence()

    def isatty(self) -> bool:
        import sys

        try:
            return sys.stderr.isatty()
        except (OSError, ValueError, AttributeError):
            return False

    @staticmethod
    def _silence() -> None:
        import os
        import sys

        sys.stderr = open(os.devnull, "w", encoding="utf-8")  # noqa: SIM115 (process-wide)


#: where usdwrinkle writes everything it says on stderr
STDERR = _SafeStderr()


def print_stderr(text: str) -> None:
    """One line on stderr (STDERR: never fails)."""
    STDERR.write(text + "\n")


def print_warning(message: str) -> None:
    """The one way a warning reaches the user: ``usdwrinkle: warning: <message>`` on stderr
    (cli/common.Reporter adds de-duplication and --quiet on top)."""
    print_stderr(f"usdwrinkle: warning: {fold(message)}")


class GLContextError(UsdWrinkleError):
    """No usable OpenGL 4.3 context (compute shaders) could be created."""


class SchemaRegistrationError(UsdWrinkleError):
    """The WrinkleAPI plugin was registered after USD built its schema registry."""


class ShaderError(UsdWrinkleError):
    """A shader failed to load, preprocess or compile: a broken installation or a GL
    driver that rejects it, reported as one line (exit 2), not as a crash.

    Carries the file and line, as moderngl-window's loader does, so that a
    message from the GLSL compiler points at the file a developer edits.
    """

    def __init__(self, file: str, line: int, message: str):
        self.file = file
        self.line = line
        self.message = message
        super().__init__(f"shader {file}:{line}: {message}; the installation is incomplete "
                         "or the GL driver rejects the shader (usdwrinkle info names the "
                         "driver; reinstall usdwrinkle, or report it with that line)")
