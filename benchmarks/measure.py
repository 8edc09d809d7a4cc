"""Measurements of the real pipeline (scene delegate -> render delegate -> passes): the
paper's cases, scaling, baselines, end to end, triangulation. No fast path exists for
the benchmark. Per-pass times come from GL timer queries where the driver gives
plausible ones, else from the wall clock between glFinish calls (Mesa's llvmpipe
answers timer queries with 1 ns); the source is recorded per pass."""
from __future__ import annotations

import math
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from pxr import Usd, UsdGeom, Vt

from usdwrinkle import __version__
from usdwrinkle.process._resources import resource_dir

from .paper import PAPER
from .stages import sleeve_stage

PASSES = ("skin", "crush", "relax", "draw", "readback")


def _median(values):
    return float(statistics.median(values)) if values else float("nan")


def measure_frames(engines, width, height, frames, warmup=3, repeat=1):
    """Per engine (a list of (engine, wrinkles)): median per-pass times (ms), median wall
    time per frame (ms), the time sources and the frame count.

    The engines take turns frame by frame, so that drift in the machine's speed (large on
    shared VMs) falls on all of them alike; each keeps its own phase history.
    """
    for frame in frames[:warmup]:
        for engine, wrinkles in engines:
            engine.render_frame(frame, width, height, wrinkles, samples=1)
    results = [([], {name: [] for name in PASSES + ("usd_read", "sync")}, {})
               for _ in engines]
    for _ in range(repeat):
        for frame in frames[warmup:]:
            for (engine, wrinkles), (walls, passes, sources) in zip(engines, results, strict=True):
                ctx = engine.ctx
                ctx.finish()
                started = time.perf_counter()
                engine.render_frame(frame, width, height, wrinkles, samples=1)
                walls.append((time.perf_counter() - started) * 1e3)
                for name in passes:
                    if name in engine.last_timings:
                        passes[name].append(engine.last_timings[name])
                sources.update({k: v for k, v in engine.last_timings.items()
                                if k.endswith(".source")})
    return [({name: _median(v) for name, v in passes.items() if v}, _median(walls), sources,
             len(walls)) for walls, passes, sources in results]


def size_for(pixels: int, aspect: float) -> tuple[int, int]:
    width = max(16, int(round(math.sqrt(pixels * aspect))))
    return width, max(16, int(round(width / aspect)))


