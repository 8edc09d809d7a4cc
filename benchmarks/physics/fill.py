"""Fill the physics cache with the Newton referee's simulations, several at a time, before
the tables that read them (referee.py, candidate.py) are made.

    python -m benchmarks.physics.fill [--table converged|sweep] [--only NAME ...]
                                      [--jobs N] [--keep] [--cache .physics-cache]

A fresh checkout has none of them: the converged referee's ten shots are about 13 hours of
solver on one core here (each 1 cm curtain 1.9-3.9 hours, each 1 cm sheared panel about
an hour, each 2 cm sleeve 10-32 minutes). Each simulation runs in its own process
(simulate.simulate_newton), so ``--jobs`` N runs N of them at once, the longest first;
each is cached as it ends. A run that is stopped (or outlasts simulate's four hours) goes
on from its last checkpoint, every 10 frames, the next time (newton_client.py); a resumed
run is the same simulation, not bit for bit the same numbers. Prints each shot as it
starts and ends, and what is left. A shot kept in the repository (kept.py,
benchmarks/physics/simulations/) is read from there, not simulated; ``--keep`` keeps
every simulation of the table that the cache holds there, to be committed."""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from pathlib import Path

from . import kept, referee
from .simulate import cached_newton, newton_path, simulate_newton

ROOT = Path(__file__).resolve().parents[2]


def _cost(name: str, converged: bool) -> float:
    """A shot's share of the solver's time, for the order (the longest first): its points
    times its frames (the 1 cm curtains 630,500, the sheared panels 274,625, the 25 cm
    sleeve 229,600, the 10 cm sleeves at 2 cm 91,840)."""
    shot = referee.SWEEP[name](referee.referee_grid(name, converged)).shot
    return float(len(shot.rest) * shot.frames)


def planned(table: str, only: list[str] | None) -> list[str]:
    """The table's shots (referee.py's): every one of SWEEP for ``converged``, all but
    CONVERGED_ONLY for ``sweep``; ``only`` picks among them. Longest first."""
    converged = table == "converged"
    names = only or [name for name in referee.SWEEP
                     if converged or name not in referee.CONVERGED_ONLY]
    unknown = [name for name in names if name not in referee.SWEEP]
    if unknown:
        raise SystemExit(f"unknown shot(s) {', '.join(unknown)}; the sweep's: "
                         f"{', '.join(referee.SWEEP)}")
    return sorted(names, key=lambda name: -_cost(name, converged))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.fill",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--table", choices=("converged", "sweep"), default="converged",
                        help="whose simulations: the converged referee's (2 cm, 1 cm where "
                             "it differs; 160 iterations) or the 10-iteration sweep's (1 cm)")
    parser.add_argument("--only", nargs="*", default=None, help="these shots only")
    parser.add_argument("--jobs", type=int, default=1,
                        help="simulations at once (each takes one core)")
    parser.add_argument("--keep", action="store_true",
                        help="then keep the table's cached simulations in "
                             "benchmarks/physics/simulations/ (to commit: a fresh checkout "
                             "reads them instead of simulating)")
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error("--jobs must be at least 1")
    converged = args.table == "converged"
    iterations = referee.CONVERGED[1] if converged else None
    solver = referee.solver_options(iterations)

    def shot(name: str):
        return referee.SWEEP[name](referee.referee_grid(name, converged))

    names = planned(args.table, args.only)
    todo = [name for name in names if not cached_newton(shot(name), args.cache, solver)]
    print(f"{len(names) - len(todo)} of {len(names)} cached in {args.cache}; simulating "
          f"{', '.join(todo) or 'none'} ({args.jobs} at a time)", flush=True)
    started, failed = time.perf_counter(), []

    def run(name: str) -> float:
        begun = time.perf_counter()
        simulate_newton(shot(name), args.cache, solver)
        return time.perf_counter() - begun

    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        running = {pool.submit(run, name): name for name in todo}
        while running:
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in done:
                name = running.pop(future)
                try:
                    seconds = future.result()
                    print(f"{name}: cached after {seconds / 60:.0f} minutes "
                          f"({len(running)} running or waiting)", flush=True)
                except (RuntimeError, subprocess.TimeoutExpired) as exc:  # the others go on
                    failed.append(name)
                    print(f"{name}: failed ({exc}); run again to go on from its last "
                          "checkpoint", file=sys.stderr, flush=True)
    print(f"{(time.perf_counter() - started) / 60:.0f} minutes", flush=True)
    if args.keep:
        for name in names:
            cached = newton_path(shot(name), args.cache, solver)[0]
            if cached.exists():
                out = kept.keep(cached)
                print(f"{name}: kept in {out.relative_to(ROOT)} "
                      f"({out.stat().st_size / 2 ** 20:.1f} MiB)", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
