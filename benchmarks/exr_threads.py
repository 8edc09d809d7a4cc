"""Writer threads against OpenEXR's own threads per file (issue 45).

    python -m benchmarks.exr_threads [--quick]

A 1080p EXR frame takes about 270 ms to compress on one core, so a short chunk (24
frames) on a 16-core node is bound by the last frames' compression, not by the cores:
with 15 writer threads each compressing a whole file, the loop ends waiting for the
last of them. OpenEXR can compress one file's chunks on threads of its own
(``USDWRINKLE_EXR_THREADS``, outputs/writer.exr_threads). Each row is one ``usdwrinkle
render`` process of the shirt and of CesiumMan at 1920x1080 (24 frames), with T writer
threads and t OpenEXR threads per file, the rows alternating over the repeats; fps over
the frame loop (median), and the share of the loop the renderer waited for the writer.
"""
from __future__ import annotations

import json
import os
import statistics
import sys
import tempfile
from pathlib import Path

from .farm import _cli
from .files_written import SHIRT
from .stages import default_corpus


def combinations(cores: int) -> list[tuple[int, int]]:
    """(writer threads, OpenEXR threads per file) to compare on ``cores`` cores."""
    rows = [(max(1, cores - 1), 0), (max(1, cores - 1), 1)]
    for share in (2, 4, 8):
        if cores // share >= 1 and share <= cores:
            rows.append((max(1, cores // share), share))
    return list(dict.fromkeys(rows))


def measure(corpus: Path | None = None, quick: bool = False) -> dict:
    from usdwrinkle.outputs.writer import cores

    size = ("480", "270") if quick else ("1920", "1080")
    frames = "1:4" if quick else "1:24"
    stages = [("shirt", SHIRT, [])]
    cesium = corpus / "usd-wg" / "CesiumMan.usdz" if corpus else None
    if cesium is not None and cesium.is_file():
        stages.append(("CesiumMan", cesium, ["--all-meshes"]))
    combos = combinations(cores())[:2] if quick else combinations(cores())
    repeats = 1 if quick else 2
    runs: dict = {}
    with tempfile.TemporaryDirectory() as folder:
        for repeat in range(repeats):
            for name, stage, extra in stages:
                for threads, per_file in combos:
                    key = f"{name}/{threads}/{per_file}"
                    stats = os.path.join(folder, f"{len(runs)}-{repeat}.json")
                    out = os.path.join(folder, f"{key.replace('/', '_')}{repeat}",
                                       "f.####.exr")
                    wall, cpu = _cli("render", stage, out, *extra, "--frames", frames,
                                     "--width", size[0], "--height", size[1],
                                     "--write-threads", threads, "--stats", stats,
                                     "--no-stats-passes", "--quiet",
                                     env={"USDWRINKLE_EXR_THREADS": str(per_file)})
                    data = json.loads(Path(stats).read_text())
                    runs.setdefault(key, []).append(
                        (len(data["frames"]) / data["loop_s"], data["waited_s"] / data["loop_s"],
                         cpu / (wall * cores()), wall))
    rows = []
    for key, values in runs.items():
        name, threads, per_file = key.split("/")
        rows.append({"stage": name, "write_threads": int(threads), "exr_threads": int(per_file),
                     "fps": statistics.median(v[0] for v in values),
                     "wait_share": statistics.median(v[1] for v in values),
                     "cpu_utilisation": statistics.median(v[2] for v in values),
                     "wall_s": statistics.median(v[3] for v in values)})
    return {"cores": cores(), "frames": frames, "size": "x".join(size), "repeats": repeats,
            "rows": rows}


def markdown(result: dict) -> list[str]:
    lines = ["### Writer threads and OpenEXR's threads", "",
             f"{result['size']} EXR, frames {result['frames']}, on {result['cores']} core(s), "
             f"median of {result['repeats']} alternating runs (`python -m "
             "benchmarks.exr_threads`): T writer threads, each file compressed on t threads "
             "of OpenEXR's own (0: in its writer thread).", "",
             "| stage | T | t | fps | waits for the writer | CPU utilisation | whole process s |",
             "|---|---|---|---|---|---|---|"]
    for row in result["rows"]:
        lines.append(f"| {row['stage']} | {row['write_threads']} | {row['exr_threads']} | "
                     f"{row['fps']:.1f} | {100 * row['wait_share']:.0f}% | "
                     f"{100 * row['cpu_utilisation']:.0f}% | {row['wall_s']:.2f} |")
    return lines + [""]


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    result = measure(default_corpus(), quick="--quick" in args)
    print("\n".join(markdown(result)))
    if "--json" in args:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
