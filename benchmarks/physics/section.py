"""Cross-sections of a converged curtain beside usdwrinkle's bake of it at matched W
(issue 55: why the curtains' folds stand taller than the referee's at matched W).

    python -m benchmarks.physics.section [--shot curtain-cotton] [--cache .physics-cache]
                                         [--out docs/images/physics_section_cotton.png]

For the end of each phase from 16% on, one horizontal line of the curtain at mid-height,
seen from above (the push across, the curtain's normal up): the simulation (black), its
low-pass, which is usdwrinkle's coarse mesh (blue), and usdwrinkle's displaced mesh at the
width matched to the simulation's mean wavelength (red), at the same scale. Prints per
phase, over the inner zone's lines: the simulated line's length over its low-pass's, the
share of it that runs backwards (overhanging folds: a height field cannot draw them), and
the RMS of each one's distance from the low-pass. Needs .venv-newton's cached simulation
(referee.py); about 10 s here (two bakes of the 1 cm curtain).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .coarse import lowpass
from .oracle import per_phase, zones
from .referee import (
    CONVERGED,
    ROOT,
    SWEEP,
    bake_on,
    cloth_attributes,
    matched_width,
    referee_grid,
    referee_pair,
)

#: the phases drawn, one band each
PHASES = ("push to 16%", "push to 32%", "push to 48%")
#: the curtain's line drawn (share of its height from the rail)
LINE = 0.5
#: pixels: the image's width, and each band's height
WIDTH, BAND = 960, 170


def line_stats(sim_line: np.ndarray, low_line: np.ndarray, ours_line: np.ndarray) -> dict:
    """One phase's lines (lines, points, 3): length over the low-pass's, the backward
    share of the simulated length, the RMS distances from the low-pass."""
    seg = np.diff(sim_line, axis=1)
    tangent = np.diff(low_line, axis=1)
    low_length = np.linalg.norm(tangent, axis=-1)
    tangent /= low_length[..., None] + 1e-30
    length = np.linalg.norm(seg, axis=-1)
    back = (seg * tangent).sum(-1) < 0.0
    return {"length": float(length.sum() / low_length.sum()),
            "overhang": float(length[back].sum() / length.sum()),
            "sim rms": float(np.sqrt(np.mean(np.sum((sim_line - low_line) ** 2, -1)))),
            "ours rms": float(np.sqrt(np.mean(np.sum((ours_line - low_line) ** 2, -1))))}


def draw(path: Path, bands: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]]) -> None:
    """Each band: the three lines (points, 3), x across and y out of the curtain."""
    import OpenImageIO as oiio

    img = np.ones((BAND * len(bands), WIDTH, 3), np.float32)
    for index, (_, sim_line, low_line, ours_line) in enumerate(bands):
        x0, x1 = sim_line[:, 0].min(), sim_line[:, 0].max()
        scale = (WIDTH - 20) / (x1 - x0)
        middle = BAND * index + BAND / 2
        y_mid = low_line[:, 1].mean()
        for line, colour in ((low_line, (0.55, 0.6, 1.0)), (ours_line, (0.85, 0.1, 0.1)),
                             (sim_line, (0.0, 0.0, 0.0))):
            steps = np.linspace(0.0, 1.0, 24)[:, None, None]
            dense = (line[:-1][None] * (1 - steps) + line[1:][None] * steps).reshape(-1, 3)
            px = np.round(10 + (dense[:, 0] - x0) * scale).astype(int)
            py = np.round(middle - (dense[:, 1] - y_mid) * scale).astype(int)
            keep = (px >= 0) & (px < WIDTH) & (py >= BAND * index) & (py < BAND * (index + 1))
            for dy in (0, 1):
                img[np.clip(py[keep] + dy, 0, len(img) - 1), px[keep]] = colour
        img[BAND * (index + 1) - 1] = 0.8
    buf = oiio.ImageBuf(oiio.ImageSpec(WIDTH, len(img), 3, oiio.UINT8))
    buf.set_pixels(oiio.ROI(), img)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf.write(str(path))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.section",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--shot", default="curtain-cotton",
                        choices=[name for name in SWEEP if name.startswith("curtain")])
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    out = args.out or ROOT / "docs" / "images" / \
        f"physics_section_{args.shot.split('-')[-1]}.png"
    grid = referee_grid(args.shot, True)
    # baked as the converged table bakes it (referee.sweep_row): on the 1 cm grid, read
    # back at the simulation's own points
    sim, fine = referee_pair(args.shot, args.cache, grid, CONVERGED[1])
    shot = sim.shot
    cloth = cloth_attributes(shot)
    default, _ = bake_on(sim, fine, "default", None, cloth)
    width = matched_width(shot, per_phase(sim, default))
    ours, _ = bake_on(sim, fine, "matched", width, cloth)
    inner = zones(shot)["all"].reshape(shot.rows, shot.cols)
    rows = np.flatnonzero(inner.any(axis=1))
    cols = np.flatnonzero(inner.any(axis=0))
    line = rows[int(round(LINE * (len(rows) - 1)))]
    bands = []
    print(f"{args.shot} ({100 * grid:g} cm grid): matched W {100 * width:.1f} cm")
    for phase in PHASES:
        frame = min(shot.phases[phase][1], shot.frames - 1)
        grids = [p.reshape(shot.rows, shot.cols, 3)[rows][:, cols] for p in (
            sim.points[frame], lowpass(shot, sim.points[frame:frame + 1])[0],
            ours.points[frame])]
        stats = line_stats(*grids)
        print(f"  {phase}: length over the low-pass's {stats['length']:.2f}, overhanging "
              f"{100 * stats['overhang']:.1f}%, RMS distance from the low-pass: sim "
              f"{1000 * stats['sim rms']:.1f} mm, ours {1000 * stats['ours rms']:.1f} mm")
        at = int(np.flatnonzero(rows == line)[0])
        bands.append((phase, *(g[at] for g in grids)))
    draw(out, bands)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
