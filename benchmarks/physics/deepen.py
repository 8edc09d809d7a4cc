"""The deepened pleats (method/deepen.py, contract.DEEPEN_CAP) at other caps: the law is
built into the passes; this measures what its cap buys, 0 (none) included, by setting the
shaders' DEEPEN_CAP in this process (render/bindings.COMMON) before each engine is made.

    python -m benchmarks.physics.deepen [--write docs/physics.md] [--caps 0 0.5 0.75 1]
                                        [--referee CAP ...] [--only SHOT ...]
                                        [--cache .physics-cache]
                                        [--figure docs/images/physics_deepen.png]

- Sample stages (STAGES) at their measured frame: benchmarks.physics.area's measure of the
  geometry bake per cap, the wrinkled area over the rest area where the coarse surface is
  compressed and the pairs of fine triangles that pass through each other, and the 90th
  percentile of |offset| there.
- Pleated sheets (PLEATS): a flat sheet pushed together and folded into pleats, the
  geometry bake's area per cap where the room lowers the folds on the pleats' crests.
- ``--referee CAP``: the converged referee's rows (referee.sweep_report, its simulations
  cached; ``--only`` its shots) with the cap set.
- ``--figure``: the curtain sample's frame 24 rendered from its geometry bake (usdwrinkle
  render --no-wrinkles over the bake layer) at cap 0 (left) and DEEPEN_CAP (right).
"""
from __future__ import annotations

import argparse
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
STAGES = ("curtain", "shirt", "zeppelin")
CAPS = (0.0, 0.5, 0.75, 1.0)


@contextmanager
def deepen_cap(cap: float):
    """The passes' DEEPEN_CAP set to ``cap`` for the engines made inside the block."""
    from usdwrinkle.method.contract import glsl_literal
    from usdwrinkle.render import bindings

    before = bindings.COMMON["DEEPEN_CAP"]
    bindings.COMMON["DEEPEN_CAP"] = glsl_literal(float(cap))
    try:
        yield
    finally:
        bindings.COMMON["DEEPEN_CAP"] = before


def _offsets(name: str, ctx) -> np.ndarray:
    """|offset| over the points of the stage's wrinkled meshes where the coarse surface
    is compressed (r < 1), at its measured frame."""
    from usdwrinkle.engine import WrinkleEngine

    engine = WrinkleEngine(str(ROOT / "sample_stages" / f"{name}.usda"), ctx=ctx)
    try:
        engine.compute_frame(24)
        out = []
        for path in engine.wrinkled_paths:
            fields = engine.read_fields(path)
            out.append(np.abs(fields.offset[fields.compression < 1.0]))
        return np.concatenate(out) if out else np.zeros(0)
    finally:
        engine.release()


def measure_stage(name: str, ctx, scratch: Path, caps=CAPS) -> list[dict]:
    """Per wrinkled mesh of the stage, per cap: (cap, area where compressed, crossings,
    p90 |offset|)."""
    from .area import measure_stage as area_rows

    rows: dict[str, dict] = {}
    for cap in caps:
        with deepen_cap(cap):
            offsets = _offsets(name, ctx)
            for row in area_rows(name, ctx, scratch):
                entry = rows.setdefault(row["mesh"], {"stage": name, "mesh": row["mesh"],
                                                      "caps": []})
                entry["caps"].append((cap, row["compressed"], row["crossings"],
                                      float(np.percentile(offsets, 90)) if len(offsets)
                                      else 0.0))
    return list(rows.values())


#: the pleated sheets: (W, the sheet's compression along x, the pleats' amplitude and
#: period, m), pleats of a 1 m x 0.4 m cotton sheet (81 x 17 points) pushed together
PLEATS = ((0.1, 0.5, 0.03, 0.2), (0.1, 0.6, 0.03, 0.25), (0.15, 0.6, 0.03, 0.25),
          (0.15, 0.5, 0.03, 0.2))


def pleated_sheet(compression: float, amplitude: float, period: float):
    """(rest, posed, counts, indices): a flat 1 m x 0.4 m sheet (81 x 17 points) pushed to
    ``compression`` of its length along x and folded into pleats z = amplitude cos(2 pi x /
    period) (its coarse mesh compressed 0.5-0.75 along x, the pleats' crests curving at up
    to amplitude (2 pi / period)^2)."""
    from usdwrinkle.authoring.builders import grid_faces

    x, y = np.meshgrid(np.linspace(-0.5, 0.5, 81), np.linspace(-0.2, 0.2, 17), indexing="ij")
    rest = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], 1)
    posed_x = compression * x.ravel()
    posed = np.stack([posed_x, y.ravel(), amplitude * np.cos(2 * np.pi * posed_x / period)], 1)
    counts, indices = grid_faces(81, 17)
    return rest, posed, counts, indices


