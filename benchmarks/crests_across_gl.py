"""Crests across GL implementations (issue 46): the same frames on a GPU and on llvmpipe.

    python -m benchmarks.crests_across_gl --save gpu.npz       # on the GPU node
    python -m benchmarks.crests_across_gl --compare gpu.npz    # here, on llvmpipe
    python -m benchmarks.crests_across_gl --save-tables t.npz [shirt] [cesium_man]
    python -m benchmarks.crests_across_gl --compare-tables t.npz

Each run renders the shirt and CesiumMan (``--all-meshes``, with its units) at the
frames and size of benchmarks/stability.py from a cold engine, and keeps each frame's
``wrinkle.height``, ``wrinkle.amplitude`` and coverage. ``--compare`` measures, per
frame, the share of wrinkled pixels whose height differs by more than 15% of the largest
amplitude between the saved run and this machine's: stability's "crest moved", where the
change is the GL implementation rather than the input (issue 46's bar: 2%).
"""
from __future__ import annotations

import sys
import tempfile

import numpy as np

from .stability import FRAMES, SHIRT, SLEEVE, corpus_dir, heights, moved_share, with_units


def runs(ctx=None) -> dict:
    """stage -> frame -> (height, amplitude, alpha)."""
    out = {"shirt": heights(str(SHIRT), ctx=ctx)}
    cesium = corpus_dir() / "usd-wg" / "CesiumMan.usdz"
    if cesium.exists():
        with tempfile.TemporaryDirectory() as folder:
            out["cesium_man"] = heights(with_units(str(cesium), f"{folder}/cesium.usda"),
                                        all_meshes=True, ctx=ctx)
    return out


def save(path: str, result: dict) -> None:
    from usdwrinkle.render.context import renderer_info

    arrays = {f"{stage}/{frame}/{index}": plane for stage, frames in result.items()
              for frame, planes in frames.items() for index, plane in enumerate(planes)}
    arrays["renderer"] = np.array(renderer_info()["renderer"])
    np.savez_compressed(path, **arrays)


def load(path: str) -> tuple[str, dict]:
    data = np.load(path)
    result: dict = {}
    for key in data.files:
        if key == "renderer":
            continue
        stage, frame, index = key.split("/")
        planes = result.setdefault(stage, {}).setdefault(int(frame), [None, None, None])
        planes[int(index)] = data[key]
    return str(data["renderer"]), {stage: {f: tuple(p) for f, p in frames.items()}
                                   for stage, frames in result.items()}


def compare(path: str) -> str:
    from usdwrinkle.render.context import renderer_info

    theirs_name, theirs = load(path)
    ours = runs()
    lines = [f"crests of {theirs_name} against {renderer_info()['renderer']}: wrinkled pixels "
             "whose height differs by more than 15% of the largest amplitude", "",
             "| stage | " + " | ".join(f"frame {f}" for f in FRAMES) + " |",
             "|---|" + "---|" * len(FRAMES)]
    for stage in ours:
        if stage not in theirs:
            continue
        shares = moved_share(ours[stage], theirs[stage])
        lines.append(f"| {stage} | " + " | ".join(f"{100 * shares[f]:.2f}%" for f in FRAMES)
                     + " |")
    return "\n".join(lines)


def _table_stage(name: str, folder: str) -> tuple[str, bool, str | None]:
    """A stage of TABLE_STAGES: its path (made in ``folder``), whether all its meshes
    wrinkle, and the mesh whose tables are kept (None: the first of the stage's)."""
    if name == "shirt":
        return str(SHIRT), False, SLEEVE
    return (with_units(str(corpus_dir() / "usd-wg" / "CesiumMan.usdz"),
                       f"{folder}/cesium.usda"), True, None)


#: the stages whose per-vertex tables --save-tables keeps (each, with its history and
#: cold, about 8 MB of compressed arrays)
TABLE_STAGES = ("shirt", "cesium_man")


def _key_prefix(stage: str) -> str:
    """The prefix of a stage's keys in a --save-tables file (the shirt's as before)."""
    return "" if stage == "shirt" else f"{stage}:"


