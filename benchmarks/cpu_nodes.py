"""CPU render nodes: CesiumMan end to end as a farm node without a GPU runs it.

24 frames at 640x360, ``--all-meshes``, to EXR (every AOV) and to PNG, each render a
whole process (start-up, USD read, all AOVs, encode): the serial path (``--write-threads
0``) against the default (encode overlapped with the next frame), and, with ``bench
--before CHECKOUT``, the default of an earlier usdwrinkle in the same run, alternating.
Wall time and CPU time of the process; one more run of each with ``--stats`` gives the
per-frame split. The encoders table times one frame's pixels written by OpenImageIO and
by OpenEXR alone, on one thread: the floor that overlap can hide but not remove, and the
measurements behind the EXR defaults.
"""
from __future__ import annotations

import json
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

from .farm import _cli

#: the runs compared: name -> extra render options
MODES = {"serial": ["--write-threads", "0"], "overlapped": []}
SPLIT = ("usd_read", "skin", "crush", "relax", "draw", "readback", "encode")
ROWS = (("before_exr", "EXR, before"), ("exr_serial", "EXR, serial"),
        ("exr_overlapped", "EXR, overlapped"), ("png_serial", "PNG, serial"),
        ("png_overlapped", "PNG, overlapped"))


def _split(stats_path: str) -> dict:
    stats = json.loads(Path(stats_path).read_text())
    frames = stats["frames"]
    row = {key: statistics.median(f.get(key, 0.0) for f in frames) for key in SPLIT}
    row["render"] = statistics.median(f["render"] for f in frames)
    row["wait"] = stats["waited_s"] * 1e3 / max(len(frames), 1)
    row["loop_s"] = stats["loop_s"]
    return row