def pleated_rows(scratch: Path, caps) -> list[dict]:
    """Per PLEATS sheet and cap: the geometry bake's area over the rest area on the
    sheet's middle (|x| < 0.35, |y| < 0.12 at rest) and its crossings; and the share of its
    middle points whose fold the room lowers (the numpy reference)."""
    from pxr import Usd, UsdGeom

    from usdwrinkle import api
    from usdwrinkle.authoring.builders import point_cache_stage
    from usdwrinkle.geometry.measure import self_intersections, triangle_areas
    from usdwrinkle.geometry.subdivide import subdivide
    from usdwrinkle.reference.crush import crush
    from usdwrinkle.scene.topology import build_topology

    rows = []
    for width, compression, amplitude, period in PLEATS:
        rest, posed, counts, indices = pleated_sheet(compression, amplitude, period)
        stage_path = scratch / f"pleats_{width:g}_{compression:g}_{period:g}.usda"
        stage = point_cache_stage(rest, {1: posed}, counts, indices, width=width)
        stage.GetRootLayer().Export(str(stage_path))
        law = crush(rest, posed, build_topology(counts, indices, rest), np.zeros_like(rest),
                    np.full(len(rest), width))
        middle = (np.abs(rest[:, 0]) < 0.35) & (np.abs(rest[:, 1]) < 0.12)
        row = {"sheet": (width, compression, amplitude, period),
               "lowered": float(np.mean(law["over_room"][middle] > 1.0)), "caps": []}
        quads = np.asarray(indices).reshape(-1, 4)
        triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
        fine_rest = subdivide(rest, triangles, 3).points
        for cap in caps:
            with deepen_cap(cap):
                layer = api.bake(stage_path, scratch / f"{stage_path.stem}_{cap:g}.usdc",
                                 frames=[1], geometry=True, levels=3)
            baked = Usd.Stage.Open(str(layer))
            mesh = UsdGeom.Mesh(baked.GetPrimAtPath("/Sheet_wrinkled"))
            points = np.asarray(mesh.GetPointsAttr().Get(1), np.float64)
            faces = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), np.int64).reshape(-1, 3)
            centre = fine_rest[faces].mean(axis=1)
            inside = (np.abs(centre[:, 0]) < 0.35) & (np.abs(centre[:, 1]) < 0.12)
            area = triangle_areas(points, faces)[inside].sum() / \
                triangle_areas(fine_rest, faces)[inside].sum()
            row["caps"].append((cap, float(area), len(self_intersections(points, faces))))
        rows.append(row)
    return rows


def referee_rows(cache: Path, cap: float, shots) -> list[str]:
    """The converged referee's table rows with the cap set, then its phase by phase
    lines."""
    from . import referee

    with deepen_cap(cap):
        text = referee.sweep_report(list(shots), cache, "converged")
    lines = text.splitlines()
    return ([line for line in lines if line.startswith("| ") and not line.startswith("| shot")]
            + [""] + [line for line in lines if line.startswith("- ")])


def figure(out: Path, cap: float | None = None, frame: int = 24,
           name: str = "curtain") -> None:
    """A sample stage (the curtain) without and with its deepened pleats, side by side,
    rendered from its geometry bake (module docstring)."""
    import tempfile

    import OpenImageIO as oiio

    from usdwrinkle import api
    from usdwrinkle.method.contract import DEEPEN_CAP

    stage = str(ROOT / "sample_stages" / f"{name}.usda")
    halves = []
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-deepen-") as scratch:
        for side in (0.0, DEEPEN_CAP if cap is None else cap):
            with deepen_cap(side):
                layer = api.bake(stage, f"{scratch}/geometry_{side:g}.usdc", frames=[frame],
                                 geometry=True)
            written = api.render(stage, f"{scratch}/side_{side:g}.####.png", frames=[frame],
                                 width=1080, height=720, no_wrinkles=True, sublayer=[layer])
            halves.append(oiio.ImageBuf(written[0]).get_pixels(oiio.UINT8))
    # both sides cut to the columns and rows where either shows the curtain, with a margin
    drawn = np.any([half[..., 3] > 0 for half in halves], axis=0)  # alpha: the curtain
    rows, cols = np.flatnonzero(drawn.any(axis=1)), np.flatnonzero(drawn.any(axis=0))
    box = (slice(max(rows[0] - 20, 0), rows[-1] + 20), slice(max(cols[0] - 20, 0), cols[-1] + 20))
    both = np.concatenate([half[box] for half in halves], axis=1)
    image = oiio.ImageBuf(oiio.ImageSpec(both.shape[1], both.shape[0], both.shape[2],
                                         oiio.UINT8))
    image.set_pixels(oiio.ROI(), both)
    if not image.write(str(out)):
        raise SystemExit(f"cannot write {out}: {image.geterror()}")
    print(f"wrote {out}")