def paper_table(quick: bool, ctx) -> list[dict]:
    from usdwrinkle.engine import WrinkleEngine

    samples = resource_dir("sample_stages")
    rows = []
    for name, vertices, pixels, paper, unit in PAPER:
        if name in ("shirt", "zeppelin", "curtain"):
            stage = str(samples / f"{name}.usda")
        else:
            stage = sleeve_stage(vertices)
        engine = WrinkleEngine(stage, ctx=ctx, profile=True)
        plain = WrinkleEngine(stage, ctx=ctx, profile=True)
        try:
            aspect = engine.camera_aspect(1.0) or 1.0
            width, height = size_for(pixels // (16 if quick else 1), aspect)
            frames = [float(f) for f in range(1, 9 if quick else 25)]
            (passes, wall, sources, count), (_, plain_wall, _, _) = measure_frames(
                [(engine, True), (plain, False)], width, height, frames)
            actual_vertices = sum(len(r.rest_points) for r in engine.meshes.values())
        finally:
            engine.release()
            plain.release()
        gpu = sum(passes.get(p, 0.0) for p in ("skin", "crush", "relax", "draw"))
        rows.append({
            "case": name, "vertices": actual_vertices, "pixels": width * height,
            "width": width, "height": height, "frames_measured": count,
            "pass_ms": passes, "pass_sources": sources,
            "gpu_ms": gpu, "gpu_fps": 1e3 / gpu if gpu > 0 else float("inf"),
            "wall_ms": wall, "wall_fps": 1e3 / wall, "plain_wall_ms": plain_wall,
            "wrinkle_overhead": wall / plain_wall,
            "paper": paper, "paper_unit": unit,
            "paper_ms": 1e3 / paper if unit == "fps" else paper,
        })
    return rows


def linear_fit(x, y) -> dict:
    x, y = np.asarray(x, float), np.asarray(y, float)
    slope, intercept = np.polyfit(x, y, 1)
    predicted = slope * x + intercept
    ss_res = float(np.sum((y - predicted) ** 2))
    ss_tot = float(np.sum((y - y.mean()) ** 2)) or 1e-30
    return {"slope": float(slope), "intercept": float(intercept), "r2": 1 - ss_res / ss_tot}


def scaling(quick: bool, ctx) -> dict:
    from usdwrinkle.engine import WrinkleEngine

    vertex_sizes = [1_000, 10_000] if quick else [1_000, 10_000, 100_000, 1_000_000]
    pixel_sizes = [128, 256] if quick else [128, 256, 512, 1024, 2048]
    frames = [float(f) for f in range(1, 6 if quick else 10)]
    by_vertices = []
    for vertices in vertex_sizes:
        engine = WrinkleEngine(sleeve_stage(vertices), ctx=ctx, profile=True)
        try:
            n = len(next(iter(engine.meshes.values())).rest_points)
            (passes, wall, _, _), = measure_frames([(engine, True)], 512, 512, frames, warmup=2)
        finally:
            engine.release()
        compute = sum(passes.get(p, 0.0) for p in ("skin", "crush", "relax"))
        by_vertices.append({"vertices": n, "compute_ms": compute, "draw_ms": passes.get("draw"),
                            "wall_ms": wall, "per_vertex_ns": compute * 1e6 / n,
                            "pass_ms": passes})
    by_pixels = []
    engine = WrinkleEngine(sleeve_stage(5_000), ctx=ctx, profile=True)
    try:
        for side in pixel_sizes:
            (passes, wall, _, _), = measure_frames([(engine, True)], side, side, frames,
                                                     warmup=2)
            draw = passes.get("draw", 0.0)
            by_pixels.append({"pixels": side * side, "side": side, "draw_ms": draw,
                              "readback_ms": passes.get("readback"), "wall_ms": wall,
                              "per_pixel_ns": draw * 1e6 / (side * side), "pass_ms": passes})
    finally:
        engine.release()
    return {"vertices": by_vertices, "pixels": by_pixels,
            "vertex_fit": linear_fit([r["vertices"] for r in by_vertices],
                                     [r["compute_ms"] for r in by_vertices]),
            "pixel_fit": linear_fit([r["pixels"] for r in by_pixels],
                                    [r["draw_ms"] for r in by_pixels])}


def skin_baseline(quick: bool, ctx) -> list[dict]:
    """UsdSkel's C++ ComputeSkinnedPoints against our skin pass, on the same skinned mesh."""
    from usdwrinkle.authoring.builders import usdskel_queries
    from usdwrinkle.engine import WrinkleEngine

    rows = []
    for vertices in ([50_000] if quick else [50_000, 1_000_000]):
        stage = sleeve_stage(vertices)
        engine = WrinkleEngine(stage, ctx=ctx, profile=True)
        try:
            path = next(iter(engine.meshes))
            skel_query, skinning_query = usdskel_queries(stage, path)
            points = UsdGeom.Mesh(stage.GetPrimAtPath(path)).GetPointsAttr().Get()
            cpu, gpu, gpu_read = [], [], []
            engine.compute_frame(1.0, wrinkles=False)  # builds the GPU resources
            for frame in range(2, 8 if quick else 12):
                t = Usd.TimeCode(frame)
                started = time.perf_counter()
                xforms = skel_query.ComputeSkinningTransforms(t)
                skinned = Vt.Vec3fArray(points)
                skinning_query.ComputeSkinnedPoints(xforms, skinned, t)
                cpu.append((time.perf_counter() - started) * 1e3)
                engine.compute_frame(float(frame), wrinkles=False)  # syncs the frame
                ctx.finish()
                started = time.perf_counter()
                engine.debug.run_skin(path)
                ctx.finish()
                gpu.append((time.perf_counter() - started) * 1e3)
                engine.mesh_resources(path).posed_points.read()
                gpu_read.append((time.perf_counter() - started) * 1e3)
            n = len(points)
        finally:
            engine.release()
        rows.append({"vertices": n, "usdskel_cpu_ms": _median(cpu), "gpu_skin_ms": _median(gpu),
                     "gpu_skin_with_readback_ms": _median(gpu_read),
                     "speedup": _median(cpu) / _median(gpu)})
    return rows


def numpy_baseline(quick: bool, ctx) -> dict:
    """A vectorised numpy crush + relax against the GPU passes, on the same frame (medians:
    nine GPU frames with phase history, three numpy runs)."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.reference.crush import crush
    from usdwrinkle.reference.relax import relax

    vertices = 10_000 if quick else 50_000
    engine = WrinkleEngine(sleeve_stage(vertices), ctx=ctx, profile=True)
    try:
        path = next(iter(engine.meshes))
        record = engine.meshes[path]
        engine.compute_frame(1.0)
        gpu_times = []
        for frame in range(2, 11):
            engine.compute_frame(float(frame))
            timings = engine.last_timings
            gpu_times.append(timings["crush"] + timings["relax"])
        fields = engine.read_fields(path)
        iterations = record.params.relax_iterations
        numpy_times = []
        for _ in range(3):
            started = time.perf_counter()
            reference = crush(record.rest_points, fields.points, record.topology,
                              record.params.q, record.params.width,
                              record.params.amplitude_scale)
            relax(fields.points, reference["wave_vector"], reference["amplitude"],
                  reference["phase"], record.topology, iterations)
            numpy_times.append((time.perf_counter() - started) * 1e3)
    finally:
        engine.release()
    gpu_ms = _median(gpu_times)
    numpy_ms = _median(numpy_times)
    return {"vertices": len(record.rest_points), "relax_iterations": iterations,
            "numpy_ms": numpy_ms, "gpu_ms": gpu_ms, "speedup": numpy_ms / gpu_ms}


def end_to_end(quick: bool, ctx, corpus: Path | None) -> dict:
    """CesiumMan to EXR, with and without wrinkles: time per frame by stage."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.outputs.images import write_image

    path = corpus / "usd-wg" / "CesiumMan.usdz" if corpus else None
    if path is None or not path.is_file():
        return {"skipped": f"CesiumMan.usdz not found (looked in {corpus})"}
    width, height = (320, 180) if quick else (960, 540)
    frames = [float(f) for f in range(1, 7 if quick else 49)]
    out = {}
    for label, wrinkles in (("wrinkles", True), ("no_wrinkles", False)):
        engine = WrinkleEngine(str(path), all_meshes=True, ctx=ctx, profile=True)
        stages = {k: [] for k in ("usd_read", "upload", "gpu", "readback", "encode", "total")}
        try:
            with tempfile.TemporaryDirectory() as folder:
                for frame in frames:
                    started = time.perf_counter()
                    buffers = engine.render_frame(frame, width, height, wrinkles)
                    rendered = time.perf_counter()
                    write_image(os.path.join(folder, f"c.{int(frame):04d}.exr"), buffers)
                    done = time.perf_counter()
                    t = engine.last_timings
                    stages["usd_read"].append(t.get("usd_read", 0.0))
                    stages["upload"].append(t.get("sync", 0.0))
                    stages["gpu"].append(sum(t.get(p, 0.0) for p in
                                             ("skin", "crush", "relax", "draw")))
                    stages["readback"].append(t.get("readback", 0.0))
                    stages["encode"].append((done - rendered) * 1e3)
                    stages["total"].append((done - started) * 1e3)
        finally:
            engine.release()
        out[label] = {k: float(np.mean(v[1:] if len(v) > 1 else v)) for k, v in stages.items()}
    out["ratio"] = out["wrinkles"]["total"] / out["no_wrinkles"]["total"]
    out.update({"frames": len(frames), "width": width, "height": height})
    return out


def triangulation(quick: bool) -> dict:
    """build_topology (triangulation + adjacency) on hostile sizes: one concave polygon of
    10,000 corners (a star: every other corner reflex) and a grid of 1 M quads."""
    from usdwrinkle.scene.topology import build_topology

    corners = 10_000
    theta = np.arange(corners) * (2 * np.pi / corners)
    radius = np.where(np.arange(corners) % 2 == 0, 1.0, 0.5)
    star = np.stack([radius * np.cos(theta), radius * np.sin(theta), np.zeros(corners)], 1)
    side = 317 if quick else 1001  # 100 k or 1 M quads
    gx, gy = np.meshgrid(np.arange(side, dtype=np.float64), np.arange(side, dtype=np.float64))
    grid = np.stack([gx.ravel(), gy.ravel(), np.zeros(side * side)], 1)
    i = np.arange(side - 1)
    a = (i[:, None] * side + i[None, :]).ravel()
    quads = np.stack([a, a + 1, a + side + 1, a + side], 1)
    rows = {}
    for key, counts, indices, points in (
            ("polygon", [corners], np.arange(corners), star),
            ("quads", np.full(len(quads), 4), quads.ravel(), grid)):
        times = []
        for _ in range(1 if quick else 3):
            started = time.perf_counter()
            topology = build_topology(counts, indices, points)
            times.append((time.perf_counter() - started) * 1e3)
        rows[key] = {"faces": len(counts), "points": len(points),
                     "triangles": len(topology.triangles), "ms": _median(times)}
    return rows


def machine(ctx) -> dict:
    cpu = platform.processor() or ""
    try:
        with open("/proc/cpuinfo") as handle:
            for line in handle:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"platform": platform.platform(), "python": platform.python_version(), "cpu": cpu,
            "cores": os.cpu_count(), "gl_renderer": ctx.info.get("GL_RENDERER", "?"),
            "gl_version": ctx.info.get("GL_VERSION", "?"), "usdwrinkle": __version__}

