"""Inextensibility on the sample stages (issue 55): the displaced geometry's area over the
rest area where the coarse mesh is compressed, per wrinkled mesh, and whether the
displaced surface passes through itself.

    python -m benchmarks.physics.area [--write docs/physics.md]

Each stage is baked with ``bake --geometry`` at its frame (24; the flag 1) and measured
on the fine triangles of the bake, against the subdivided rest mesh:
- **compressed**: every corner's coarse vertex compressed along its wave beyond 3 x the
  slack (crush's r_geo, the numpy reference), unpainted;
- **uniaxial, with room**: of those, the ones neither stretched nor compressed across by
  more than 10% and whose fold the room did not lower (tests/test_folds.py checks these);
- the fine triangles that cross another one, less those next to where the coarse mesh
  itself crosses (the skinned elbow).
About a minute here. Not a test: tests/test_folds.py asserts the sample stages' bounds.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "sample_stages"
STAGES = ("shirt", "zeppelin", "curtain", "flag", "pillow", "pull")
#: fewer fine triangles than this in a region: no ratio (too few to average the folds)
LEAST = 100


def _near(triangles: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    points = np.unique(triangles[chosen].ravel())
    return np.isin(triangles, points).any(axis=1)


def measure_stage(name: str, ctx, scratch: Path, path: Path | None = None) -> list[dict]:
    """The area rows of sample stage ``name`` at its measured frame (``path``: a layer
    over it to measure instead, such as benchmarks.stability.perturbed's)."""
    from pxr import Usd, UsdGeom

    from usdwrinkle import api
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.geometry.measure import self_intersections, triangle_areas
    from usdwrinkle.geometry.subdivide import fine_point_count, subdivide
    from usdwrinkle.method.contract import SLACK_RAMP
    from usdwrinkle.reference.crush import crush

    stage_path = path or SAMPLES / f"{name}.usda"
    frame = 1 if name == "flag" else 24
    layer = api.bake(stage_path, scratch / f"{name}_geo.usdc", frames=[frame], geometry=True)
    baked = Usd.Stage.Open(layer)
    engine = WrinkleEngine(str(stage_path), ctx=ctx)
    rows = []
    try:
        engine.compute_frame(frame)
        for path in engine.wrinkled_paths:
            record = engine.meshes[path]
            fields = engine.read_fields(path).arrays()
            triangles = record.topology.triangles
            law = crush(record.rest_points, fields["points"], record.topology,
                        record.params.q, record.params.width, slack=record.params.slack)
            fine = UsdGeom.Mesh(baked.GetPrimAtPath(path + "_wrinkled"))
            faces = np.asarray(fine.GetFaceVertexIndicesAttr().Get(), np.int64).reshape(-1, 3)
            points = np.asarray(fine.GetPointsAttr().Get(frame), np.float64)
            levels = next(level for level in range(11) if fine_point_count(
                len(record.rest_points), triangles, level) == len(points))
            rest = subdivide(record.rest_points, triangles, levels)
            coarse = self_intersections(fields["points"], triangles)
            spoiled = _near(triangles, np.unique(coarse.ravel())) if len(coarse) else \
                np.zeros(len(triangles), bool)
            pairs = self_intersections(points, faces)
            new = int(np.sum(~spoiled[rest.face_triangle[pairs]].any(axis=1))) if len(pairs) \
                else 0
            unpainted = np.linalg.norm(record.params.q, axis=1) == 0
            compressed = ((law["geometric"] < 1.0 - SLACK_RAMP * record.params.slack)
                          & unpainted)
            uniaxial = compressed & (np.abs(law["stretch"] - 1.0) < 0.1) & ~law["capped"]
            ours, rest_areas = triangle_areas(points, faces), triangle_areas(rest.points, faces)
            row = {"stage": name, "mesh": path, "crossings": new,
                   "coarse crossings": int(len(coarse))}
            for key, per_point in (("compressed", compressed), ("uniaxial", uniaxial)):
                chosen = per_point[triangles[rest.face_triangle]].all(axis=1)
                row[key + " triangles"] = int(chosen.sum())
                row[key] = float(ours[chosen].sum() / rest_areas[chosen].sum()) \
                    if chosen.sum() >= LEAST else float("nan")
                row[key + " flat"] = float(
                    triangle_areas(subdivide(fields["points"], triangles, levels).points,
                                   faces)[chosen].sum() / rest_areas[chosen].sum()) \
                    if chosen.sum() >= LEAST else float("nan")
            rows.append(row)
    finally:
        engine.release()
    return rows


def report(rows: list[dict], seconds: float) -> str:
    from ..blocks import markers, stage_block_head

    def cell(row, key):
        if not np.isfinite(row[key]):
            return f"- ({row[key + ' triangles']} triangles)"
        return f"{row[key]:.3f} (flat {row[key + ' flat']:.3f}, {row[key + ' triangles']})"

    lines = stage_block_head("area", seconds) + [
             "| stage | mesh | area: compressed | area: uniaxial, with room | "
             "crossings (the coarse mesh's own) |", "|---|---|---|---|---|"]
    for row in rows:
        lines.append(f"| {row['stage']} | {row['mesh']} | {cell(row, 'compressed')} | "
                     f"{cell(row, 'uniaxial')} | {row['crossings']} "
                     f"({row['coarse crossings']}) |")
    lines += ["", "Each area cell: the wrinkled area over the rest area, the subdivided "
              "coarse (flat) surface's, and the fine triangles measured; `-` where fewer "
              f"than {LEAST}.", "", markers("area")[1]]
    return "\n".join(lines)


def main(argv=None) -> int:
    import tempfile

    from ..blocks import stage_block_main

    with tempfile.TemporaryDirectory(prefix="usdwrinkle-area-") as scratch:
        return stage_block_main(argv, "area", STAGES,
                                lambda name, ctx: measure_stage(name, ctx, Path(scratch)),
                                report)


if __name__ == "__main__":
    raise SystemExit(main())
