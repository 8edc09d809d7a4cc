"""Simulate a shot in Blender's cloth solver (sim_client.py in the bpy Python), cached."""
from __future__ import annotations

import contextlib
import hashlib
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from . import kept
from .shots import Shot

HERE = Path(__file__).resolve().parent


def simulate(shot: Shot, cache: Path, preset: str = "Cotton") -> tuple[np.ndarray, float]:
    """The fine points of every frame (frames, n, 3) and the solver's seconds; cached in
    ``cache`` by shot and preset (delete the file to simulate again)."""
    spec_arrays = _spec(shot, preset)
    digest = hashlib.sha1(b"".join(np.ascontiguousarray(v).tobytes()
                                   for v in spec_arrays.values())).hexdigest()[:10]
    out = cache / f"{shot.name}-{preset}-{digest}.npz"
    if not out.exists():
        from realclients import bpy_python

        cache.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix="usdwrinkle-cloth-") as scratch:
            spec = os.path.join(scratch, "shot.npz")
            np.savez(spec, **spec_arrays)
            done = subprocess.run([bpy_python(), str(HERE / "sim_client.py"), spec,
                                   str(out) + ".tmp.npz"], capture_output=True, text=True,
                                  timeout=3600, env={**os.environ, "TMPDIR": scratch,
                                                     "PYTHONNOUSERSITE": "1"})
            if done.returncode != 0 or not os.path.exists(str(out) + ".tmp.npz"):
                raise RuntimeError(f"Blender's cloth failed on {shot.name}: "
                                   f"{done.stderr.strip()[-800:]}")
            os.replace(str(out) + ".tmp.npz", out)
    data = np.load(out)
    return data["points"], float(data["seconds"])


def _spec(shot: Shot, preset: str) -> dict:
    spec = dict(rest=shot.rest, quads=shot.quads(), pinned=shot.pinned,
                key_frames=np.array([f for f, _ in shot.keys]),
                key_points=np.stack([p for _, p in shot.keys]), frames=np.array(shot.frames),
                gravity=np.array(shot.gravity), preset=np.array(preset))
    spec.update({key: np.array(value) for key, value in shot.solver.items()})
    if shot.collider is not None:
        rest, quads, keys = shot.collider
        spec.update(collider_rest=rest, collider_quads=quads, collider_keys=np.stack(keys))
    return spec


def newton_python() -> str:
    """The Python with ``newton`` (USDWRINKLE_NEWTON_PYTHON, or the checkout's
    .venv-newton: ``python3 -m venv .venv-newton && .venv-newton/bin/pip install newton``)."""
    path = os.environ.get("USDWRINKLE_NEWTON_PYTHON")
    if path:
        return path
    local = HERE.parents[1] / ".venv-newton" / "bin" / "python"
    if local.exists():
        return str(local)
    raise RuntimeError("the Newton referee needs a Python with Newton: "
                       "python3 -m venv .venv-newton && .venv-newton/bin/pip install newton "
                       "(or set USDWRINKLE_NEWTON_PYTHON)")


def newton_path(sweep_shot, cache: Path, solver: dict | None = None) -> tuple[Path, dict]:
    from .sweep import spec

    arrays = spec(sweep_shot, solver)
    digest = hashlib.sha1(b"".join(np.ascontiguousarray(v).tobytes()
                                   for v in arrays.values())).hexdigest()[:10]
    spacing = sweep_shot.shot.spacing
    return cache / f"newton-{sweep_shot.shot.name}-{1000 * spacing:.2f}mm-{digest}.npz", arrays


def cached_newton(sweep_shot, cache: Path, solver: dict | None = None) -> bool:
    """Whether the shot's simulation is in the cache already, or kept in the repository
    (kept.py), where simulate_newton reads it from."""
    path = newton_path(sweep_shot, cache, solver)[0]
    return path.exists() or kept.kept_path(path).exists()


@contextlib.contextmanager
def _simulating(out: Path):
    """Hold OUT.lock while this process simulates OUT: two processes that simulated the
    same shot would write one checkpoint and one result (fill.py runs several at once).
    A lock whose process is gone is taken over."""
    lock = Path(str(out) + ".lock")
    while True:
        try:
            with open(lock, "x") as handle:
                handle.write(str(os.getpid()))
            break
        except FileExistsError:
            try:
                holder = int(lock.read_text() or 0)
                os.kill(holder, 0)
            except (ValueError, ProcessLookupError, FileNotFoundError):
                lock.unlink(missing_ok=True)  # its process is gone
                continue
            except PermissionError:
                pass  # alive, another user's
            raise RuntimeError(f"{out.name} is being simulated by process {holder} "
                               f"(its lock: {lock})") from None
    try:
        yield
    finally:
        lock.unlink(missing_ok=True)


def _run_newton(sweep_shot, out: Path, arrays: dict, cache: Path, progress: bool) -> None:
    """newton_client.py on the shot's arrays, its result moved to ``out`` when done."""
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-newton-") as scratch:
        path = os.path.join(scratch, "shot.npz")
        np.savez(path, **arrays)
        env = {**os.environ, "PYTHONNOUSERSITE": "1",
               "WARP_CACHE_PATH": str(cache / "warp-kernels")}
        if progress:
            env["NEWTON_CLIENT_PROGRESS"] = "1"
        done = subprocess.run([newton_python(), str(HERE / "newton_client.py"), path,
                               str(out) + ".tmp.npz"], stdout=subprocess.PIPE,
                              stderr=None if progress else subprocess.PIPE, text=True,
                              timeout=4 * 3600, env=env)
        if done.returncode != 0 or not os.path.exists(str(out) + ".tmp.npz"):
            raise RuntimeError(f"Newton's cloth failed on {sweep_shot.shot.name}: "
                               f"{(done.stderr or '').strip()[-800:]}")
        os.replace(str(out) + ".tmp.npz", out)


def simulate_newton(sweep_shot, cache: Path, solver: dict | None = None,
                    progress: bool = False) -> tuple[np.ndarray, float, float]:
    """Newton's VBD on a sweep shot (sweep.py): the fine points of every frame, the solver's
    seconds and the 99th percentile of the last frame's edge strain; cached in ``cache`` by
    the shot's arrays."""
    out, arrays = newton_path(sweep_shot, cache, solver)
    if not out.exists() and kept.restore(out):
        print(f"physics: {sweep_shot.shot.name} at {100 * sweep_shot.shot.spacing:.3g} cm "
              f"read from {kept.KEPT}", file=sys.stderr, flush=True)
    if not out.exists():
        # a fresh checkout has no cache: say what is about to take hours, before it does
        print(f"physics: {sweep_shot.shot.name} at {100 * sweep_shot.shot.spacing:.3g} cm is "
              f"not in {cache}: simulating it with Newton (a 1 cm curtain took 1.9-3.9 hours "
              "on one core here; cached afterwards)", file=sys.stderr, flush=True)
        cache.mkdir(parents=True, exist_ok=True)
        with _simulating(out):
            if not out.exists():  # not finished by another process before the lock
                _run_newton(sweep_shot, out, arrays, cache, progress)
    data = np.load(out)
    return data["points"], float(data["seconds"]), float(data["stretch_p99"])
