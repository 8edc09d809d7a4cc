"""Atomic file writes: a temporary file in the same folder, then a rename."""
from __future__ import annotations

import contextlib
import glob
import os
import tempfile


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _temporary_affixes(path: str) -> tuple[str, str, str]:
    """(folder, prefix, suffix) of the temporary files that stand in for ``path``."""
    folder = os.path.dirname(os.path.abspath(path)) or "."
    base, ext = os.path.splitext(os.path.basename(path))
    return folder, f".{base}.", f".tmp{ext}"


def remove_temporaries(path: str) -> None:
    """Remove temporary files of ``path`` that a killed process left behind (one that
    dies in the middle of atomic_path never reaches its cleanup)."""
    folder, prefix, suffix = _temporary_affixes(path)
    pattern = os.path.join(glob.escape(folder), f"{glob.escape(prefix)}*{glob.escape(suffix)}")
    for tmp in glob.glob(pattern):
        with contextlib.suppress(OSError):
            os.unlink(tmp)


@contextlib.contextmanager
def atomic_path(path: str):
    """Yield a temporary path beside ``path`` (same extension); rename on success.

    On any error, or Ctrl-C, the temporary file is removed and ``path`` is
    left as it was: never a half-written file.
    """
    folder, prefix, suffix = _temporary_affixes(path)
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=prefix, suffix=suffix, dir=folder)
    os.close(fd)
    try:
        yield tmp
        # mkstemp makes 0600 files; give the output the permissions a plain open() would
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
