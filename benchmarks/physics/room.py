"""What the room costs, and what finer folds would buy (issue 55): where the posed surface
curves tighter than the law's fold is high, the fold is lowered to its room (FOLD_ROOM of
the radius of curvature) and the cloth loses length; a fold the same slope but m times
shorter rises m times less, so it fits, and keeps the length.

    python -m benchmarks.physics.room [--write docs/physics.md] [--only shirt ...]

The engine computes each stage's frame 24; the compressed region is blend.py's (every fine
face whose coarse corners are compressed beyond 3 x the slack, unpainted), displaced along
the interpolated coarse normals by the blend of the engine's fitted corner waves, as
blend.py draws it (as the geometry bake displaces).
Per stage:
- the room's share: the compressed points whose fold the room lowers, and how many times
  its room the law's fold would rise there (the median and the 90th percentile of
  crush's ``over_room`` over the region's points);
- the area over the rest area: flat; drawn (the law: lowered to the room); without the
  room (the law's full height, which passes through its neighbours where it is over 1);
- the same with each point's fold drawn m = 2, 4 times shorter where it is over its room
  (the smallest power of two that fits, at most ``top``), at the law's slope, h =
  sum_c b_c (a_c / m_c) H(m_c theta_c), and the 99th percentile of what is left over the
  room. Each row is subdivided so that its shortest folds get as many fine vertices as
  the law's get at blend.py's LEVELS (LEVELS + log2 top levels).
One system only (a stage with wrinkle:biaxial is skipped). About 2.5 minutes and 18 GB of
memory here (the curtain and the shirt at 7 levels).
"""
from __future__ import annotations

import numpy as np

from .blend import (
    LEVELS,
    _area,
    _blend_area,
    aligned_corners,
    compressed_region,
    stage_regions,
)

STAGES = ("shirt", "curtain", "zeppelin")
#: the largest shortening tried (a power of two)
TOPS = (2, 4)


def _drawn_area(region, amplitude: np.ndarray, shorter: np.ndarray) -> float:
    """The region's displaced area over its rest area, each point's fold ``shorter``
    times shorter at ``amplitude`` / shorter."""
    k, theta = aligned_corners(region.corners, region.fields["wave_vector"],
                               region.fields["phase"].astype(np.float64))
    area = _blend_area(theta, k, region.offset, region.bary, amplitude[region.corners],
                       region.height, region.at, region.normal, shorter[region.corners])
    return float(area[region.chosen].sum() / region.rest_area)


def measure_stage(name: str, ctx) -> list[dict]:
    rows = []
    for engine, path, region in stage_regions(name, ctx):
        over = region.law["over_room"]
        lowered = np.maximum(over, 1.0)
        drawn = region.fields["amplitude"].astype(np.float64)
        inside = region.compressed & (over > 0)
        row = {"stage": name, "mesh": path, "faces": int(region.chosen.sum()),
               "lowered": float(np.mean(over[inside] > 1.0 + 1e-6)),
               "over": np.percentile(over[inside], [50, 90]),
               "flat": float(_area(region.at)[region.chosen].sum() / region.rest_area),
               "drawn": _drawn_area(region, drawn, np.ones_like(over)),
               "no room": _drawn_area(region, drawn * lowered, np.ones_like(over)),
               "shorter": []}
        for top in TOPS if row["lowered"] > 0.0 else ():
            levels = LEVELS + int(np.log2(top))
            m = np.clip(2.0 ** np.ceil(np.log2(lowered)), 1.0, top)
            left = np.percentile((lowered / m)[inside], 99)
            row["shorter"].append((top, levels, _drawn_area(
                compressed_region(engine, path, levels), drawn * lowered, m), float(left)))
        rows.append(row)
    return rows


def report(rows: list[dict], seconds: float) -> str:
    from ..blocks import markers, stage_block_head

    lines = stage_block_head("room", seconds) + [
             "| stage | points lowered by the room | law's fold over its room (median, p90) "
             "| area: flat | drawn (lowered) | without the room | "
             + " | ".join(f"folds up to {top}x shorter (p99 left over the room)"
                          for top in TOPS) + " |",
             "|---|---|---|---|---|---|" + "---|" * len(TOPS)]
    for row in rows:
        shorter = [f"{area:.3f} ({left:.2f}; {levels} levels)"
                   for _, levels, area, left in row["shorter"]]
        shorter += ["-"] * (len(TOPS) - len(shorter))
        lines.append(f"| {row['stage']} | {row['lowered']:.0%} | {row['over'][0]:.2f}, "
                     f"{row['over'][1]:.2f} | {row['flat']:.3f} | {row['drawn']:.3f} | "
                     f"{row['no room']:.3f} | " + " | ".join(shorter) + " |")
    lines += ["", "Area over rest area in the compressed region (frame 24), displaced along "
              "the interpolated coarse normals (as the geometry bake); `-` where the room "
              "lowers no fold.", "",
              markers("room")[1]]
    return "\n".join(lines)


def main(argv=None) -> int:
    from ..blocks import stage_block_main

    return stage_block_main(argv, "room", STAGES, measure_stage, report)


if __name__ == "__main__":
    raise SystemExit(main())
