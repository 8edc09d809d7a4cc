"""The referee's simulations kept in the repository (benchmarks/physics/simulations/), so
that a fresh checkout need not simulate them again: the converged referee's ten shots are
about 13 hours of solver on one core here, and ``.physics-cache`` is not committed.

A kept simulation is its cache file (simulate.simulate_newton's, named by the shot's
arrays and the solver's options) made small: the first frame as float32, every later
frame as int16 steps from it of ``scale`` metres (the largest displacement over 32,767:
15 micrometres on a curtain pushed 48 cm, against folds millimetres to centimetres tall),
compressed. simulate_newton reads a kept simulation into the cache when the cache lacks
it, before it would simulate; ``python -m benchmarks.physics.fill --keep`` keeps what the
cache holds. A kept simulation's points differ from the cache's by at most half a step."""
from __future__ import annotations

from pathlib import Path

import numpy as np

#: where the kept simulations are (committed)
KEPT = Path(__file__).resolve().parent / "simulations"
#: the int16 range a displacement is quantised to
STEPS = 32767


def kept_path(cached: Path) -> Path:
    """Where the cache file ``cached`` is kept (the same name)."""
    return KEPT / cached.name


def keep(cached: Path) -> Path:
    """Keep the cache file ``cached`` (points, seconds, stretch_p99) in KEPT; returns
    its path there."""
    data = np.load(cached)
    points = np.asarray(data["points"], np.float64)
    first = points[0].astype(np.float32)
    offset = points[1:] - first.astype(np.float64)
    reach = float(np.abs(offset).max()) if offset.size else 0.0
    scale = reach / STEPS if reach > 0 else 1.0
    steps = np.round(offset / scale).astype(np.int16)
    KEPT.mkdir(parents=True, exist_ok=True)
    out = kept_path(cached)
    tmp = out.with_name(out.name + ".tmp.npz")
    np.savez_compressed(tmp, first=first, steps=steps, scale=np.float64(scale),
                        seconds=np.float64(data["seconds"]),
                        stretch_p99=np.float64(data["stretch_p99"]))
    tmp.replace(out)
    return out


def restore(cached: Path) -> bool:
    """Write the cache file ``cached`` from its kept simulation, if there is one; whether
    there was."""
    source = kept_path(cached)
    if not source.exists():
        return False
    data = np.load(source)
    first = np.asarray(data["first"], np.float32)
    later = first.astype(np.float64) + data["steps"].astype(np.float64) * float(data["scale"])
    points = np.concatenate([first[None], later.astype(np.float32)])
    cached.parent.mkdir(parents=True, exist_ok=True)
    tmp = cached.with_name(cached.name + ".restoring.npz")
    np.savez(tmp, points=points, seconds=data["seconds"], stretch_p99=data["stretch_p99"])
    tmp.replace(cached)
    return True
