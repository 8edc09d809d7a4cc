"""Wrinkles for other renderers: what ``bake --maps`` costs per frame.

The shirt sample, baked in one process with the wave fields only, then with normal and
height maps at each size; the map time per frame is the difference per frame (the GPU
rasterisation in UV space, padding, readback and the overlapped encode), and the files
each frame adds are summed.
"""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

SHIRT = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"


def _bake_seconds(ctx, frames, maps=None) -> tuple[float, int]:
    """(seconds of one bake of the shirt, bytes of map files written)."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.shot import bake_layer

    engine = WrinkleEngine(str(SHIRT), ctx=ctx, warn=lambda m: None, use_baked=False)
    try:
        with tempfile.TemporaryDirectory() as folder:
            layer = os.path.join(folder, "shirt_maps.usda")
            started = time.perf_counter()
            bake_layer(engine, str(SHIRT), layer, frames, "bench", maps=maps)
            seconds = time.perf_counter() - started
            size = sum(p.stat().st_size for p in Path(folder).rglob("*.png")) + \
                sum(p.stat().st_size for p in Path(folder).rglob("*.exr"))
    finally:
        engine.release()
    return seconds, size


def wrinkle_maps(quick: bool, ctx) -> dict:
    from usdwrinkle.maps.bake import MapOptions

    frames = [float(f) for f in range(1, 7 if quick else 25)]
    sizes = (256, 512) if quick else (1024, 2048)
    base, _ = _bake_seconds(ctx, frames)
    rows = []
    for size in sizes:
        options = MapOptions(kinds=("normal", "height"), size=size)
        seconds, size_bytes = _bake_seconds(ctx, frames, options)
        rows.append({"size": size, "seconds": seconds,
                     "ms_per_frame": (seconds - base) * 1e3 / len(frames),
                     "total_ms_per_frame": seconds * 1e3 / len(frames),
                     "mb_per_frame": size_bytes / 1e6 / len(frames)})
    return {"frames": len(frames), "fields_only_ms_per_frame": base * 1e3 / len(frames),
            "rows": rows}


def markdown(result: dict) -> list[str]:
    maps = result.get("wrinkle_maps")
    if not maps:
        return []
    lines = ["", "## Wrinkle maps (`bake --maps normal,height`)", "",
             f"The shirt, {maps['frames']} frames baked in one process; the wave fields alone "
             f"take {maps['fields_only_ms_per_frame']:.0f} ms a frame. Map time = (bake with "
             "maps - bake without) per frame: UV-space rasterisation of the wave blend, "
             "padding, readback, and the 16-bit PNG normal and float EXR height encodes "
             "(overlapped with the next frame).", "",
             "| map size | map ms per frame | whole bake ms per frame | MB of maps per frame |",
             "|---|---|---|---|"]
    for row in maps["rows"]:
        lines.append(f"| {row['size']}² | {row['ms_per_frame']:.0f} | "
                     f"{row['total_ms_per_frame']:.0f} | {row['mb_per_frame']:.2f} |")
    return lines
