"""CPU render nodes: CesiumMan end to end as a farm node without a GPU runs it.

24 frames at 640x360, ``--all-meshes``, to EXR (every AOV) and to PNG, each render a
whole process (start-up, USD read, all AOVs, encode): the serial path (``--write-threads
0``, every EXR channel float, zip) against the default (encode overlapped with the next
frame). Wall time and CPU time of the process; one more run of each with ``--stats``
gives the per-frame split, and the encode time of the same pixels with OpenImageIO
alone is the floor that overlap can hide but not remove.
"""
from __future__ import annotations

import json
import os
import statistics
import tempfile
from pathlib import Path

from .farm import _cli

#: the runs compared: name -> extra render options
MODES = {"serial": ["--write-threads", "0"], "overlapped": []}
SPLIT = ("usd_read", "skin", "crush", "relax", "draw", "readback", "encode")


def _split(stats_path: str) -> dict:
    stats = json.loads(Path(stats_path).read_text())
    frames = stats["frames"]
    row = {key: statistics.median(f.get(key, 0.0) for f in frames) for key in SPLIT}
    row["render"] = statistics.median(f["render"] for f in frames)
    row["wait"] = stats["waited_s"] * 1e3 / max(len(frames), 1)
    row["loop_s"] = stats["loop_s"]
    return row


def cpu_nodes(quick: bool, corpus: Path | None) -> dict:
    path = corpus / "usd-wg" / "CesiumMan.usdz" if corpus else None
    if path is None or not path.is_file():
        return {"skipped": f"CesiumMan.usdz not found (looked in {corpus})"}
    count = 6 if quick else 24
    width, height = (320, 180) if quick else (640, 360)
    runs = 1 if quick else 5
    cores = os.cpu_count() or 1
    rows = {}
    with tempfile.TemporaryDirectory() as folder:
        common = ["--all-meshes", "--frames", f"1:{count}", "--width", width, "--height",
                  height, "--quiet"]
        walls = {(ext, mode): [] for ext in ("exr", "png") for mode in MODES}
        cpus = {key: [] for key in walls}
        for run in range(runs):  # alternate, so that the VM's drift falls on every mode
            for ext, mode in walls:
                out = os.path.join(folder, f"{ext}{mode}{run}", f"c.####.{ext}")
                wall, cpu = _cli("render", path, out, *common, *MODES[mode])
                walls[(ext, mode)].append(wall)
                cpus[(ext, mode)].append(cpu)
        for ext, mode in walls:
            stats = os.path.join(folder, f"{ext}{mode}.json")
            _cli("render", path, os.path.join(folder, f"s{ext}{mode}", f"c.####.{ext}"),
                 *common, *MODES[mode], "--stats", stats)
            wall = statistics.median(walls[(ext, mode)])
            split = _split(stats)
            rows[f"{ext}_{mode}"] = {
                "seconds": wall, "fps": count / wall,
                "cpu_utilisation": statistics.median(cpus[(ext, mode)]) / (wall * cores),
                # what is not the frame loop: interpreter, imports, stage, GL, shaders
                "startup_s": max(wall - split["loop_s"], 0.0),
                "split_ms": split}
    exr = rows["exr_overlapped"]
    return {"frames": count, "width": width, "height": height, "runs": runs, "cores": cores,
            "rows": rows, "target_fps": 10.0, "exr_fps": exr["fps"],
            "speedup_exr": rows["exr_serial"]["seconds"] / exr["seconds"],
            "speedup_png": rows["png_serial"]["seconds"] / rows["png_overlapped"]["seconds"],
            # the floor: frames cannot come faster than the render loop alone allows
            "floor_fps": 1e3 / exr["split_ms"]["render"]}


def markdown(result: dict) -> list[str]:
    row = result.get("cpu_nodes")
    if not row:
        return []
    lines = ["", "## CPU render nodes", ""]
    if "skipped" in row:
        return lines + [f"Skipped ({row['skipped']}).", ""]
    lines += [
        f"CesiumMan.usdz, {row['frames']} frames at {row['width']}x{row['height']}, "
        "`--all-meshes`, each render a whole process (start-up, USD read, every AOV, encode), "
        f"median of {row['runs']}; the split is the median per frame of one `--stats` run "
        "(ms; each pass then ends in glFinish). Serial: `--write-threads 0`; overlapped: the "
        "default, frame f encoded while f + 1 renders.", "",
        "| run | seconds | fps | CPU utilisation | start-up s | USD read | skin | crush | "
        "relax | draw | readback | encode | wait |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for key, label in (("exr_serial", "EXR, serial"), ("exr_overlapped", "EXR, overlapped"),
                       ("png_serial", "PNG, serial"), ("png_overlapped", "PNG, overlapped")):
        r = row["rows"][key]
        s = r["split_ms"]
        lines.append(
            f"| {label} | {r['seconds']:.2f} | {r['fps']:.1f} | "
            f"{r['cpu_utilisation']:.0%} of {row['cores']} | {r['startup_s']:.2f} | "
            + " | ".join(f"{s[k]:.1f}" for k in (*SPLIT, "wait")) + " |")
    met = "met" if row["exr_fps"] >= row["target_fps"] else "not met"
    lines += ["", f"Overlapping the encode: EXR {row['speedup_exr']:.2f}x, PNG "
              f"{row['speedup_png']:.2f}x. Target {row['target_fps']:.0f} fps for EXR: "
              f"{row['exr_fps']:.1f} fps, {met}. The render loop alone (USD read, passes, "
              f"resolve and readback, no encode) allows at most {row['floor_fps']:.1f} fps "
              "here: llvmpipe draws and resolves on the same two cores that encode.", ""]
    return lines
