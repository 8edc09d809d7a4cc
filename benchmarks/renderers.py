"""Wrinkles for other renderers: what ``bake --maps`` and ``bake --geometry`` cost.

The shirt sample, baked in one process with the wave fields only, then with normal and
height maps at each size; the map time per frame is the difference per frame (the GPU
rasterisation in UV space, padding, readback and the overlapped encode), and the files
each frame adds are summed. The same difference for ``--geometry`` (the survey of the
shot, the subdivision, the GPU evaluation and the layer) gives fine points per second,
and the .usdc layer's growth per frame its size.
"""
from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

SHIRT = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"


def _bake_seconds(ctx, frames, maps=None, geometry=None, stage=SHIRT,
                  all_meshes=False) -> tuple[float, int, int, dict]:
    """(seconds of one bake, bytes of map files written, bytes of the .usdc layer, the
    layer's usdwrinkle metadata)."""
    from pxr import Sdf

    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.frameloop import BakeRequest, bake_layer

    engine = WrinkleEngine(str(stage), ctx=ctx, use_baked=False,
                           all_meshes=all_meshes)
    try:
        with tempfile.TemporaryDirectory() as folder:
            layer = os.path.join(folder, "bench.usdc")
            started = time.perf_counter()
            bake_layer(engine, BakeRequest(str(stage), layer, tuple(frames), "bench",
                                           maps=maps, geometry=geometry))
            seconds = time.perf_counter() - started
            size = sum(p.stat().st_size for p in Path(folder).rglob("*.png")) + \
                sum(p.stat().st_size for p in Path(folder).rglob("*.exr"))
            layer_size = os.path.getsize(layer)
            meta = dict(Sdf.Layer.FindOrOpen(layer).customLayerData["usdwrinkle"])
    finally:
        engine.release()
    return seconds, size, layer_size, meta


def wrinkle_maps(quick: bool, ctx) -> dict:
    from usdwrinkle.maps.bake import MapOptions

    frames = [float(f) for f in range(1, 7 if quick else 25)]
    sizes = (256, 512) if quick else (1024, 2048)
    base = _bake_seconds(ctx, frames)[0]
    rows = []
    sets = MapOptions().sets
    for size in sizes:
        options = MapOptions(kinds=("normal", "height"), size=size)
        seconds, size_bytes, _, _ = _bake_seconds(ctx, frames, options)
        rows.append({"size": size, "seconds": seconds,
                     "ms_per_frame": (seconds - base) * 1e3 / len(frames),
                     "total_ms_per_frame": seconds * 1e3 / len(frames),
                     "mb_per_frame": size_bytes / 1e6 / len(frames)})
    return {"frames": len(frames), "fields_only_ms_per_frame": base * 1e3 / len(frames),
            "rows": rows, "sets": [f"{s.purpose}: {s.tangent_space}, {s.layout or 'asset'}"
                                   for s in sets]}


def displaced_geometry(quick: bool, ctx, corpus: Path | None) -> dict:
    from usdwrinkle.geometry.bake import GeometryOptions

    cases = [("shirt", SHIRT, False, [float(f) for f in range(1, 7 if quick else 25)])]
    cesium = corpus / "usd-wg" / "CesiumMan.usdz" if corpus else None
    if cesium is not None and cesium.is_file():
        cases.append(("CesiumMan", cesium, True,
                      [float(f) for f in range(1, 7 if quick else 49)]))
    rows = []
    for name, stage, all_meshes, frames in cases:
        base, _, base_layer, _ = _bake_seconds(ctx, frames, stage=stage,
                                               all_meshes=all_meshes)
        for levels in ((2, None) if quick else (3, None)):
            seconds, _, layer, meta = _bake_seconds(ctx, frames,
                                                    geometry=GeometryOptions(levels),
                                                    stage=stage, all_meshes=all_meshes)
            count = int(meta["geometry"]["finePoints"])
            used = sorted({p.split("=")[-1] for p in meta["geometry"]["levels"].split(",")})
            extra = max(seconds - base, 1e-9)
            rows.append({"case": name, "frames": len(frames), "levels": ",".join(used),
                         "fine_points": count, "seconds": seconds,
                         "geometry_ms_per_frame": extra * 1e3 / len(frames),
                         "points_per_second": count * len(frames) / extra,
                         "layer_mb_per_frame": (layer - base_layer) / 1e6 / len(frames),
                         "default_levels": levels is None})
    return {"rows": rows}


def markdown(result: dict) -> list[str]:
    maps = result.get("wrinkle_maps")
    lines = []
    if maps:
        lines += _maps_markdown(maps)
    geometry = result.get("displaced_geometry")
    if geometry:
        lines += _geometry_markdown(geometry)
    return lines


def _maps_markdown(maps: dict) -> list[str]:
    lines = ["", "## Wrinkle maps (`bake --maps normal,height`)", "",
             f"The shirt, {maps['frames']} frames baked in one process; the wave fields alone "
             f"take {maps['fields_only_ms_per_frame']:.0f} ms a frame. " +
             (f"The bake's default map sets ({'; '.join(maps['sets'])}), each a normal and a "
              "height map per frame. " if "sets" in maps else "") + "Map time = (bake with "
             "maps - bake without) per frame: UV-space rasterisation of the wave blend, "
             "padding, readback, and the 16-bit PNG normal and float EXR height encodes "
             "(overlapped with the next frame).", "",
             "| map size | map ms per frame | whole bake ms per frame | MB of maps per frame |",
             "|---|---|---|---|"]
    for row in maps["rows"]:
        lines.append(f"| {row['size']}² | {row['ms_per_frame']:.0f} | "
                     f"{row['total_ms_per_frame']:.0f} | {row['mb_per_frame']:.2f} |")
    return lines


def _geometry_markdown(geometry: dict) -> list[str]:
    lines = ["", "## Displaced geometry (`bake --geometry`)", "",
             "Geometry time = (bake with `--geometry` - bake without) over the frames: with "
             "the default levels it includes the survey of the shot (every frame computed once "
             "more), the subdivision, the GPU evaluation at every fine vertex, the read-back "
             "and the layer's time samples; the layer is .usdc (points and normals, float32).",
             "", "| case | frames | levels | fine points | geometry ms per frame | "
             "fine points per second | layer MB per frame |", "|---|---|---|---|---|---|---|"]
    for row in geometry["rows"]:
        levels = f"{row['levels']} (default)" if row["default_levels"] else row["levels"]
        lines.append(f"| {row['case']} | {row['frames']} | {levels} | "
                     f"{row['fine_points']:,} | {row['geometry_ms_per_frame']:.0f} | "
                     f"{row['points_per_second'] / 1e6:.2f} M | "
                     f"{row['layer_mb_per_frame']:.2f} |")
    return lines
