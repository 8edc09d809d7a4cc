"""The markdown report: the fixed text (the paper's figures and the targets) lives in
the data table of paper.py; the rest is made from a run's results."""
from __future__ import annotations

import json
from pathlib import Path

from .beyond import markdown as beyond_report
from .cpu_nodes import markdown as cpu_nodes_report
from .paper import paper_figure
from .renderers import markdown as renderers_report


def history(folder: Path) -> list[dict]:
    """Key figures of the labelled runs kept in ``folder`` (before/after each change)."""
    rows = []
    for path in sorted(folder.glob("*.json")) if folder.is_dir() else []:
        data = json.loads(path.read_text())
        table = {r["case"]: r for r in data.get("paper_table", [])}
        b = table.get("B", {})
        e2e = data.get("end_to_end", {})
        rows.append({
            "file": path.name, "label": data.get("label", path.stem),
            "quick": data.get("quick"),
            "shirt_wall_ms": table.get("shirt", {}).get("wall_ms"),
            "shirt_overhead": table.get("shirt", {}).get("wrinkle_overhead"),
            "B_crush_ms": b.get("pass_ms", {}).get("crush"),
            "B_relax_ms": b.get("pass_ms", {}).get("relax"),
            "B_wall_ms": b.get("wall_ms"),
            "numpy_speedup": data.get("numpy_baseline", {}).get("speedup"),
            "cesium_ratio": e2e.get("ratio"),
        })
    return rows


def targets(result: dict) -> list[dict]:
    rows = {r["case"]: r for r in result["paper_table"]}
    skin = result["skin_baseline"][-1]
    shirt_fps, b_ms = paper_figure("shirt"), paper_figure("B")  # the paper's figures
    out = [
        {"measure": "shirt", "target": f">= {shirt_fps:g} fps",
         "value": f"{rows['shirt']['wall_fps']:.0f} fps",
         "met": rows["shirt"]["wall_fps"] >= shirt_fps},
        {"measure": "case B", "target": f"<= {b_ms:g} ms",
         "value": f"{rows['B']['wall_ms']:.1f} ms", "met": rows["B"]["wall_ms"] <= b_ms},
        {"measure": "wrinkled / plain render (shirt)", "target": "<= 1.25x",
         "value": f"{rows['shirt']['wrinkle_overhead']:.2f}x",
         "met": rows["shirt"]["wrinkle_overhead"] <= 1.25},
        {"measure": f"GPU skin vs UsdSkel at {skin['vertices']:,} points",
         "target": "no slower", "value": _speed(skin["speedup"]),
         "met": skin["speedup"] >= 1.0},
        {"measure": "crush + relax vs numpy", "target": ">= 10x",
         "value": f"{result['numpy_baseline']['speedup']:.1f}x",
         "met": result["numpy_baseline"]["speedup"] >= 10},
    ]
    e2e = result["end_to_end"]
    if "ratio" in e2e:
        out.append({"measure": "CesiumMan with / without wrinkles", "target": "<= 1.3x",
                    "value": f"{e2e['ratio']:.2f}x", "met": e2e["ratio"] <= 1.3})
    peers = result.get("peers")
    if peers is not None:
        out.append({"measure": "usdwrinkle with wrinkles vs Storm's plain frames (CesiumMan "
                               "960x540, PNG)", "target": ">= 3x Storm's frame rate",
                    "value": f"{peers['lead']:.2f}x" if peers["ran"] else
                    f"not run: {peers['why']}", "met": peers["ran"] and peers["lead"] >= 3.0})
    from .paint import paint_targets

    out += paint_targets(result)
    return out


