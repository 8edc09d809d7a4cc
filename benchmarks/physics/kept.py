"""The referee's simulations kept in the repository (benchmarks/physics/simulations/), so
that a fresh checkout need not simulate them again: the converged referee's ten shots are
about 13 hours of solver on one core here, and ``.physics-cache`` is not committed.

A kept simulation is its cache file (simulate.simulate_newton's, named by the shot's
arrays and the solver's options) made small: the first frame as float32, every later
frame as int16 steps of ``scale`` metres from the frame before as it is kept (so that
the rounding does not add up: every point within half a step of the cache's), the
step the largest move from one frame to the next over 32,767 (about a micrometre on the
sleeves, against folds millimetres to centimetres tall), compressed. simulate_newton
reads a kept simulation into the cache when the cache lacks it, before it would
simulate; ``python -m benchmarks.physics.fill --keep`` keeps what the cache holds."""
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
    # the step: the largest move between frames, with a margin for the rounding carried
    moves = np.abs(np.diff(points, axis=0)).max() if len(points) > 1 else 0.0
    scale = float(moves) / (STEPS - 2) if moves > 0 else 1.0
    steps = np.empty((len(points) - 1, *points.shape[1:]), np.int16)
    shown = first.astype(np.float64)  # the frame before, as it will be read back
    for frame in range(1, len(points)):
        steps[frame - 1] = np.round((points[frame] - shown) / scale)
        shown = shown + steps[frame - 1] * scale
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
    moved = np.cumsum(data["steps"].astype(np.float64), axis=0) * float(data["scale"])
    points = np.concatenate([first[None], (first.astype(np.float64) + moved)
                             .astype(np.float32)])
    cached.parent.mkdir(parents=True, exist_ok=True)
    tmp = cached.with_name(cached.name + ".restoring.npz")
    np.savez(tmp, points=points, seconds=data["seconds"], stretch_p99=data["stretch_p99"])
    tmp.replace(cached)
    return True