def report(rows: list[dict], pleats: list[dict], referee: dict, caps, shots,
           seconds: float) -> str:
    from usdwrinkle.method.contract import DEEPEN_CAP

    from ..blocks import markers

    options = " --caps" + "".join(f" {cap:g}" for cap in caps)
    if referee:
        options += " --referee" + "".join(f" {cap:g}" for cap in referee)
        options += " --only" + "".join(f" {shot}" for shot in shots)
    lines = [
        markers("deepen")[0], "",
        f"Made by `python -m benchmarks.physics.deepen{options} --write docs/physics.md` "
        f"({seconds:.0f} s here; the law's cap is {DEEPEN_CAP:g}).", "",
        "Sample stages at frame 24 (the geometry bake, as benchmarks.physics.area measures "
        "it), per cap (0: no deepening): the wrinkled area over the rest area where the "
        "coarse surface is compressed, the pairs of fine triangles that pass through each "
        "other, and the 90th percentile of |offset| at the compressed points (m).", "",
        "| stage | mesh | " + " | ".join(f"cap {cap:g}" for cap in caps) + " |",
        "|---|---|" + "---|" * len(caps)]
    for row in rows:
        lines.append(f"| {row['stage']} | {row['mesh']} | " + " | ".join(
            f"{area:.3f}, {crossings}, {p90:.3f}" for _, area, crossings, p90 in row["caps"])
            + " |")
    lines += ["", "Pleated sheets (benchmarks.physics.deepen PLEATS: a flat cotton sheet "
              "pushed together along x and folded into pleats of the given amplitude and "
              "period, as a gathered curtain's coarse mesh is; the geometry bake at 3 "
              "levels): the share of the middle's points whose fold the room lowers, then "
              "per cap the area over the rest area on the middle and the crossings.", "",
              "| W | compression | pleats: amplitude, period | lowered | "
              + " | ".join(f"cap {cap:g}" for cap in caps) + " |",
              "|---|---|---|---|" + "---|" * len(caps)]
    for row in pleats:
        width, compression, amplitude, period = row["sheet"]
        lines.append(f"| {width:g} m | {compression:g} | {amplitude:g}, {period:g} m | "
                     f"{row['lowered']:.0%} | " + " | ".join(
                         f"{area:.3f}, {crossings}" for _, area, crossings in row["caps"])
                     + " |")
    for cap, table in referee.items():
        lines += ["", f"The converged referee at cap {cap:g} (columns as in its table above; "
                  "then phase by phase, ours / sim at the default W: wavelength, height):",
                  "",
                  "| shot | D (N m) | grid | window | W default, matched | wavelength "
                  "(default W) | height (matched) | correlation | crest motion | area: ours, "
                  "sim |", "|---|---|---|---|---|---|---|---|---|---|", *table]
    lines += ["", markers("deepen")[1]]
    return "\n".join(lines)


def main(argv=None) -> int:
    import tempfile

    from usdwrinkle.render.context import create_context

    from ..blocks import add_write_option, emit
    from . import referee as referee_module

    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.deepen")
    add_write_option(parser, "deepen", "docs/physics.md")
    parser.add_argument("--caps", type=float, nargs="*", default=list(CAPS))
    parser.add_argument("--referee", type=float, nargs="*", default=[], metavar="CAP",
                        help="the converged referee's rows at these caps")
    parser.add_argument("--only", nargs="*", default=list(referee_module.SWEEP),
                        metavar="SHOT", help="the referee's shots (default: all)")
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    parser.add_argument("--figure", type=Path, default=None, metavar="PNG",
                        help="also draw the curtain sample without and with the deepening")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    if args.figure is not None:
        figure(args.figure)
    ctx = create_context()
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-deepen-") as scratch:
        rows = [row for stage in STAGES
                for row in measure_stage(stage, ctx, Path(scratch), args.caps)]
        pleats = pleated_rows(Path(scratch), args.caps)
    referee = {cap: referee_rows(args.cache, cap, args.only) for cap in args.referee}
    emit(args.write, "deepen", report(rows, pleats, referee, args.caps, args.only,
                                      time.perf_counter() - started))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