def markdown(result: dict) -> str:
    m = result["machine"]
    lines = ["# Benchmarks", "",
             f"Made by `{result['command']}` on {result['date']} (usdwrinkle {m['usdwrinkle']}).",
             "This file is the output of that command; do not edit it by hand.", "",
             f"- machine: {m['cpu']}, {m['cores']} cores; {m['platform']}",
             f"- GL: {m['gl_renderer']}; {m['gl_version']}",
             f"- mode: {'quick (reduced sizes)' if result['quick'] else 'full'}",
             "- times are medians per frame; per-pass times come from GL timer queries on a "
             "GPU, and from the wall clock between glFinish calls on a software rasteriser "
             "(llvmpipe's timer queries do not measure its work); `wall` is the whole per-frame "
             "pipeline "
             "(USD read, upload, the four passes, readback of every AOV), without file IO; "
             "one sample per pixel; the wrinkled and the plain render of a case alternate "
             "frame by frame (two engines), so that drift in the machine's speed falls on "
             "both", "",
             "## Targets", "", "| measure | target | measured | met |", "|---|---|---|---|"]
    for t in result["targets"]:
        lines.append(f"| {t['measure']} | {t['target']} | {t['value']} | "
                     f"{'yes' if t['met'] else 'no'} |")
    lines += ["", "## The paper's table", "",
              "| case | vertices | pixels | skin | crush | relax | draw | readback | GPU fps | "
              "wall | wall fps | plain wall | with/without | paper (2006 GPU) |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in result["paper_table"]:
        p = r["pass_ms"]
        paper = f"{r['paper']:g} {r['paper_unit']}"
        lines.append(
            f"| {r['case']} | {r['vertices']:,} | {r['pixels']:,} | {p.get('skin', 0):.2f} | "
            f"{p.get('crush', 0):.2f} | {p.get('relax', 0):.2f} | {p.get('draw', 0):.2f} | "
            f"{p.get('readback', 0):.2f} | {r['gpu_fps']:.0f} | {r['wall_ms']:.2f} ms | "
            f"{r['wall_fps']:.0f} | {r['plain_wall_ms']:.2f} ms | {r['wrinkle_overhead']:.2f}x | "
            f"{paper} |")
    s = result["scaling"]
    lines += ["", "## Scaling", "", "Vertices at 512x512 (skin + crush + relax):", "",
              "| vertices | compute ms | ns per vertex | draw ms | wall ms |",
              "|---|---|---|---|---|"]
    for r in s["vertices"]:
        lines.append(f"| {r['vertices']:,} | {r['compute_ms']:.2f} | {r['per_vertex_ns']:.1f} | "
                     f"{r['draw_ms']:.2f} | {r['wall_ms']:.2f} |")
    vf, pf = s["vertex_fit"], s["pixel_fit"]
    lines += ["", f"Linear fit: {vf['slope'] * 1e6:.1f} ns per vertex + {vf['intercept']:.2f} ms, "
              f"R² = {vf['r2']:.4f}.", "", "Pixels at about 5,000 vertices (draw pass):", "",
              "| pixels | draw ms | ns per pixel | readback ms | wall ms |",
              "|---|---|---|---|---|"]
    for r in s["pixels"]:
        lines.append(f"| {r['side']}² | {r['draw_ms']:.2f} | {r['per_pixel_ns']:.2f} | "
                     f"{r['readback_ms']:.2f} | {r['wall_ms']:.2f} |")
    lines += ["", f"Linear fit: {pf['slope'] * 1e6:.2f} ns per pixel + {pf['intercept']:.2f} ms, "
              f"R² = {pf['r2']:.4f}.", "", "## Baselines", "",
              "UsdSkel's C++ skinning (`ComputeSkinnedPoints`, with `ComputeSkinningTransforms`) "
              "against the GPU skin pass on the same mesh and frame:", "",
              "| points | UsdSkel CPU ms | GPU skin ms | GPU skin + readback ms | speed-up |",
              "|---|---|---|---|---|"]
    for r in result["skin_baseline"]:
        lines.append(f"| {r['vertices']:,} | {r['usdskel_cpu_ms']:.2f} | {r['gpu_skin_ms']:.2f} | "
                     f"{r['gpu_skin_with_readback_ms']:.2f} | {r['speedup']:.1f}x |")
    nb = result["numpy_baseline"]
    lines += ["", f"Vectorised numpy crush + relax ({nb['relax_iterations']} iterations) against "
              f"the GPU passes at {nb['vertices']:,} vertices: numpy {nb['numpy_ms']:.1f} ms, GPU "
              f"{nb['gpu_ms']:.2f} ms, {nb['speedup']:.1f}x.", "", "## End to end", ""]
    e2e = result["end_to_end"]
    if "skipped" in e2e:
        lines.append(f"Skipped: {e2e['skipped']}")
    else:
        lines += [f"CesiumMan.usdz, {e2e['frames']} frames at {e2e['width']}x{e2e['height']} "
                  "to EXR, `--all-meshes` (4 samples per pixel, as `render`), mean ms per frame "
                  "(the first frame, which builds the GPU resources, is left out):", "",
                  "| run | USD read | upload | GPU | readback | encode | total |",
                  "|---|---|---|---|---|---|---|"]
        for label in ("wrinkles", "no_wrinkles"):
            r = e2e[label]
            lines.append(f"| {label.replace('_', ' ')} | {_ms(r['usd_read'])} | "
                         f"{_ms(r['upload'])} | {_ms(r['gpu'])} | {_ms(r['readback'])} | "
                         f"{_ms(r['encode'])} | {_ms(r['total'])} |")
        lines.append(f"\nWith ÷ without wrinkles: {e2e['ratio']:.2f}x.")
    f = result.get("floors")
    if f:
        rows = {r["case"]: r for r in result["paper_table"]}
        shirt, b = rows["shirt"], rows["B"]
        lines += ["", "## What the rasteriser costs by itself", "",
                  "Measured in the same run, with no usdwrinkle code:", "",
                  f"- an empty compute dispatch: {f['empty_dispatch_ms']:.3f} ms "
                  "(each relax iteration is one dispatch);",
                  "- a 6-neighbour gather over 50,000 vertices (the memory pattern of crush "
                  f"and relax): {f['gather6_50k_ms']:.2f} ms from storage buffers, "
                  f"{f.get('gather6_50k_tables_ms', float('nan')):.2f} ms from tables "
                  "(texelFetch, what the passes use; Mesa 22's llvmpipe loads SSBO elements "
                  "lane by lane);",
                  f"- copying {f.get('copy_points', 0):,} points from one table to another, "
                  f"the least a skin pass does: {f.get('copy_points_ms', float('nan')):.2f} ms;",
                  "- reading back one 330 kpixel RGBA float target that was just drawn: "
                  f"{f['readback_330k_rgba32f_ms']:.2f} ms.", "",
                  "So on this machine: the shirt rendered plain, with no wrinkle pass at all, "
                  f"already takes {shirt['plain_wall_ms']:.1f} ms a frame "
                  f"({1e3 / shirt['plain_wall_ms']:.0f} fps) against the paper's 3.05 ms, and "
                  f"its wrinkled draw {shirt['pass_ms'].get('draw', 0):.1f} ms: at 330 kpixels "
                  "the rasteriser's fill and shading, shared by the plain render, set the "
                  f"frame rate. Case B's crush took {b['pass_ms'].get('crush', 0):.1f} ms and "
                  f"its relax {b['pass_ms'].get('relax', 0):.1f} ms (9 sweeps over the 1-ring), "
                  "while one bare 6-neighbour gather over as many vertices takes "
                  f"{f.get('gather6_50k_tables_ms', f['gather6_50k_ms']):.1f} ms here; its draw "
                  f"of 100 k triangles took {b['pass_ms'].get('draw', 0):.1f} ms. The paper's "
                  f"{paper_figure('B'):g} ms for all of case B is below what this software "
                  "rasteriser gives for "
                  "the memory traffic and triangle setup alone; on a GPU the same kernels are "
                  "bandwidth-trivial at these sizes."]
        skin = (result.get("skin_baseline") or [None])[-1]
        if skin and f.get("copy_points") == skin["vertices"] and "gather6_50k_tables_ms" in f:
            # the gather floor reads 12 texels per vertex (6 indices, 6 values)
            per_texel_ns = f["gather6_50k_tables_ms"] * 1e6 / (50_000 * 12)
            floor_ms = skin["vertices"] * 9 * per_texel_ns * 1e-6
            lines += ["", f"UsdSkel's C++ skinning of {skin['vertices']:,} points took "
                      f"{skin['usdskel_cpu_ms']:.1f} ms, the GPU skin pass "
                      f"{skin['gpu_skin_ms']:.1f} ms. Only copying as many points from one "
                      f"table to another takes {f['copy_points_ms']:.1f} ms here, and an LBS "
                      "point with two influences reads 9 texels (its rest point; per "
                      "influence one texel of joint index and weight and three matrix "
                      "columns): at the "
                      f"gather's {per_texel_ns:.1f} ns per texel that is {floor_ms:.0f} ms of "
                      "fetches alone. llvmpipe runs compute on the same two cores through a "
                      "per-texel fetch path, where UsdSkel runs a tight multithreaded loop "
                      "over contiguous arrays."]
        numpy_row = result.get("numpy_baseline") or {}
        if numpy_row:
            lines += ["", f"crush + relax against vectorised numpy at {numpy_row['vertices']:,} "
                      f"vertices: {numpy_row['speedup']:.1f}x. Both run on the same two CPU "
                      "cores; numpy pays a temporary array per step of the 1-ring sums, the "
                      "passes gather in registers."]
    from . import farm as farm_bench
    from .peers import markdown as peers_report
    lines += peers_report(result)
    lines += farm_bench.markdown(result)
    lines += cpu_nodes_report(result)
    lines += renderers_report(result)
    lines += beyond_report(result)
    from .paint import paint_markdown

    lines += paint_markdown(result)
    tri = result.get("triangulation")
    if tri:
        lines += ["", "## Triangulation of hostile meshes", "",
                  "`build_topology` (triangulation and adjacency) in one process, median of 3: "
                  "a concave star polygon of 10,000 corners (every other corner reflex; "
                  "ear-clipped by mapbox earcut) and a grid of quads (convexity tested "
                  "vectorised, then fanned). The pure-Python ear clipping that came before "
                  "took minutes on an 8,000-gon and never finished 5 M quads.", "",
                  "| mesh | faces | points | triangles | ms |", "|---|---|---|---|---|"]
        for key, label in (("polygon", "one concave polygon"), ("quads", "quad grid")):
            row = tri[key]
            lines.append(f"| {label} | {row['faces']:,} | {row['points']:,} | "
                         f"{row['triangles']:,} | {row['ms']:.0f} |")
    hist = result.get("history") or []
    if hist:
        lines += ["", "## Before and after each change", "",
                  "Labelled runs kept in docs/bench/ (quick mode: reduced sizes; compare rows "
                  "with each other, not with the tables above):", "",
                  "| run | shirt wall ms | shirt with/without | B crush ms | B relax ms | "
                  "B wall ms | numpy speed-up | CesiumMan with/without |",
                  "|---|---|---|---|---|---|---|---|"]

        def fmt(value, spec):
            return "-" if value is None else format(value, spec)

        for h in hist:
            lines.append(f"| {h['label']} | {fmt(h['shirt_wall_ms'], '.2f')} | "
                         f"{fmt(h['shirt_overhead'], '.2f')} | {fmt(h['B_crush_ms'], '.1f')} | "
                         f"{fmt(h['B_relax_ms'], '.1f')} | {fmt(h['B_wall_ms'], '.1f')} | "
                         f"{fmt(h['numpy_speedup'], '.1f')} | {fmt(h['cesium_ratio'], '.2f')} |")
    return "\n".join(lines) + "\n"


def _speed(speedup: float) -> str:
    """A speed ratio in words: 3.0x faster, or 0.3x (3.3x slower), never "0.3x faster"."""
    if speedup >= 1.0:
        return f"{speedup:.1f}x faster"
    return f"{1.0 / speedup:.1f}x slower" if speedup > 0 else "not measured"


def _ms(value: float) -> str:
    """A part of a frame's time, in ms. A part found by subtraction can come out a hair
    below zero on a noisy machine: that is shown as below the resolution, not negative."""
    return f"{value:.2f}" if value >= 0.005 else "< 0.01"

