"""Cross-sections of a converged curtain beside usdwrinkle's bake of it at matched W
(issue 55: why the curtains' folds stand taller than the referee's at matched W).

    python -m benchmarks.physics.section [--shot curtain-cotton] [--cache .physics-cache]
                                         [--out docs/images/physics_section_cotton.png]

For the end of each phase from 16% on, one horizontal line of the curtain at mid-height,
seen from above (the push across, the curtain's normal up): the simulation (black), its
low-pass, which is usdwrinkle's coarse mesh (blue), and usdwrinkle's displaced mesh at the
width matched to the simulation's mean wavelength (red), at the same scale. Prints per
phase, over the inner zone's lines, for each: the length over the low-pass's, the share
of it that runs backwards (overhanging folds: a height field cannot draw them), the RMS
distance from the low-pass, the out-of-plane travel, the waves a metre, and how much of
the length runs flat (within 30 degrees of the line) and steep (60-90), and the RMS over
a zigzag's of the same length and waves a metre: how each holds its length
(line_stats). Last, what overhanging folds would save (overhang_model) and what a height
field's profile can reach at the lines' lengths (profile_shape, box_shape). Needs
.venv-newton's cached simulation (referee.py); about 10 s here (two bakes of the 1 cm
curtain).
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from usdwrinkle.method.profiles import preset_at

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


def zigzag_rms(length: float) -> float:
    """The RMS height, per wavelength, of the zigzag that is ``length`` times as long as
    its wavelength: amplitude sqrt(length^2 - 1) / 4, RMS the amplitude over sqrt 3."""
    return float(np.sqrt(max(length ** 2 - 1.0, 0.0)) / 4.0 / np.sqrt(3.0))


def line_stats(sim_line: np.ndarray, low_line: np.ndarray, ours_line: np.ndarray) -> dict:
    """One phase's lines (lines, points, 3; y out of the curtain): for the simulation and
    for ours (keys "sim ..." and "ours ..."), the length over the low-pass's, the share of
    it that runs backwards along the low-pass (overhanging folds), the RMS distance from
    the low-pass, the out-of-plane travel (the summed |change| of the offset's y, over
    the low-pass's length), the waves per metre (half the offset's sign changes, over
    the low-pass's length), the RMS over a zigzag's of the same length and waves a metre
    ("shape"), and the shares of the length whose segments run within 30 degrees of the
    low-pass line ("flat") and between 60 and 90 ("steep")."""
    tangent = np.diff(low_line, axis=1)
    low_length = np.linalg.norm(tangent, axis=-1)
    tangent /= low_length[..., None] + 1e-30
    out = {}
    for name, line in (("sim", sim_line), ("ours", ours_line)):
        seg = np.diff(line, axis=1)
        length = np.linalg.norm(seg, axis=-1)
        along = (seg * tangent).sum(-1) / np.maximum(length, 1e-30)
        offset = (line - low_line)[..., 1]
        centred = offset - offset.mean(axis=1, keepdims=True)
        changes = np.count_nonzero(np.diff(np.sign(centred), axis=1))
        out[f"{name} length"] = float(length.sum() / low_length.sum())
        out[f"{name} overhang"] = float(length[along < 0.0].sum() / length.sum())
        out[f"{name} rms"] = float(np.sqrt(np.mean(np.sum((line - low_line) ** 2, -1))))
        out[f"{name} travel"] = float(np.abs(np.diff(offset, axis=1)).sum()
                                      / low_length.sum())
        out[f"{name} waves"] = float(0.5 * changes / low_length.sum())
        # the RMS over a zigzag's of the same length and waves a metre
        zigzag = zigzag_rms(out[f"{name} length"]) / max(out[f"{name} waves"], 1e-30)
        out[f"{name} shape"] = out[f"{name} rms"] / max(zigzag, 1e-30)
        out[f"{name} flat"] = float(length[along > np.cos(np.radians(30))].sum()
                                    / length.sum())
        out[f"{name} steep"] = float(length[(along >= 0.0)
                                            & (along < np.cos(np.radians(60)))].sum()
                                     / length.sum())
    return out


def overhang_model(length: float, lean: float, samples: int = 20000) -> tuple[float, float]:
    """What overhanging folds save: the curve x = (theta - lean sin 2 theta) / 2 pi,
    y = A sin theta (one wavelength; lean 0.5 stands its flanks upright, more tips them
    over), its amplitude A chosen for ``length`` per wavelength. Returns its RMS height
    (over its length) over the zigzag's of the same length, and the share of its length
    that runs backwards."""
    theta = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    x = (theta - lean * np.sin(2 * theta)) / (2 * np.pi)
    dx = np.diff(np.append(x, x[0] + 1.0))

    def curve(amplitude: float) -> tuple[float, float, float]:
        y = amplitude * np.sin(theta)
        seg = np.hypot(dx, np.diff(np.append(y, y[0])))
        return (float(seg.sum()), float(np.sqrt((y ** 2 * seg).sum() / seg.sum())),
                float(seg[dx < 0].sum() / seg.sum()))

    low, high = 0.0, 5.0
    for _ in range(60):  # the length grows with the amplitude
        middle = 0.5 * (low + high)
        low, high = (low, middle) if curve(middle)[0] > length else (middle, high)
    _, rms, back = curve(0.5 * (low + high))
    return rms / zigzag_rms(length), back


def profile_shape(height, length: float, samples: int = 65536) -> float:
    """A height field's RMS over the zigzag's of the same length: the periodic profile
    ``height`` (a function of the phase theta, one crest a period 2 pi) scaled to hold
    ``length`` times its wavelength. The triangle gives 1; nothing drawn with upright
    flanks gets below box_shape(length)."""
    theta = np.linspace(0.0, 2 * np.pi, samples, endpoint=False)
    values = np.asarray(height(theta), np.float64)
    slope = np.gradient(values, theta)
    low, high = 0.0, 100.0
    for _ in range(100):  # the length grows with the amplitude
        middle = 0.5 * (low + high)
        grown = float(np.mean(np.hypot(1.0, middle * slope)))
        low, high = (low, middle) if grown > length else (middle, high)
    amplitude = 0.5 * (low + high) / (2 * np.pi)  # per wavelength, as zigzag_rms
    return amplitude * float(np.sqrt(np.mean(values ** 2))) / zigzag_rms(length)


def box_shape(length: float) -> float:
    """The box with upright flanks (heads at +-A, length 1 + 4 A per wavelength) over the
    zigzag of the same length: sqrt(3 (length - 1) / (length + 1))."""
    return float(np.sqrt(3.0 * (length - 1.0) / (length + 1.0)))


#: the profiles profile_shape compares: usdwrinkle's presets and steeper boxes
SHAPES = {
    "fold (the default)": lambda t: preset_at("fold", t),
    "cosine": np.cos,
    "tanh 6 cos (box preset)": lambda t: preset_at("box", t),
    "tanh 20 cos": lambda t: np.tanh(20 * np.cos(t)) / np.tanh(20),
    "tanh 100 cos": lambda t: np.tanh(100 * np.cos(t)) / np.tanh(100),
}


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
        print(f"  {phase}:")
        for name in ("sim", "ours"):
            print(f"    {name:4s} length over the low-pass's {stats[name + ' length']:.2f}, "
                  f"overhanging {100 * stats[name + ' overhang']:.1f}%, RMS distance "
                  f"{1000 * stats[name + ' rms']:.1f} mm ({stats[name + ' shape']:.2f} x "
                  f"the zigzag's), out-of-plane travel "
                  f"{stats[name + ' travel']:.2f}, {stats[name + ' waves']:.1f} waves a "
                  f"metre, flat {100 * stats[name + ' flat']:.0f}% and steep "
                  f"{100 * stats[name + ' steep']:.0f}% of the length")
        at = int(np.flatnonzero(rows == line)[0])
        bands.append((phase, *(g[at] for g in grids)))
    draw(out, bands)
    print(f"wrote {out}")
    print("What overhanging folds save (overhang_model): the RMS height of a fold that leans "
          "over, over the zigzag's of the same length and wavelength")
    for length in (1.46, 1.86):
        cells = [f"lean {lean}: {ratio:.2f} ({100 * back:.0f}% backwards)"
                 for lean in (0.5, 0.6, 0.7) for ratio, back in [overhang_model(length, lean)]]
        print(f"  length {length}: " + ", ".join(cells))
    print("What a height field can reach (profile_shape): each profile scaled to hold the "
          "length, its RMS over the zigzag's")
    for length in (1.20, 1.46, 1.86):
        cells = [f"{name} {profile_shape(height, length):.3f}"
                 for name, height in SHAPES.items()]
        print(f"  length {length}: " + ", ".join(cells)
              + f", box with upright flanks {box_shape(length):.3f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
