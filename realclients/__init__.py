"""Real clients: Storm (usdview's Hydra renderer) and Cycles/EEVEE (through Blender's USD
importer), driven from usdwrinkle's checkout to look at what users see.

Blender's ``bpy`` wheel (PyPI, ``bpy==5.0.1``, about 370 MB) ships OpenUSD 25.08 with
UsdImagingGL, UsdAppUtils and the Storm plugin, and Cycles. Its USD build cannot share a
process with usd-core, so each client runs in a Python of its own that has ``bpy``
(storm_client.py, cycles_client.py) and takes a JSON list of jobs.

Which Python: ``USDWRINKLE_BPY_PYTHON`` when set, else ``.venv-bpy/bin/python`` in the
checkout (``.ci/run`` makes it: ``python3 -m venv .venv-bpy && .venv-bpy/bin/pip install
bpy==5.0.1 moderngl``). :func:`bpy_python` says why there is none.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
BPY_VERSION = "5.0.1"


class NoClient(RuntimeError):
    """No Python with Blender's bpy here; the message says how to get one."""


def bpy_python() -> str:
    """The Python that runs the clients; raises NoClient, saying how to install one."""
    candidates = [os.environ.get("USDWRINKLE_BPY_PYTHON"),
                  str(REPO / ".venv-bpy" / "bin" / "python")]
    for candidate in candidates:
        if candidate and os.path.isfile(candidate) and os.access(candidate, os.X_OK):
            with tempfile.TemporaryDirectory(prefix="usdwrinkle-client-") as scratch:
                probe = subprocess.run([candidate, "-c", "import bpy, moderngl"],
                                       capture_output=True, text=True, timeout=120,
                                       env={**os.environ, "TMPDIR": scratch})
            if probe.returncode == 0:
                return candidate
            raise NoClient(f"{candidate} cannot import bpy and moderngl "
                           f"({probe.stderr.strip().splitlines()[-1:]})")
    raise NoClient("no Python with Blender's bpy: python3 -m venv .venv-bpy && "
                   f".venv-bpy/bin/pip install bpy=={BPY_VERSION} moderngl "
                   "(or set USDWRINKLE_BPY_PYTHON)")


#: seconds each job's render took in the client, by output path (the last run's)
SECONDS: dict[str, float] = {}


def _run(script: str, jobs: list[dict], timeout: float) -> dict[str, str]:
    """Run a client on ``jobs``; returns {out path: "ok" or the failure}. The time each
    render took inside the client goes to SECONDS."""
    python = bpy_python()
    # Blender makes a blender_* folder in TMPDIR that os._exit never removes: give each
    # client run its own TMPDIR (and Blender user scripts folder) and remove it afterwards
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-client-") as scratch:
        jobs_path = os.path.join(scratch, "jobs.json")
        with open(jobs_path, "w", encoding="utf-8") as handle:
            json.dump(jobs, handle)
        done = subprocess.run([python, str(HERE / script), jobs_path], capture_output=True,
                              text=True, timeout=timeout,
                              env={**os.environ, "PYTHONNOUSERSITE": "1", "TMPDIR": scratch,
                                   # an add-on a job installs stays in the scratch folder
                                   "BLENDER_USER_SCRIPTS": os.path.join(scratch, "scripts")})
    results = {}
    for line in done.stdout.splitlines():
        if line.startswith("ok "):
            results[line[3:]] = "ok"
        elif line.startswith("seconds "):
            _, seconds, path = line.split(" ", 2)
            SECONDS[path] = float(seconds)
        elif line.startswith("failed "):
            path, _, reason = line[7:].partition(": ")
            results[path] = reason
    for job in jobs:
        results.setdefault(job["out"], f"no result (exit {done.returncode}): "
                                       f"{done.stderr.strip()[-500:]}")
    return results


def storm(jobs: list[dict], timeout: float = 600) -> dict[str, str]:
    """Record each job with Storm (storm_client.py documents the job's keys)."""
    return _run("storm_client.py", jobs, timeout)


def cycles(jobs: list[dict], timeout: float = 1200) -> dict[str, str]:
    """Render each job with Blender's Cycles or EEVEE (cycles_client.py)."""
    return _run("cycles_client.py", jobs, timeout)


def blender_tangents(jobs: list[dict], timeout: float = 300) -> dict[str, str]:
    """Blender's MikkTSpace tangents of each job's mesh (tangents_client.py)."""
    return _run("tangents_client.py", jobs, timeout)


def blender_import(jobs: list[dict], timeout: float = 300) -> dict[str, str]:
    """The materials Blender's USD importer gives each job's meshes (import_client.py)."""
    return _run("import_client.py", jobs, timeout)


if __name__ == "__main__":  # python -m realclients: say whether the clients can run here
    try:
        print(bpy_python())
    except NoClient as exc:
        print(exc, file=sys.stderr)
        sys.exit(1)
