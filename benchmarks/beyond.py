"""Beyond the paper: the wrinkled/plain overhead of the second wave system and tension
wrinkles, next to the one-system figure, on the pillow (biaxial) and the pulled sheet.

Each case renders the same stage three ways, taking turns frame by frame (measure.py):
with both features on (wrinkle:biaxial = 1, wrinkle:tension = 1, set in each stage's
session layer), with both off (the paper's one system), and plain (no wrinkles).
"""
from __future__ import annotations

from pathlib import Path

from .measure import measure_frames, size_for

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
CASES = ("pillow", "pull")


def _stage(name: str, features: bool):
    from pxr import Sdf, Usd

    from usdwrinkle.usd import schema

    stage = Usd.Stage.Open(str(SAMPLES / f"{name}.usda"))
    stage.SetEditTarget(stage.GetSessionLayer())
    for prim in stage.Traverse():
        if schema.has_wrinkle_api(prim):
            for attr in (schema.BIAXIAL, schema.TENSION):
                prim.CreateAttribute(attr, Sdf.ValueTypeNames.Float).Set(
                    1.0 if features else 0.0)
    return stage


def overhead(quick: bool, ctx) -> list[dict]:
    from usdwrinkle.engine import WrinkleEngine

    rows = []
    for name in CASES:
        engines = [(WrinkleEngine(_stage(name, True), ctx=ctx, profile=True), True),
                   (WrinkleEngine(_stage(name, False), ctx=ctx, profile=True), True),
                   (WrinkleEngine(_stage(name, False), ctx=ctx, profile=True), False)]
        try:
            aspect = engines[0][0].scene.camera_aspect(None, 1.0) or 1.0
            width, height = size_for(64_000 if quick else 1_000_000, aspect)
            frames = [float(f) for f in range(1, 9 if quick else 25)]
            (both, both_wall, _, count), (one, one_wall, _, _), (_, plain_wall, _, _) = \
                measure_frames(engines, width, height, frames)
            vertices = sum(len(r.rest_points) for r in engines[0][0].meshes.values())
        finally:
            for engine, _ in engines:
                engine.release()
        rows.append({"case": name, "vertices": vertices, "pixels": width * height,
                     "frames_measured": count, "both_pass_ms": both, "one_pass_ms": one,
                     "both_wall_ms": both_wall, "one_wall_ms": one_wall,
                     "plain_wall_ms": plain_wall, "both_overhead": both_wall / plain_wall,
                     "one_overhead": one_wall / plain_wall})
    return rows


def markdown(result: dict) -> list[str]:
    rows = result.get("beyond")
    if not rows:
        return []
    lines = ["", "## Beyond the paper: two wave systems and tension", "",
             "Wall time per frame (ms, median, one sample per pixel) with both features on "
             "(`wrinkle:biaxial = 1`, `wrinkle:tension = 1`), with the paper's one system, and "
             "plain; the overhead is wrinkled over plain. Relax and draw do the second "
             "system's work only where a mesh has `wrinkle:biaxial` on.", "",
             "| case | vertices | pixels | relax ms (both / one) | draw ms (both / one) | "
             "wall both | wall one | wall plain | overhead both | overhead one |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        b, o = r["both_pass_ms"], r["one_pass_ms"]
        lines.append(
            f"| {r['case']} | {r['vertices']:,} | {r['pixels']:,} | "
            f"{b.get('relax', 0):.2f} / {o.get('relax', 0):.2f} | "
            f"{b.get('draw', 0):.2f} / {o.get('draw', 0):.2f} | {r['both_wall_ms']:.2f} | "
            f"{r['one_wall_ms']:.2f} | {r['plain_wall_ms']:.2f} | {r['both_overhead']:.2f}x | "
            f"{r['one_overhead']:.2f}x |")
    return lines
