"""Whether a job fits in memory, checked before anything is allocated: one rule and one
message for frames (render/buffers.py), maps (maps/bake.py) and displaced geometry
(geometry/bake.py)."""
from __future__ import annotations

from .errors import UsdWrinkleError


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation (Linux MemAvailable), or None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as meminfo:
            for line in meminfo:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def require_memory(needed: int, what: str, advice: str) -> None:
    """Refuse a job that needs more than the available memory: "``what`` needs about N
    GiB, but M GiB of memory are available; ``advice``". Where the available memory is
    unknown, the job goes on."""
    available = available_memory()
    if available is not None and needed > available:
        raise UsdWrinkleError(f"{what} about {needed / 2**30:.1f} GiB, but "
                              f"{available / 2**30:.1f} GiB of memory are available; {advice}")
