"""Atomic file writes: a temporary file in the same folder, then a rename."""
from __future__ import annotations

import contextlib
import glob
import os
import re
import tempfile

from ..process.errors import UsdWrinkleError

# held back while a finished file is renamed into place or a temporary file is removed
from ..process.signals import STOP_SIGNALS, signals_held  # noqa: E402,F401


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _temporary_affixes(path: str) -> tuple[str, str, str]:
    """(folder, prefix, suffix) of the temporary files that stand in for ``path``."""
    folder = os.path.dirname(os.path.abspath(path)) or "."
    base, ext = os.path.splitext(os.path.basename(path))
    return folder, f".{base}.", f".tmp{ext}"


#: a temporary file's name: ``.<base>.<pid>.<random>.tmp<ext>`` (atomic_path); the pid
#: tells a later run whether its writer is still alive
_TEMPORARY = re.compile(r"^\.(?P<base>.+)\.(?P<pid>\d+)\.[^.]+\.tmp(?P<ext>\.[^.]*)?$")


def sweep_dead_temporaries(paths: list[str]) -> int:
    """Remove the temporary files of ``paths`` whose writing process no longer runs (a
    SIGKILLed or crashed run of the same frames); one listing per folder. Returns how many
    were removed. Those of live processes (another run writing now) stay."""
    wanted: dict[str, set[str]] = {}
    for path in paths:
        folder = os.path.dirname(os.path.abspath(path)) or "."
        wanted.setdefault(folder, set()).add(os.path.basename(path))
    removed = 0
    for folder, names in wanted.items():
        try:
            entries = os.listdir(folder)
        except OSError:
            continue
        for entry in entries:
            match = _TEMPORARY.match(entry)
            if not match or match["base"] + (match["ext"] or "") not in names:
                continue
            if _alive(int(match["pid"])):
                continue
            with contextlib.suppress(OSError):
                os.unlink(os.path.join(folder, entry))
                removed += 1
    return removed


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True  # alive, but another user's
    return True


def remove_temporaries(path: str) -> None:
    """Remove temporary files of ``path`` that a killed process left behind (one that
    dies in the middle of atomic_path never reaches its cleanup)."""
    folder, prefix, suffix = _temporary_affixes(path)
    pattern = os.path.join(glob.escape(folder), f"{glob.escape(prefix)}*{glob.escape(suffix)}")
    for tmp in glob.glob(pattern):
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def sweep_dead(folder: str, prefix: str, remove) -> None:
    """Call ``remove(path)`` for every entry of ``folder`` named ``<prefix><pid>.*`` whose
    process no longer runs (a SIGKILLed run never reaches its cleanup); the entries of
    processes that run, also other users', stay."""
    try:
        names = os.listdir(folder)
    except OSError:
        return
    for name in names:
        if not name.startswith(prefix):
            continue
        pid = name[len(prefix):].split(".", 1)[0]
        if not pid.isdigit():
            continue
        try:
            os.kill(int(pid), 0)
        except ProcessLookupError:
            with contextlib.suppress(OSError):
                remove(os.path.join(folder, name))
        except OSError:
            pass  # alive, but another user's


def write_error(path: str, exc: OSError) -> UsdWrinkleError:
    """An OSError of an output write as the one-line error (full disk, permissions, ...)."""
    reason = exc.strerror or str(exc)
    if isinstance(exc, (FileExistsError, NotADirectoryError)):
        reason = "a part of its folder path is a file, not a folder"
    return UsdWrinkleError(f"cannot write '{path}': {reason}")


def check_writable(paths) -> None:
    """Refuse, before any work, outputs that cannot be written: a folder that cannot be
    made or written to, an output under a file, an output that is a folder."""
    folders = {}
    for path in paths:
        if os.path.isdir(path):
            raise UsdWrinkleError(f"cannot write '{path}': it is a folder")
        folders.setdefault(_temporary_affixes(path)[0], path)
    for folder, path in folders.items():
        try:
            os.makedirs(folder, exist_ok=True)
            probe_folder(folder)
        except OSError as exc:
            raise write_error(path, exc) from None


def probe_folder(folder: str) -> None:
    """Make and remove a file in ``folder`` (permissions alone do not say whether one can
    be made: root, a read-only file system); raises the OSError when it cannot. A stop
    signal waits until the probe is gone: a Ctrl-C between the two left it behind."""
    with signals_held():
        fd, probe = tempfile.mkstemp(prefix=".usdwrinkle-probe.", dir=folder)
        os.close(fd)
        os.unlink(probe)


@contextlib.contextmanager
def atomic_path(path: str, verify=None):
    """Yield a temporary path beside ``path`` (same extension); rename on success.

    ``verify(tmp)``, if given, runs before the rename and raises when the file is not
    complete. On any error, or Ctrl-C, the temporary file is removed and ``path`` is
    left as it was: never a half-written file. OSErrors (a full disk, a read-only
    folder, an output that is a folder) become the one-line UsdWrinkleError.
    """
    folder, prefix, suffix = _temporary_affixes(path)
    tmp = None
    try:
        try:
            os.makedirs(folder, exist_ok=True)
            if os.path.isdir(path):
                raise IsADirectoryError(21, "it is a folder")
            # held, so that a Ctrl-C lands after ``tmp`` names the file the cleanup removes
            with signals_held():
                fd, tmp = tempfile.mkstemp(prefix=f"{prefix}{os.getpid()}.", suffix=suffix,
                                           dir=folder)
                os.close(fd)
            yield tmp
            if verify is not None:
                verify(tmp)
            # mkstemp makes 0600 files; give the output the permissions a plain open() would
            os.chmod(tmp, 0o666 & ~_umask())
            with signals_held():
                os.replace(tmp, path)
        except OSError as exc:
            raise write_error(path, exc) from None
    except BaseException:
        if tmp is not None:
            with signals_held(), contextlib.suppress(OSError):
                os.unlink(tmp)
        raise
