"""Where the blend adds or loses area (issue 55): the wave blend of the sample stages'
compressed regions, taken apart in numpy.

    python -m benchmarks.physics.blend [--write docs/physics.md] [--only zeppelin ...]

The engine computes each stage's frame 24 (its phase history from the shot's start, as
every render and bake does); the fine mesh is the coarse posed mesh subdivided LEVELS (5)
times, displaced along the interpolated coarse normals (as ``bake --geometry`` displaces
it, shaders/geometry.glsl) by the blend
h = sum_c b_c a_c H(theta_c) of include/wave.glsl, divided by its coherence (no band
limit), and its area is
measured where every corner is compressed beyond 3 x the slack, unpainted
(benchmarks.physics.area's region). The blend is drawn with:
- **crush's waves**: k and a as the crush pass makes them (the numpy reference), with
  the engine's relaxed phases: the blend before relax's fit;
- the same, with the phases relaxed to convergence (2,000 iterations, numpy);
- **fitted**: the engine's fields, k and a fitted to the relaxed phases (relax.glsl's
  FIT), as drawn;
- **agreed**: the fitted waves, each corner's phase moved so that the three corner waves
  agree at the triangle's centroid (their amplitude-weighted circular mean). This is not
  a surface (h jumps at the coarse edges); it is what the blend would draw with no phase
  misfit inside the triangles.
One system only (a stage with wrinkle:biaxial is skipped), and the folds alone: the
deepened pleats' offset (method/deepen.py), which the geometry bake adds where the room
binds, is left out (benchmarks.physics.deepen measures it). A few seconds here.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "sample_stages"
STAGES = ("zeppelin", "shirt", "curtain")
#: subdivision levels of the compressed regions: the shirt's area moves by under 1% from
#: 5 to 6 (at 3 it read 8% low displaced along the face normals, which then happened to
#: agree with the bake)
LEVELS = 5
CONVERGED = 2000
#: centroid misfit bins (radians) of the per-triangle table
BINS = (0.0, 0.2, 0.4, 0.8, np.pi + 1e-9)


def _area(x: np.ndarray) -> np.ndarray:
    return 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)


def _blend_area(phase, k, offset, bary, amplitude, height, at, normal,
                shorter=1.0) -> np.ndarray:
    """Each fine face's area, displaced by the blend of its coarse triangle's corner
    waves (k, amplitude, ``phase`` per face and corner) along ``normal`` (per fine vertex:
    the interpolated coarse normal, as the geometry bake displaces), as
    include/wave.glsl blends them (usdwrinkle.reference.blend: divided by its coherence,
    within the interpolated amplitude); each corner's fold ``shorter`` times
    shorter at amplitude / shorter, the same slope (benchmarks.physics.room; 1: the
    waves as they are)."""
    from usdwrinkle.reference.blend import blended_height

    theta = phase[:, None, :] + np.einsum("mcj,mvcj->mvc", k, offset)
    m = np.broadcast_to(np.asarray(shorter, np.float64), amplitude.shape)[:, None, :]
    h = blended_height(bary * (amplitude[:, None, :] / m), m * theta, height)
    return _area(at + h[..., None] * normal)


def aligned_corners(corners: np.ndarray, wave_vector, phases: np.ndarray):
    """Per fine face and corner: k sign-aligned to corner 0's (as include/wave.glsl's
    corner_waves aligns it) and the phase with the same sign."""
    k = np.asarray(wave_vector, np.float64)[corners]
    sign = np.where(np.einsum("mcj,mj->mc", k, k[:, 0]) < 0, -1.0, 1.0)
    return k * sign[..., None], phases[corners] * sign


@dataclass
class Region:
    """A mesh's compressed region at the engine's current frame, subdivided: every fine
    face of the coarse triangles whose corners are all compressed beyond 3 x the slack,
    unpainted (``chosen``), with what the blend needs per fine face and corner."""
    law: dict                  # crush's fields (the numpy reference)
    fields: dict               # the engine's fields (fitted k and a, relaxed phases)
    posed: np.ndarray          # coarse posed points
    topology: object
    compressed: np.ndarray     # per coarse vertex
    corners: np.ndarray        # (m, 3) coarse vertex of each fine face's corner
    corner_points: np.ndarray  # (m, 3, 3)
    bary: np.ndarray           # (m, 3 fine vertices, 3 corners), as blend_weights makes them
    at: np.ndarray             # (m, 3, 3) the fine vertices, flat
    normal: np.ndarray         # (m, 3, 3) the interpolated coarse normal at each fine vertex
    offset: np.ndarray         # (m, 3 fine vertices, 3 corners, 3) fine vertex - corner
    chosen: np.ndarray         # (m,) the fine faces measured
    rest_area: float           # their rest area
    height: np.ndarray         # the mesh's height profile


def compressed_region(engine, path: str, levels: int) -> Region | None:
    """The compressed region of ``path`` (one system only) at the engine's current frame,
    subdivided ``levels`` times; None where it has fewer than 100 fine faces."""
    from usdwrinkle.geometry.subdivide import subdivide
    from usdwrinkle.method.contract import SLACK_RAMP
    from usdwrinkle.reference.crush import crush

    record = engine.meshes[path]
    computed = engine.read_fields(path)
    fields = computed.arrays()
    # the amplitude as the surface draws it (lowered where the mesh is stretched across)
    fields["amplitude"] = computed.drawn_amplitude
    triangles = record.topology.triangles
    posed = fields["points"].astype(np.float64)
    law = crush(record.rest_points, posed, record.topology, record.params.q,
                record.params.width, slack=record.params.slack,
                hold=record.params.hold, coarsening=record.params.coarsening)
    law["amplitude"] = law["amplitude"] * law["drawn"]
    unpainted = np.linalg.norm(record.params.q, axis=1) == 0
    compressed = (law["geometric"] < 1 - SLACK_RAMP * record.params.slack) & unpainted
    fine = subdivide(posed, triangles, levels)
    bary = np.clip(fine.corner_bary.astype(np.float64), 0, 1)
    bary /= bary.sum(-1, keepdims=True)  # blend_weights
    corners = triangles[fine.face_triangle.astype(np.int64)]
    chosen = compressed[corners].all(1)
    if chosen.sum() < 100:
        return None
    corner_points = posed[corners]
    # the posed normals crush sums (the geometry bake's shading normals where the mesh
    # authors none), interpolated per fine vertex and normalised, as geometry.glsl does
    normal = np.einsum("mvc,mcj->mvj", bary,
                       fields["normals"].astype(np.float64)[:, :3][corners])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    at = np.einsum("mvc,mcj->mvj", bary, corner_points)
    rest_area = _area(np.einsum("mvc,mcj->mvj", bary,
                                record.rest_points.astype(np.float64)[corners]))
    return Region(law, fields, posed, record.topology, compressed, corners, corner_points,
                  bary, at, normal, at[:, :, None, :] - corner_points[:, None, :, :], chosen,
                  float(rest_area[chosen].sum()),
                  np.asarray(record.params.height_profile, np.float64))


def stage_regions(name: str, ctx, levels: int = LEVELS):
    """(engine, path, region) for each one-system mesh of sample stage ``name`` with a
    compressed region at frame 24; the engine is released after the last."""
    from usdwrinkle.engine import WrinkleEngine

    engine = WrinkleEngine(str(SAMPLES / f"{name}.usda"), ctx=ctx)
    try:
        engine.compute_frame(24)
        for path in engine.wrinkled_paths:
            if engine.meshes[path].params.biaxial:
                continue
            region = compressed_region(engine, path, levels)
            if region is not None:
                yield engine, path, region
    finally:
        engine.release()


def measure_stage(name: str, ctx) -> list[dict]:
    from usdwrinkle.reference.relax import phase_misfit, relax

    rows = []
    for _, path, region in stage_regions(name, ctx):
        law, fields, posed = region.law, region.fields, region.posed
        corners, corner_points, offset = region.corners, region.corner_points, region.offset
        bary, height, at, normal = region.bary, region.height, region.at, region.normal
        chosen, rest_area, compressed = region.chosen, region.rest_area, region.compressed
        flat = _area(at)
        phase = fields["phase"].astype(np.float64)
        converged = relax(posed, law["wave_vector"], law["amplitude"], phase,
                          region.topology, CONVERGED)

        def drawn(wave_vector, amplitude, phases, agree=False,
                  mesh=(corners, corner_points, offset, bary, height, at, normal)):
            corners, corner_points, offset, bary, height, at, normal = mesh
            k, theta = aligned_corners(corners, wave_vector, phases)
            a = np.asarray(amplitude, np.float64)[corners]
            misfit = np.zeros(len(k))
            if agree:
                centroid = corner_points.mean(1)
                at_centroid = theta + np.einsum("mcj,mcj->mc", k,
                                                centroid[:, None, :] - corner_points)
                mean = np.angle((a * np.exp(1j * at_centroid)).sum(1))
                misfit = np.abs(np.angle(np.exp(1j * (at_centroid - mean[:, None])))).max(1)
                theta = mean[:, None] + np.einsum("mcj,mcj->mc", k,
                                                  corner_points - centroid[:, None, :])
            return _blend_area(theta, k, offset, bary, a, height, at, normal), misfit

        before, _ = drawn(law["wave_vector"], law["amplitude"], phase)
        _, misfit = drawn(law["wave_vector"], law["amplitude"], phase, agree=True)
        after, _ = drawn(fields["wave_vector"], fields["amplitude"], phase)
        agreed, _ = drawn(fields["wave_vector"], fields["amplitude"], phase, agree=True)
        row = {"stage": name, "mesh": path, "faces": int(chosen.sum()),
               "flat": flat[chosen].sum() / rest_area,
               "crush": before[chosen].sum() / rest_area,
               "converged": drawn(law["wave_vector"], law["amplitude"], converged)[0][
                   chosen].sum() / rest_area,
               "fitted": after[chosen].sum() / rest_area,
               "agreed": agreed[chosen].sum() / rest_area,
               "misfit": phase_misfit(posed, law["wave_vector"], phase, region.topology,
                                      compressed),
               "misfit fitted": phase_misfit(posed, fields["wave_vector"], phase,
                                             region.topology, compressed),
               "bins": []}
        for low, high in zip(BINS[:-1], BINS[1:], strict=True):
            inside = chosen & (misfit >= low) & (misfit < high)
            if inside.sum():
                row["bins"].append((low, high, float(inside.mean() / chosen.mean()),
                                    before[inside].sum() / flat[inside].sum(),
                                    after[inside].sum() / flat[inside].sum()))
        rows.append(row)
    return rows


def report(rows: list[dict], seconds: float) -> str:
    from ..blocks import markers, stage_block_head

    lines = stage_block_head("blend", seconds) + [
             "| stage | flat | crush's waves | ... relaxed to convergence | fitted (drawn) | "
             "fitted, phases agreed per triangle | edge misfit (rad): crush's k / fitted k |",
             "|---|---|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['stage']} | {row['flat']:.3f} | {row['crush']:.3f} | "
                     f"{row['converged']:.3f} | {row['fitted']:.3f} | {row['agreed']:.3f} | "
                     f"{row['misfit']:.2f} / {row['misfit fitted']:.2f} |")
    lines += ["", f"Area over rest area in the compressed region ({LEVELS} levels, displaced along "
              "the interpolated coarse normals). By how far crush's corner "
              "waves disagree at the triangle's centroid (the three phases' largest distance "
              "from their mean): the share of the region's fine triangles, and crush's waves / "
              "flat, fitted / flat there.", ""]
    for row in rows:
        cells = "; ".join(f"{low:.1f}-{min(high, np.pi):.1f} rad: {share:.0%}, "
                          f"{before:.3f}, {after:.3f}"
                          for low, high, share, before, after in row["bins"])
        lines.append(f"- {row['stage']}: {cells}")
    lines += ["", markers("blend")[1]]
    return "\n".join(lines)


def main(argv=None) -> int:
    from ..blocks import stage_block_main

    return stage_block_main(argv, "blend", STAGES, measure_stage, report)


if __name__ == "__main__":
    raise SystemExit(main())