def tables(cold: bool, ctx=None, stage: str = "shirt") -> dict:
    """A stage's per-vertex tables (its wrinkled mesh's: the shirt's sleeve, CesiumMan's
    first mesh) after each frame 1..24 (posed points, the wave fields, the relaxed phases,
    crest damping's damped directions, crush's anchored phases), with the phase history
    (``cold``: each frame a cold start)."""
    from usdwrinkle.engine import WrinkleEngine

    out = {}
    engine = None
    with tempfile.TemporaryDirectory() as folder:
        path, all_meshes, mesh = _table_stage(stage, folder)
        try:
            for frame in range(1, 25):
                if engine is None or cold:
                    if engine is not None:
                        engine.release()
                    engine = WrinkleEngine(path, ctx=ctx, all_meshes=all_meshes,
                                           history_start=float(frame) if cold else None)
                engine.compute_frame(float(frame), 1.0)
                res = engine.mesh_resources(mesh or next(iter(engine.meshes)))
                out[frame] = (np.asarray(res.posed_points.read()),
                              np.asarray(res.waves.current.read()),
                              np.asarray(res.waves.phase.read()),
                              np.asarray(res.waves.written.damped.read()),
                              np.asarray(res.waves.anchor_phase.read()))
        finally:
            if engine is not None:
                engine.release()
    return out


def save_tables(path: str, stages=TABLE_STAGES) -> None:
    arrays = {}
    for stage in stages:
        if stage != "shirt" and not (corpus_dir() / "usd-wg" / "CesiumMan.usdz").exists():
            continue
        prefix = _key_prefix(stage)
        for mode in ("history", "cold"):
            for frame, planes in tables(mode == "cold", stage=stage).items():
                for index, table in enumerate(planes):
                    arrays[f"{prefix}{mode}/{frame}/{index}"] = table
    np.savez_compressed(path, **arrays)


def compare_tables(path: str) -> str:
    data = np.load(path)
    parts = []
    for stage in TABLE_STAGES:
        prefix = _key_prefix(stage)
        if any(key.startswith(prefix + "history/") for key in data.files):
            parts.append(_compare_stage_tables(data, stage, prefix))
    return "\n\n".join(parts)


def _compare_stage_tables(data, stage: str, prefix: str) -> str:
    lines = [f"per frame, the largest difference of {stage}'s tables (theirs - ours): posed "
             "points, wave fields, phases and anchored phases (radians, wrapped), damped "
             "directions (where both hold one: sin of the undirected angle between them)", "",
             "| mode | frame | points | fields | phase | vertices with phase off > 0.1 | "
             "damped | anchor |",
             "|---|---|---|---|---|---|---|---|"]

    def wrapped(a, b):
        return np.abs(np.angle(np.exp(1j * (a.astype(np.float64) - b))))

    for mode in ("history", "cold"):
        ours = tables(mode == "cold", stage=stage)
        for frame, (points, fields, phase, damped, anchor) in ours.items():
            theirs = [data[f"{prefix}{mode}/{frame}/{i}"]
                      if f"{prefix}{mode}/{frame}/{i}" in data.files else None
                      for i in range(5)]
            dphase = wrapped(theirs[2], phase)
            extra = ["", ""]
            if theirs[3] is not None:  # a file saved before the damped tables were kept
                a, b = theirs[3].reshape(-1, 4)[:, :2], damped.reshape(-1, 4)[:, :2]
                both = (theirs[3].reshape(-1, 4)[:, 2] > 0.5) & (damped.reshape(-1, 4)[:, 2] > 0.5)
                cross = np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
                extra = [f"{cross[both].max(initial=0.0):.2e}",
                         f"{wrapped(theirs[4], anchor).max():.2e}"]
            lines.append(f"| {mode} | {frame} | {np.abs(theirs[0] - points).max():.2e} | "
                         f"{np.abs(theirs[1] - fields).max():.2e} | "
                         f"{dphase.max():.2e} | "
                         f"{int((dphase > 0.1).any(axis=-1).sum())} | {extra[0]} | "
                         f"{extra[1]} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if len(args) >= 2 and args[0] == "--save-tables" and \
            set(args[2:]) <= set(TABLE_STAGES):
        save_tables(args[1], tuple(args[2:]) or TABLE_STAGES)
        return 0
    if len(args) == 2 and args[0] == "--compare-tables":
        print(compare_tables(args[1]))
        return 0
    if len(args) == 2 and args[0] == "--save":
        save(args[1], runs())
        return 0
    if len(args) == 2 and args[0] == "--compare":
        print(compare(args[1]))
        return 0
    print("\n".join(__doc__.strip().splitlines()[2:6]), file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
