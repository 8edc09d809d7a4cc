"""Length restoration of the displaced geometry (``bake --geometry``), against the
derivation in docs/method.md.

    python -m benchmarks.lengths [--write docs/method.md]

For each profile preset and compression r, a sheet compressed uniformly by r along x is
baked with ``--geometry --levels 3``; along its middle row the fine mesh's height is the
plane wave (amplitude, wavelength), and its arc length over the whole wavelengths that
fit inside 80% of the sheet, divided by their rest length, is the measured ratio; the
fold law restores the length exactly for every profile (folds.slope_table), so the
derived ratio is 1. The shirt's inner elbow line (rest angle 0 around the sleeve, from
1.0 to 2.0 along it, frame 24, default levels) gives the ratio on a real shot. ``--write``
replaces the table between the markers in docs/method.md.
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np

from .blocks import add_write_option, emit, markers

ROOT = Path(__file__).resolve().parents[1]
SHIRT = ROOT / "sample_stages" / "shirt.usda"
WIDTH = 0.3
RATIOS = (0.5, 0.7, 0.9)
LEVELS = 3
BEGIN, END = markers("lengths")


def _bake(source: str, layer: str, *args: str) -> None:
    from usdwrinkle.cli.main import main

    code = main(["bake", source, layer, "--quiet", "--geometry", *args])
    if code:
        raise SystemExit(f"usdwrinkle bake {source} failed ({code})")


def sheet_lengths(preset: str, ratio: float, folder: str, levels: int | None = LEVELS,
                  *bake_args: str) -> dict:
    """Bake the compressed sheet with ``preset`` and measure its fine mesh's middle row
    (``levels`` None: the bake's default levels; ``bake_args`` more of bake's flags)."""
    from pxr import Usd, UsdGeom

    from usdwrinkle.authoring.api import WrinkleAPI
    from usdwrinkle.authoring.builders import grid_sheet, point_cache_stage
    from usdwrinkle.geometry.measure import length_ratio_along, plane_wave
    from usdwrinkle.method.folds import (
        excess_length,
        material_wavelength,
        profile_slope,
        slope_table,
    )
    from usdwrinkle.method.profiles import profile_preset

    rest, counts, indices = grid_sheet(31, 31, 2.0)
    posed = rest * np.array([ratio, 1, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=WIDTH)
    WrinkleAPI(stage.GetPrimAtPath("/Sheet")).set_profile(profile_preset(preset))
    name = f"{preset}_{ratio:g}"
    source = os.path.join(folder, f"sheet_{name}.usda")
    layer = os.path.join(folder, f"sheet_{name}_geometry.usdc")
    stage.GetRootLayer().Export(source)
    _bake(source, layer, *(() if levels is None else ("--levels", str(levels))), *bake_args)
    baked = Usd.Stage.Open(layer)  # held: its prims die with it
    fine = UsdGeom.Mesh(baked.GetPrimAtPath("/Sheet_wrinkled"))
    points = np.asarray(fine.GetPointsAttr().Get(1), np.float64)
    row = np.abs(points[:, 1]) < 1e-6                 # the middle row, y = 0
    x, z = points[row, 0], points[row, 2]
    inner = np.abs(x) < 0.8 * ratio                   # away from the free edges
    amplitude, wavelength = plane_wave(x[inner], z[inner])
    rho = excess_length(ratio, ratio, 0.0)           # the analytic sheet authors slack 0
    material = float(material_wavelength(WIDTH, rho))
    posed = ratio * material
    periods = int(2 * 0.8 * ratio / posed)            # whole waves away from the edges
    start = -0.5 * periods * posed
    return {"preset": preset, "ratio": ratio, "amplitude": amplitude,
            "expected_amplitude": float(profile_slope(slope_table(profile_preset(preset)), rho)
                                        * posed / (2 * np.pi)),
            "wavelength": wavelength, "expected_wavelength": posed,
            "measured": length_ratio_along(x, z, ratio, material, start, periods),
            "derived": 1.0}


def elbow(folder: str) -> dict:
    """The shirt's inner elbow line at frame 24: rest, coarse posed and displaced lengths."""
    from pxr import Usd, UsdGeom

    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.geometry.measure import polyline_length
    from usdwrinkle.geometry.subdivide import subdivide

    layer = os.path.join(folder, "shirt_geometry.usdc")
    _bake(str(SHIRT), layer, "--with-points")
    stage = Usd.Stage.Open(layer)
    levels = int(stage.GetRootLayer().customLayerData["usdwrinkle"]["geometry"]["levels"]
                 .split("=")[-1])
    engine = WrinkleEngine(str(SHIRT))
    try:
        record = engine.meshes["/World/Arm/Sleeve"]
    finally:
        engine.release()
    fine = subdivide(record.rest_points, record.topology.triangles, levels)
    line = (np.abs(fine.points[:, 2]) < 1e-6) & (fine.points[:, 1] > 0) & \
        (fine.points[:, 0] >= 1.0) & (fine.points[:, 0] <= 2.0)
    order = np.argsort(fine.points[line, 0])
    displaced = np.asarray(UsdGeom.Mesh(stage.GetPrimAtPath("/World/Arm/Sleeve_wrinkled"))
                           .GetPointsAttr().Get(24), np.float64)[line][order]
    coarse_posed = np.asarray(UsdGeom.Mesh(stage.GetPrimAtPath("/World/Arm/Sleeve"))
                              .GetPointsAttr().Get(24), np.float64)
    corners = coarse_posed[record.topology.triangles[fine.vertex_triangle[line]]]
    flat = np.einsum("vk,vkd->vd", fine.vertex_bary[line], corners)[order]
    rest_length = polyline_length(fine.points[line][order].astype(np.float64))
    return {"levels": levels, "rest": rest_length,
            "coarse": polyline_length(flat) / rest_length,
            "displaced": polyline_length(displaced) / rest_length}


def table(rows: list[dict], shirt: dict) -> str:
    lines = [BEGIN, "",
             "Made by `python -m benchmarks.lengths --write docs/method.md` (sheet: W = 0.3, "
             f"--levels {LEVELS}, the whole wavelengths of the middle row inside 80% of the "
             "sheet).", "",
             "| profile | r | derived L/L0 | measured L/L0 | amplitude / law | "
             "wavelength / r L |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['preset']} | {r['ratio']:g} | {r['derived']:.4f} | "
                     f"{r['measured']:.4f} | {r['amplitude'] / r['expected_amplitude']:.4f} | "
                     f"{r['wavelength'] / r['expected_wavelength']:.4f} |")
    lines += ["", f"The shirt's inner elbow at frame 24 (fold profile, {shirt['levels']} "
              f"levels): the coarse mesh keeps {shirt['coarse']:.3f} of the line's rest "
              f"length ({shirt['rest']:.3f}); the displaced mesh {shirt['displaced']:.3f}.",
              "", END]
    return "\n".join(lines)


def main(argv=None) -> int:
    import argparse

    from usdwrinkle.method.profiles import PRESETS

    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.lengths",
        description="Each profile's length on a baked sheet, and the shirt's inner elbow "
                    "line (the module's docstring says how).")
    add_write_option(parser, "lengths", "docs/method.md")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    with tempfile.TemporaryDirectory() as folder:
        rows = [sheet_lengths(preset, ratio, folder) for preset in PRESETS for ratio in RATIOS]
        shirt = elbow(folder)
    text = table(rows, shirt)
    emit(args.write, "lengths", text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