def _before(checkout: str | None) -> dict | None:
    """The earlier usdwrinkle to compare with: its source folder and commit."""
    if not checkout:
        return None
    src = Path(checkout) / "src"
    if not (src / "usdwrinkle").is_dir():
        raise RuntimeError(f"--before {checkout}: no src/usdwrinkle there")
    commit = subprocess.run(["git", "-C", checkout, "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    return {"env": {"PYTHONPATH": str(src)}, "commit": commit}


def cpu_nodes(quick: bool, corpus: Path | None, ctx=None, before: str | None = None) -> dict:
    path = corpus / "usd-wg" / "CesiumMan.usdz" if corpus else None
    if path is None or not path.is_file():
        return {"skipped": f"CesiumMan.usdz not found (looked in {corpus})"}
    count = 6 if quick else 24
    width, height = (320, 180) if quick else (640, 360)
    runs = 1 if quick else 5
    cores = os.cpu_count() or 1
    earlier = _before(before)
    rows = {}
    with tempfile.TemporaryDirectory() as folder:
        common = ["--all-meshes", "--frames", f"1:{count}", "--width", width, "--height",
                  height, "--quiet"]
        # (label) -> (extension, extra options, environment)
        runs_of = {(ext + "_" + mode): (ext, MODES[mode], None)
                   for ext in ("exr", "png") for mode in MODES}
        if earlier:
            runs_of["before_exr"] = ("exr", [], earlier["env"])
        walls = {key: [] for key in runs_of}
        cpus = {key: [] for key in runs_of}
        # alternate, so that the VM's drift falls on every mode (--quick, a smoke test:
        # the --stats run below is the one timed)
        for run in range(0 if quick else runs):
            for key, (ext, extra, env) in runs_of.items():
                out = os.path.join(folder, f"{key}{run}", f"c.####.{ext}")
                wall, cpu = _cli("render", path, out, *common, *extra, env=env)
                walls[key].append(wall)
                cpus[key].append(cpu)
        for key, (ext, extra, env) in runs_of.items():
            stats = os.path.join(folder, f"{key}.json")
            wall, cpu = _cli("render", path, os.path.join(folder, f"s{key}", f"c.####.{ext}"),
                             *common, *extra, "--stats", stats, env=env)
            if quick:
                walls[key].append(wall)
                cpus[key].append(cpu)
            wall = statistics.median(walls[key])
            split = _split(stats)
            rows[key] = {
                "seconds": wall, "fps": count / wall,
                "cpu_utilisation": statistics.median(cpus[key]) / (wall * cores),
                # what is not the frame loop: interpreter, imports, stage, GL, shaders
                "startup_s": max(wall - split["loop_s"], 0.0),
                "split_ms": split}
    exr = rows["exr_overlapped"]
    result = {"frames": count, "width": width, "height": height, "runs": runs,
              "cores": cores, "rows": rows, "target_fps": 10.0, "exr_fps": exr["fps"],
              "speedup_exr": rows["exr_serial"]["seconds"] / exr["seconds"],
              "speedup_png": rows["png_serial"]["seconds"] / rows["png_overlapped"]["seconds"],
              # the floor: frames cannot come faster than the render loop alone allows
              "floor_fps": 1e3 / exr["split_ms"]["render"]}
    if earlier:
        result["before"] = {"commit": earlier["commit"],
                            "speedup": rows["before_exr"]["seconds"] / exr["seconds"]}
    if ctx is not None:
        result["encoders"] = encoders(ctx, path, width, height, 3 if quick else 15)
        from .encoding import measure as encoding
        from .exr_threads import measure as exr_threads
        from .files_written import measure as files_written

        result["encoding"] = encoding(quick, ctx)
        result["files_written"] = files_written(corpus, quick)
        result["exr_threads"] = exr_threads(corpus, quick)
    return result


def encoders(ctx, stage: Path, width: int, height: int, repeats: int) -> dict:
    """One CesiumMan frame's EXR pixels encoded on one thread, median ms and bytes:
    OpenImageIO (float, and half colour and normals through its conversion) against
    OpenEXR's binding (what render uses), and each compression of the default."""
    import numpy as np
    import OpenImageIO as oiio

    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.images.aovs import AOV_BLOCKS, ImageLayout
    from usdwrinkle.outputs import images

    engine = WrinkleEngine(str(stage), all_meshes=True, ctx=ctx)
    try:
        buffers = engine.render_frame(12.0, width, height)
    finally:
        engine.release()
    frames = {half: images.image_from_buffers(buffers, ImageLayout("exr", half=half))
              for half in (False, True)}
    saved = {name: oiio.get_int_attribute(name) for name in ("threads", "exr_threads")}

    def timed(write, scratch: str) -> tuple[float, int]:
        write(scratch)
        times = []
        for _ in range(repeats):
            started = time.perf_counter()
            write(scratch)
            times.append((time.perf_counter() - started) * 1e3)
        return statistics.median(times), os.path.getsize(scratch)

    def with_oiio(half: bool, compression: str):
        def write(scratch: str) -> None:
            names = AOV_BLOCKS
            pixels = np.ascontiguousarray(np.concatenate(
                [buffers[aov].pixels for aov in names], axis=2), np.float32)
            spec = oiio.ImageSpec(width, height, pixels.shape[2], "float")
            spec.channelnames = tuple(n for aov in names for n in buffers[aov].channel_names)
            if half:
                spec.channelformats = tuple(
                    oiio.TypeDesc("half" if n in frames[True].planes and
                                  frames[True].planes[n].dtype == np.float16 else "float")
                    for n in spec.channelnames)
            spec.attribute("compression", compression)
            images.encode_file(scratch, spec, pixels, scratch)
        return write

    def with_openexr(half: bool, compression: str):
        return lambda scratch: images.encode_frame(scratch, frames[half], scratch, compression)

    rows = []
    oiio.attribute("threads", 1)
    oiio.attribute("exr_threads", 1)
    try:
        with tempfile.TemporaryDirectory() as folder:
            scratch = os.path.join(folder, "frame.exr")
            cases = [("OpenImageIO", False, "zip"), ("OpenImageIO", True, "zip"),
                     ("OpenEXR", False, "zip")] + \
                [("OpenEXR", True, c) for c in images.EXR_COMPRESSIONS]
            for library, half, compression in cases:
                make = with_oiio if library == "OpenImageIO" else with_openexr
                ms, size = timed(make(half, compression), scratch)
                rows.append({"library": library, "half": half, "compression": compression,
                             "ms": ms, "bytes": size})
    finally:
        for name, value in saved.items():
            oiio.attribute(name, value)
    return {"width": width, "height": height, "repeats": repeats, "rows": rows}


def markdown(result: dict) -> list[str]:
    row = result.get("cpu_nodes")
    if not row:
        return []
    lines = ["", "## CPU render nodes", ""]
    if "skipped" in row:
        return lines + [f"Skipped ({row['skipped']}).", ""]
    before = row.get("before")
    from usdwrinkle.render.context import is_software_renderer

    software = is_software_renderer(result.get("machine", {}).get("gl_renderer", ""))
    lines += [
        f"CesiumMan.usdz, {row['frames']} frames at {row['width']}x{row['height']}, "
        "`--all-meshes`, each render a whole process (start-up, USD read, every AOV, encode), "
        f"median of {row['runs']}; the split is the median per frame of one `--stats` run "
        "(ms; each pass then ends in glFinish; readback is the resolve pass and the copy to "
        "memory). Serial: `--write-threads 0`; overlapped: the default, frame f encoded while "
        "f + 1 renders."
        + (f" Before: the default render of usdwrinkle at commit {before['commit']} "
           "(`bench --before`), run in turn with the others." if before else ""), "",
        "| run | seconds | fps | CPU utilisation | start-up s | USD read | skin | crush | "
        "relax | draw | readback | encode | wait |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for key, label in ROWS:
        if key not in row["rows"]:
            continue
        r = row["rows"][key]
        s = r["split_ms"]
        lines.append(
            f"| {label} | {r['seconds']:.2f} | {r['fps']:.1f} | "
            f"{r['cpu_utilisation']:.0%} of {row['cores']} | {r['startup_s']:.2f} | "
            + " | ".join(f"{s[k]:.1f}" for k in (*SPLIT, "wait")) + " |")
    met = "met" if row["exr_fps"] >= row["target_fps"] else "not met"
    lines += ["", f"Overlapping the encode: EXR {row['speedup_exr']:.2f}x, PNG "
              f"{row['speedup_png']:.2f}x."
              + (f" Against the earlier code: EXR {before['speedup']:.2f}x." if before else "")
              + f" Target {row['target_fps']:.0f} fps for EXR: {row['exr_fps']:.1f} fps, "
              f"{met}. The render loop alone (USD read, passes, resolve and readback, no "
              f"encode) allows at most {row['floor_fps']:.1f} fps here"
              + (": llvmpipe draws on the same cores that encode." if software else
                 "; the encode and the start-up are the CPU's.")
              + f" Start-up is paid once per process: a farm chunk of {row['frames']} frames "
              "spends the start-up column of its seconds on it.", ""]
    enc = row.get("encoders")
    if enc:
        lines += ["### EXR encoders", "",
                  f"One frame's pixels ({enc['width']}x{enc['height']}, 10 channels), encoded "
                  f"on one thread, median of {enc['repeats']}; the file as `render` writes it "
                  "(half: colour and normals half float, the rest float).", "",
                  "| library | channels | compression | ms | KiB |", "|---|---|---|---|---|"]
        for e in enc["rows"]:
            lines.append(f"| {e['library']} | {'half + float' if e['half'] else 'float'} | "
                         f"{e['compression']} | {e['ms']:.1f} | {e['bytes'] / 1024:.0f} |")
        lines.append("")
    if row.get("encoding"):
        from .encoding import markdown as encoding

        lines += encoding(row["encoding"])
    if row.get("exr_threads"):
        from .exr_threads import markdown as exr_threads

        lines += exr_threads(row["exr_threads"])
    if row.get("files_written"):
        from .files_written import markdown as files_written

        lines += files_written(row["files_written"])
    return lines
