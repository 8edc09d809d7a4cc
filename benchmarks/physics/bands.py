"""The curtains band by band, from the rings to the hem (issue 55: where the amplitude-field
correlation goes).

    python -m benchmarks.physics.bands [--write docs/physics.md] [--only SHOT ...]
                                       [--grid M] [--cache .physics-cache]

The correlation bar compares the two amplitude fields (measure.amplitude_field) over the
cloth and the shot's frames at once. Per curtain, baked at its matched W as the
converged table matches it (referee.matched_bakes), this prints:

- the correlation, and what parts of the fields carry it: ours replaced by its own mean
  over the cloth at each frame (no place in it, only the folds' growth in time); the
  cloth's own mean per grid row (its profile from the rings to the hem, the same across
  the curtain); ours the same; ours smoothed across the curtain (a Gaussian of ACROSS
  along each grid row);
- per band of BAND grid rows (from the rings down), at the last phase: the area over the
  rest area of the low-pass (the coarse surface), of the cloth's offsets along its
  normals, and of the same offsets band-passed as the measure takes them (measure.detail:
  less their own window's average, which drops what sharpens the low-pass's own folds);
  of our bake's surface without its folds (usdwrinkle's coarse mesh, every stride-th grid
  line of the low-pass, subdivided) and with them, at the simulation's grid points (at
  the default grid, the bake's own: the fine mesh is that grid); the material wavelength
  and the RMS fold height, the cloth's and ours.

Needs the cached simulations at the converged referee's 160 iterations (``--grid``,
1 cm by default: the grid the converged table judges the curtains on); about 15 s a
curtain here (two or three bakes).
"""
from __future__ import annotations

import numpy as np

from ..blocks import markers
from . import measure, referee
from .coarse import _smooth_axis
from .oracle import moving_frames, zones

NAME = "referee-bands"
#: the shots this measures: the curtains, whose grid rows run from the rings to the hem
CURTAINS = ("curtain-silk", "curtain-cotton", "curtain-leather")
#: m, the grid of the simulations measured (the converged table's for the curtains)
GRID = 0.01
#: grid rows in a band (13 cm at 1 cm)
BAND = 13
#: m, the Gaussian that smooths our field across the curtain
ACROSS = 0.2


