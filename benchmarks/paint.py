"""The paint mode's latencies (issue 43): how fast the view follows the brush, the full
frame follows the release, and a W slider move shows, on the shirt and on CesiumMan.

Two kinds of rows:
- the window: tests/paint_driver.py's ``bench`` scenario in a real window under Xvfb (a
  960x540 view, QMouseEvents across its middle): what an artist sees, upload and blit to
  Qt included; "not run" where Xvfb or PySide6 is missing;
- the engine: the same steps on a PaintSession headless (EGL, no Qt): pick, stamp,
  preview frame; release (authored, the history replayed, full quality); W preview. These
  run on a GPU node too.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
VIEW = (960, 540)


def _cases(corpus: Path | None) -> list[tuple[str, str, bool]]:
    cases = [("shirt", str(REPO / "sample_stages" / "shirt.usda"), False)]
    if corpus is not None and (corpus / "usd-wg" / "CesiumMan.usdz").exists():
        cases.append(("CesiumMan", str(corpus / "usd-wg" / "CesiumMan.usdz"), True))
    return cases


def window_rows(corpus: Path | None) -> dict:
    """The window's own figures per case, or why they were not measured."""
    if shutil.which("xvfb-run") is None:
        return {"ran": False, "why": "xvfb-run not found (apt-get install xvfb)"}
    try:
        import PySide6  # noqa: F401
    except ImportError:
        return {"ran": False, "why": "PySide6 not installed (pip install 'usdwrinkle[paint]')"}
    rows = []
    for name, stage, all_meshes in _cases(corpus):
        with tempfile.TemporaryDirectory(prefix="usdwrinkle-paint-bench-") as out:
            env = {**os.environ, "PAINT_BENCH_ALL_MESHES": "1" if all_meshes else "0"}
            done = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1600x1000x24",
                                   sys.executable, str(REPO / "tests" / "paint_driver.py"),
                                   "bench", out, stage], env=env, capture_output=True,
                                  text=True, timeout=600)
            if done.returncode != 0:
                return {"ran": False, "why": f"the driver failed: {done.stderr[-300:]}"}
            result = json.loads((Path(out) / "result.json").read_text())
        rows.append({"case": name, "vertices": result["vertices"],
                     "view": result["view"],
                     "drag_fps": 1.0 / float(np.median(result["drag_gaps"])),
                     "drag_p90_ms": 1e3 * float(np.percentile(result["drag_gaps"], 90)),
                     "release_s": result["release"],
                     "width_ms": 1e3 * float(np.median(result["width_moves"])),
                     "stroked": result["stroked"]})
    return {"ran": True, "rows": rows}


def engine_rows(ctx, corpus: Path | None, quick: bool = False) -> list[dict]:
    """The session's steps headless, medians of several strokes (no Qt)."""
    from usdwrinkle.app.paint_session import FULL, PREVIEW, PaintSession, open_paint_stage

    width, height = VIEW
    rows = []
    for name, stage_path, all_meshes in _cases(corpus):
        with tempfile.TemporaryDirectory(prefix="usdwrinkle-paint-bench-") as out:
            stage, layer, save = open_paint_stage(stage_path, str(Path(out) / "p.usda"))
            session = PaintSession(stage, layer, save, ctx=ctx, all_meshes=all_meshes)
            try:
                session.render(width, height, FULL)
                steps, releases, widths = [], [], []
                for _ in range(2 if quick else 4):
                    y = height / 2
                    xs = np.linspace(0.1 * width, 0.9 * width, 12 if quick else 30)
                    session.render(width, height, PREVIEW)
                    if not session.begin_stroke(xs[0], y, width, height):
                        session.begin_stroke(width / 2, y, width, height)
                    for x in xs[1:]:
                        started = time.perf_counter()
                        session.drag(x, y, width, height)
                        session.render(width, height, PREVIEW)
                        steps.append(time.perf_counter() - started)
                    started = time.perf_counter()
                    session.end_stroke()
                    session.render(width, height, FULL)
                    releases.append(time.perf_counter() - started)
                    w = session.control("width")
                    started = time.perf_counter()
                    session.set_control("width", w * 0.8, live=True)
                    session.render(width, height, PREVIEW)
                    widths.append(time.perf_counter() - started)
                    session.set_control("width", w, live=False)
                rows.append({"case": name, "step_ms": 1e3 * float(np.median(steps)),
                             "drag_fps": 1.0 / float(np.median(steps)),
                             "release_s": float(np.median(releases)),
                             "width_ms": 1e3 * float(np.median(widths))})
            finally:
                session.release()
    return rows


def paint(quick: bool, ctx, corpus: Path | None) -> dict:
    window = {"ran": False, "why": "quick mode (the full bench measures the window)"} \
        if quick else window_rows(corpus)
    return {"view": list(VIEW), "window": window, "engine": engine_rows(ctx, corpus, quick)}


def paint_targets(result: dict) -> list[dict]:
    """The issue's three bars, read from the window rows (the engine's where the window
    did not run)."""
    section = result.get("paint")
    if section is None:
        return []
    window = section["window"]
    rows = window["rows"] if window.get("ran") else section["engine"]
    source = "window" if window.get("ran") else "engine only: the window did not run"
    out = []
    for row in rows:
        out += [
            {"measure": f"paint: view while dragging, {row['case']} ({source})",
             "target": ">= 10 fps at 960x540", "value": f"{row['drag_fps']:.0f} fps",
             "met": row["drag_fps"] >= 10},
            {"measure": f"paint: full-quality frame after release, {row['case']}",
             "target": "<= 1 s", "value": f"{row['release_s']:.2f} s",
             "met": row["release_s"] <= 1.0},
            {"measure": f"paint: W slider move visible, {row['case']}", "target": "<= 200 ms",
             "value": f"{row['width_ms']:.0f} ms", "met": row["width_ms"] <= 200}]
    return out


def paint_markdown(result: dict) -> list[str]:
    section = result.get("paint")
    if section is None:
        return []
    lines = ["", "## The paint window", "",
             "`usdwrinkle paint` with a 960x540 view: while the button is down the view "
             "shows a reduced preview (1 sample, half size, the current frame computed from "
             "the kept wave state of the frame before it); on release the stroke is authored, "
             "the history replays and the frame is drawn at full quality (4 samples, as "
             "`usdwrinkle render`).", ""]
    window = section["window"]
    if window.get("ran"):
        lines += ["In a real window (Xvfb, Qt's xcb platform; QMouseEvents across the "
                  "view's middle; upload and blit into Qt included):", "",
                  "| case | vertices | view | drag fps (median) | drag frame p90 | "
                  "release to full frame | W slider to frame |",
                  "|---|---|---|---|---|---|---|"]
        for r in window["rows"]:
            lines.append(f"| {r['case']} | {r['vertices']:,} | {r['view'][0]}x{r['view'][1]} "
                         f"| {r['drag_fps']:.0f} | {r['drag_p90_ms']:.0f} ms | "
                         f"{r['release_s']:.2f} s | {r['width_ms']:.0f} ms |")
    else:
        lines.append(f"The window was not measured: {window['why']}.")
    lines += ["", "The engine alone (a PaintSession, no Qt: pick, stamp, preview frame):", "",
              "| case | drag step | drag fps | release to full frame | W preview frame |",
              "|---|---|---|---|---|"]
    for r in section["engine"]:
        lines.append(f"| {r['case']} | {r['step_ms']:.1f} ms | {r['drag_fps']:.0f} | "
                     f"{r['release_s']:.2f} s | {r['width_ms']:.0f} ms |")
    return lines
