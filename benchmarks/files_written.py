"""What a farm gets: frames as files (issue 45).

Each row is one ``usdwrinkle render`` process with the default options (writer threads:
every core but one):

- the paper's shirt at 664x497 to PNG, frames 1-24 in steps of 0.1 (231 frames);
- the shirt and CesiumMan (``--all-meshes``) at 1920x1080 to EXR, 24 frames.

Frames per second without start-up: the frames over the frame loop's time (``--stats``'s
``loop_s``, with ``--no-stats-passes``, so that the loop runs as without ``--stats``).
CPU utilisation: the process's CPU time over its wall time and the cores, over the whole
process and over the frame loop alone (``loop_cpu_s``: start-up runs on one core, so on a
16-core node the whole process's figure stays low however busy the loop keeps them). Waits: the
share of the loop the renderer spent waiting for the writer (frames in flight all taken),
the bound when encoding is the slower half, and waiting on the fence of a frame's
resolve before copying it out (the GPU still busy: the bound when rendering is). ``python -m
benchmarks.files_written`` prints the table; ``python -m benchmarks`` runs it in its CPU
render nodes section.
"""
from __future__ import annotations

import datetime
import json
import os
import sys
import tempfile
from pathlib import Path

from .farm import _cli
from .stages import default_corpus

ROOT = Path(__file__).resolve().parents[1]
SHIRT = ROOT / "sample_stages" / "shirt.usda"


def cases(corpus: Path | None, quick: bool) -> list[tuple[str, Path, list, str]]:
    """(label, stage, options, extension) of each row."""
    scale = 4 if quick else 1
    paper = (664 // scale, 497 // scale, "1:6x0.1" if quick else "1:24x0.1")
    full = (1920 // scale, 1080 // scale, "1:4" if quick else "1:24")
    rows = [(f"shirt {paper[0]}x{paper[1]} PNG, {paper[2]}", SHIRT,
             ["--frames", paper[2], "--width", paper[0], "--height", paper[1]], "png"),
            (f"shirt {full[0]}x{full[1]} EXR, {full[2]}", SHIRT,
             ["--frames", full[2], "--width", full[0], "--height", full[1]], "exr")]
    cesium = corpus / "usd-wg" / "CesiumMan.usdz" if corpus else None
    if cesium is not None and cesium.is_file():
        rows.append((f"CesiumMan {full[0]}x{full[1]} EXR, {full[2]}", cesium,
                     ["--all-meshes", "--frames", full[2], "--width", full[0], "--height",
                      full[1]], "exr"))
    return rows


def measure(corpus: Path | None = None, quick: bool = False, extra: tuple = ()) -> dict:
    """The rows; ``extra``: more render options for every row (a comparison's)."""
    from usdwrinkle.outputs.writer import cores

    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for index, (label, stage, options, ext) in enumerate(cases(corpus, quick)):
            stats = os.path.join(folder, f"stats{index}.json")
            out = os.path.join(folder, f"r{index}", f"f.####.{ext}")
            wall, cpu = _cli("render", stage, out, *options, *extra, "--stats", stats,
                             "--no-stats-passes", "--quiet")
            data = json.loads(Path(stats).read_text())
            frames = len(data["frames"])
            rows.append({"case": label, "frames": frames, "wall_s": wall,
                         "fps": frames / data["loop_s"],
                         "cpu_utilisation": cpu / (wall * cores()),
                         "loop_cpu_utilisation": data["loop_cpu_s"] /
                         (data["loop_s"] * cores()),
                         "wait_share": data["waited_s"] / data["loop_s"],
                         "gpu_wait_share": data.get("gpu_waited_s", 0.0) / data["loop_s"],
                         "readback_buffers": data.get("readback_buffers", 1),
                         "exr_threads": data.get("exr_threads", 0),
                         "write_threads": data["write_threads"]})
    return {"cores": cores(), "rows": rows, "date": datetime.datetime.now(
        datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}


def markdown(result: dict) -> list[str]:
    lines = ["### Files written", "",
             f"What a farm gets: each row one `usdwrinkle render` process with the defaults "
             f"on {result['cores']} core(s) "
             f"({result['rows'][0].get('readback_buffers', 1) if result['rows'] else '?'} "
             f"readback buffers; writer threads: T, or T x t with t OpenEXR threads per "
             f"file), {result['date']} "
             "(`python -m benchmarks.files_written`). Frames per second over the frame loop "
             "(without start-up); CPU utilisation of all cores over the whole process and "
             "over the frame loop; "
             "waits: the share of the loop the renderer waited for the writer (encode the "
             "bound), and for the fence of a frame's resolve before copying it out (the "
             "GPU, or llvmpipe, the bound).", "",
             "| case | frames | writer threads | fps | CPU utilisation | CPU in the loop | "
             "waits for the writer | waits for the GPU | whole process s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for row in result["rows"]:
        threads = str(row.get("write_threads", "?")) + (
            f" x {row['exr_threads']}" if row.get("exr_threads") and "EXR" in row["case"]
            else "")
        loop = row.get("loop_cpu_utilisation")  # not in a report made before it was kept
        loop_text = "–" if loop is None else f"{100 * loop:.0f}%"
        lines.append(f"| {row['case']} | {row['frames']} | {threads} | {row['fps']:.1f} | "
                     f"{100 * row['cpu_utilisation']:.0f}% | {loop_text} | "
                     f"{100 * row['wait_share']:.0f}% | "
                     f"{100 * row.get('gpu_wait_share', 0.0):.0f}% | {row['wall_s']:.1f} |")
    return lines + [""]


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else argv
    extra = tuple(a for a in args if a != "--quick")  # render options: --readback-buffers 1
    print("\n".join(markdown(measure(default_corpus(), quick="--quick" in args,
                                      extra=extra))))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