def _rows_mean(field: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """(frames, rows, 1): each grid row's mean over the inner zone."""
    kept = np.where(inner, field, 0.0).sum(-1, keepdims=True)
    count = np.maximum(inner.sum(-1, keepdims=True), 1)
    return kept / count


def correlations(shot, sim_h: np.ndarray, our_h: np.ndarray) -> dict:
    """The correlation of the amplitude fields over the shot's moving frames (as
    oracle.compare takes it) and of the parts named in the module docstring."""
    rows, cols = shot.rows, shot.cols
    moving = moving_frames(shot)
    inner = zones(shot)["all"]
    grid_inner = inner.reshape(rows, cols)
    sim = measure.amplitude_field(shot, sim_h[moving]).reshape(-1, rows, cols)
    ours = measure.amplitude_field(shot, our_h[moving]).reshape(-1, rows, cols)
    ones = np.ones_like(ours)

    def against_sim(field):
        return measure.correlation(field.reshape(len(moving), -1)[:, inner],
                                   sim.reshape(len(moving), -1)[:, inner])

    frame_mean = ours.reshape(len(moving), -1)[:, inner].mean(1)[:, None, None]
    across = _smooth_axis(ours, 2, ACROSS / shot.spacing, False)
    return {"whole": against_sim(ours), "frame means": against_sim(frame_mean * ones),
            "cloth rows": against_sim(_rows_mean(sim, grid_inner) * ones),
            "our rows": against_sim(_rows_mean(ours, grid_inner) * ones),
            "ours smoothed across": against_sim(across)}


def bands(sim, baked, frame: int) -> list[dict]:
    """Per band of BAND grid rows at ``frame`` (module docstring); ``baked``: our bake at
    the simulation's grid points (oracle.bake, on_coarser_grid)."""
    from usdwrinkle.geometry.measure import triangle_areas

    from .newton_client import triangles

    shot = sim.shot
    tri = triangles(shot.quads())
    rest = triangle_areas(shot.rest, tri)
    inner = zones(shot)["all"]
    row_of = np.repeat(np.arange(shot.rows), shot.cols)
    low, normals, h = measure.normal_offsets(shot, sim.points[frame])
    passed = measure.detail(shot, h[None])[0]
    out = []
    for first in range(0, shot.rows, BAND):
        points_in = inner & (row_of >= first) & (row_of < first + BAND)
        faces = inner[tri].all(1) & points_in[tri].all(1)
        if faces.sum() < 50:
            continue

        def area(surface, faces=faces):
            return float(triangle_areas(surface, tri)[faces].sum() / rest[faces].sum())

        out.append({"rows": (first, min(first + BAND, shot.rows) - 1),
                    "low": area(low), "offsets": area(low + h[:, None] * normals),
                    "passed": area(low + passed[:, None] * normals),
                    "ours": (area(baked.flat[frame]), area(baked.points[frame])),
                    "wavelength": (measure.wavelength(shot, sim.h[frame], points_in),
                                   measure.wavelength(shot, baked.h[frame], points_in)),
                    "rms": (measure.rms(sim.h[frame], points_in),
                            measure.rms(baked.h[frame], points_in))})
    return out


def shot_rows(name: str, cache, grid: float) -> dict:
    sim, fine = referee.referee_pair(name, cache, grid, referee.CONVERGED[1])
    row = referee.matched_bakes(sim, fine, referee.cloth_attributes(sim.shot))
    baked = row["matched bake"]
    _, end = list(sim.shot.phases.values())[-1]
    return {"grid": grid, "window": sim.shot.window, "width": row["width"],
            "correlations": correlations(sim.shot, sim.h, baked.h),
            "bands": bands(sim, baked, end - 1),
            "spacing": sim.shot.spacing}


def report(rows: dict, seconds: float, grid: float) -> str:
    end = markers(NAME)[1]
    lines = referee.shot_block_head(NAME, "bands", seconds, grid) + [
             "The amplitude-field correlation at matched W, and with ours replaced by: its "
             "mean over the cloth at each frame; the cloth's mean per grid row; our own mean "
             f"per grid row; ours smoothed across the curtain ({ACROSS * 100:g} cm).", "",
             "| shot | window | matched W | correlation | ours: frame means | the cloth's rows "
             "| our rows | ours smoothed across |", "|---|---|---|---|---|---|---|---|"]
    for name, row in rows.items():
        c = row["correlations"]
        lines.append(f"| {name} | {row['window'] * 100:.1f} cm | {row['width'] * 100:.1f} cm "
                     f"| {c['whole']:.3f} | {c['frame means']:.3f} | {c['cloth rows']:.3f} "
                     f"| {c['our rows']:.3f} | {c['ours smoothed across']:.3f} |")
    lines += ["", "At the last phase, band by band from the rings to the hem: the area over "
              "the rest area of the low-pass, of the cloth's offsets along its normals, and of "
              "the same band-passed as the measure takes them; of our bake's surface without "
              "its folds (the coarse mesh subdivided) and with them; the material wavelength "
              "and the RMS fold height (cloth, ours).", "",
              "| shot | band (cm from the rings) | low-pass | normal offsets | band-passed "
              "| ours: unfolded, folded | wavelength: cloth, ours | RMS height: cloth, ours |",
              "|---|---|---|---|---|---|---|---|"]
    for name, row in rows.items():
        for band in row["bands"]:
            top, bottom = (v * row["spacing"] * 100 for v in band["rows"])
            lines.append(
                f"| {name} | {top:.0f}-{bottom:.0f} | {band['low']:.3f} | "
                f"{band['offsets']:.3f} | {band['passed']:.3f} | "
                f"{band['ours'][0]:.3f}, {band['ours'][1]:.3f} | "
                f"{band['wavelength'][0] * 100:.1f}, {band['wavelength'][1] * 100:.1f} cm | "
                f"{band['rms'][0] * 1000:.1f}, {band['rms'][1] * 1000:.1f} mm |")
    lines += ["", end]
    return "\n".join(lines)


def main(argv=None) -> int:
    return referee.shot_block_main(
        argv, "bands", NAME, __doc__, shot_rows, report, shots=CURTAINS, grid=GRID,
        grid_doc="the grid the converged table judges the curtains on")


if __name__ == "__main__":
    raise SystemExit(main())
