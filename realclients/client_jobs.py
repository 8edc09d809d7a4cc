"""The job protocol every client script speaks (cycles_client, storm_client,
tangents_client), in the client's own Python: read the jobs, run each, report one line per
job on stdout ("ok OUT", "seconds S OUT", or "failed OUT: reason"), and end the process
with os._exit (Blender's and Storm's C++ teardown sometimes aborts after good work).
realclients/__init__.py reads the lines."""
from __future__ import annotations

import json
import os
import sys
import time


def load(jobs_path: str) -> list[dict]:
    with open(jobs_path, encoding="utf-8") as handle:
        return json.load(handle)


def run(jobs: list[dict], do, failure=None) -> None:
    """Run ``do(job)`` for each job and report it; ``failure(job, exc)`` may turn an
    exception into a result line of its own (None: the generic one)."""
    for job in jobs:
        try:
            started = time.perf_counter()
            do(job)
            print(f"ok {job['out']}", flush=True)
            print(f"seconds {time.perf_counter() - started:.6f} {job['out']}", flush=True)
        except Exception as exc:  # noqa: BLE001 (reported per job, the next one goes on)
            line = failure(job, exc) if failure is not None else None
            print(line or f"failed {job['out']}: {type(exc).__name__}: {exc}", flush=True)


def finish() -> None:
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
