"""How well neighbouring waves align (the misfit) and how much crests swim, on the six
sample stages, as a distribution over tiny changes of the input (issue 46).

    python -m benchmarks.misfit [--before SRC] [--write docs/method.md]

For each sample stage: the mean over frames 9-24 of ``phase_misfit`` (the points whose
waves the relaxation weighs, above 5% of the largest: the folds drawn before the crests
settle, contract.DRAWN_SLACK, take their phases from their neighbours') and of
``phase_swim`` (reference/relax.py). A stage animated by UsdSkel is measured again with
every joint rotation turned by 0.0005-2 degrees (benchmarks.stability.perturbed): where
nothing but rounding places a dislocation, the misfit of one run is one draw, and the mean
over the draws is what a version of the code gets. ``--before SRC`` runs the same
measurement on another checkout's ``src`` folder (in a process of its own, with
PYTHONPATH=SRC; its shaders come from SRC/../shaders) and puts it beside this one's.
``--write`` replaces the block between the misfit markers."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from .blocks import add_write_option, emit, markers

ROOT = Path(__file__).resolve().parents[1]
STAGES = ("shirt", "zeppelin", "curtain", "pillow", "pull", "flag")
#: joint changes in degrees; 0 is the stage itself
DEGREES = (0.0, 0.0005, 0.001, 0.002, 0.003, 0.005, 0.01, 0.02, 0.03, 0.05, 0.1, 0.2, 0.3,
           0.5, 1.0, 2.0)
BEGIN, END = markers("misfit")


def run_stage(path: str, ctx) -> tuple[float, float]:
    """(mean misfit, mean swim) over frames 9-24 of a fresh engine on ``path``."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.reference.relax import phase_misfit, phase_swim

    engine = WrinkleEngine(path, ctx=ctx)
    mesh = engine.wrinkled_paths[0]
    topology = engine.meshes[mesh].topology
    misfits, swims, previous = [], [], None
    try:
        for frame in range(1, 25):
            engine.compute_frame(float(frame))
            current = engine.read_fields(mesh).arrays()
            if frame >= 9:
                # the waves the relaxation aligns (weighs): the folds drawn before the
                # crests settle take their phases from their neighbours'
                # (a checkout from before the two slacks, --before: its amplitude is
                # the weight)
                weight = current.get("weight", current["amplitude"])
                mask = weight > 0.05 * weight.max()
                misfits.append(phase_misfit(current["points"], current["wave_vector"],
                                            current["phase"], topology, mask))
                if frame >= 10:
                    swims.append(phase_swim(previous, current))
            previous = current
    finally:
        engine.release()
    return float(np.mean(misfits)), float(np.mean(swims))


def animated_by_skel(path: Path) -> bool:
    from pxr import Usd, UsdSkel

    stage = Usd.Stage.Open(str(path))
    return any(prim.IsA(UsdSkel.Animation) for prim in stage.Traverse())


def measure() -> dict:
    """stage -> {"misfit": [one per DEGREES], "swim": [...]} (one entry for a stage that
    UsdSkel does not animate: the joint change does not reach it)."""
    from usdwrinkle.render.context import create_context

    from .stability import perturbed

    ctx = create_context()
    out = {}
    with tempfile.TemporaryDirectory() as folder:
        for name in STAGES:
            path = ROOT / "sample_stages" / f"{name}.usda"
            degrees = DEGREES if animated_by_skel(path) else (0.0,)
            runs = [run_stage(str(path) if deg == 0 else
                              perturbed(str(path), deg, f"{folder}/{name}{deg}.usda"), ctx)
                    for deg in degrees]
            out[name] = {"misfit": [m for m, _ in runs], "swim": [s for _, s in runs]}
    return out


def measure_in(src: str) -> dict:
    """measure() with the usdwrinkle package of another checkout's ``src``."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([src, str(ROOT)])}
    done = subprocess.run([sys.executable, "-m", "benchmarks.misfit", "--json"],
                          cwd=ROOT, env=env, capture_output=True, text=True, check=False)
    if done.returncode:
        raise SystemExit(f"the measurement in {src} failed:\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _cell(values: list[float]) -> str:
    if len(values) == 1:
        return f"{values[0]:.3f}"
    return f"{values[0]:.3f}; {np.mean(values):.3f} ({min(values):.3f}-{max(values):.3f})"


def table(now: dict, before: dict | None, before_label: str) -> str:
    lines = [BEGIN, "", "Made by `python -m benchmarks.misfit --before SRC --write "
             "docs/method.md`: the misfit and the swim (rad, means over frames 9-24). A "
             "stage animated by UsdSkel reads: the stage itself; the mean (the smallest to "
             "the largest) over it and its joints turned by " +
             ", ".join(f"{d:g}" for d in DEGREES[1:]) + " degrees.", ""]
    if before is not None:
        lines += [f"Before: {before_label}.", "",
                  "| stage | misfit before | misfit now | swim before | swim now |",
                  "|---|---|---|---|---|"]
        for name in STAGES:
            lines.append(f"| {name} | {_cell(before[name]['misfit'])} | "
                         f"{_cell(now[name]['misfit'])} | {before[name]['swim'][0]:.3f} | "
                         f"{now[name]['swim'][0]:.3f} |")
        mean = [np.mean([np.mean(run[name]["misfit"]) for name in STAGES])
                for run in (before, now)]
        lines += ["", f"Mean over the six stages (each its mean over the draws): "
                  f"{mean[0]:.3f} before, {mean[1]:.3f} now."]
    else:
        lines += ["| stage | misfit | swim |", "|---|---|---|"]
        for name in STAGES:
            lines.append(f"| {name} | {_cell(now[name]['misfit'])} | "
                         f"{now[name]['swim'][0]:.3f} |")
    lines += ["", END]
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.misfit",
        description="The misfit and the swim of the six sample stages, as a distribution "
                    "over tiny joint changes (the module's docstring says how).")
    parser.add_argument("--before", metavar="SRC",
                        help="also measure another checkout's src folder, beside this one")
    add_write_option(parser, "misfit", "docs/method.md")
    parser.add_argument("--json", action="store_true",
                        help="print this checkout's measurement as JSON (what --before "
                             "runs in the other checkout)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    if args.json:
        print(json.dumps(measure()))
        return 0
    before, label = None, ""
    if args.before:
        before = measure_in(args.before)
        head = subprocess.run(["git", "-C", args.before, "log", "-1", "--format=%h"],
                              capture_output=True, text=True, check=False).stdout.strip()
        label = f"the code at commit {head}" if head else args.before
    emit(args.write, "misfit",
         table(measure(), before, label))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
