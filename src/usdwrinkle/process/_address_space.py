"""Address-space limits (``ulimit -v``, RLIMIT_AS), looked at before USD, numpy or Mesa
is loaded. This module imports nothing but the standard library.

These libraries reserve far more address space than they use: a render of the shirt
sample reserves about 2.0 GB for 0.3 GB resident. Most of it is per-thread: USD's path
pools (about 380 MB a worker thread), glibc's malloc arenas (64 MB a thread) and
OpenBLAS's buffers. Under a limit, their reservations fail, and the libraries do not
check: USD segfaults while it builds its schema registry, OpenBLAS exits with 1, Mesa
returns incomplete framebuffers. So, under a finite limit:

- those pools default to one thread (or two arenas), unless the user set them: a render
  then reserves about 1.5 GB (1.66 GB for a 960-pixel CesiumMan frame). USD's is set
  with Work.SetConcurrencyLimit (lean_usd), since PXR_WORK_THREAD_LIMIT in the
  environment makes USD print a banner of '#' lines on stderr;
- below MIN_ADDRESS_SPACE, usdwrinkle refuses to start, with one line that says so.
"""
from __future__ import annotations

import os

#: the smallest RLIMIT_AS usdwrinkle starts under: the lean settings' largest measured
#: peak (1.66 GB, CesiumMan at 960 pixels), with room for larger frames and meshes
MIN_ADDRESS_SPACE = 2 << 30
#: thread pools that reserve address space per thread, and their lean settings
LEAN_SETTINGS = {"OPENBLAS_NUM_THREADS": "1", "MALLOC_ARENA_MAX": "2"}


def address_space_limit() -> int | None:
    """The soft RLIMIT_AS in bytes, or None when there is none (or no such limit here)."""
    try:
        import resource
    except ImportError:  # not POSIX
        return None
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    return None if soft == resource.RLIM_INFINITY else int(soft)


def prepare() -> str | None:
    """Under a finite address-space limit, set the lean settings (those the user has not
    set); return the one-line problem when the limit is too small to start at all."""
    limit = address_space_limit()
    if limit is None:
        return None
    for name, value in LEAN_SETTINGS.items():
        os.environ.setdefault(name, value)
    if limit < MIN_ADDRESS_SPACE:
        return (f"the address-space limit (ulimit -v) is {limit >> 20:,} MiB, but "
                f"usdwrinkle needs at least {MIN_ADDRESS_SPACE >> 20:,} MiB: USD, Mesa and "
                "numpy reserve much more address space than they use (a render of the shirt "
                "sample reserves about 1.5 GB for 0.3 GB resident); raise the limit, or "
                "limit resident memory instead (ulimit -m, cgroups)")
    return None


def lean_usd() -> None:
    """Under a finite address-space limit, one USD worker thread (unless the user set
    PXR_WORK_THREAD_LIMIT): call before USD builds its schema registry, whose parallel
    parse reserves a path pool per worker thread."""
    if address_space_limit() is not None and "PXR_WORK_THREAD_LIMIT" not in os.environ:
        from pxr import Work

        Work.SetConcurrencyLimit(1)
