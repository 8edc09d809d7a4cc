"""What deepening the coarse pleats would buy (issue 55; measured, not built): where the
room (method/contract.py FOLD_ROOM) lowers a fold, the length the lowered fold does not
draw goes into an offset of the surface away from its centre of curvature, as the
referee's cloth sharpens the pleats its low-pass rounds (docs/physics.md, "Can a height
field meet the height bar and the area bar at once?").

    python -m benchmarks.physics.deepen [--write docs/physics.md] [--caps 0.5 0.75 1]
                                        [--referee CAP ...] [--cache .physics-cache]
                                        [--figure docs/images/physics_deepen.png]

Per coarse point (numpy, after the engine's frame; nothing of it is in the passes):
- kappa_d, the posed surface's normal curvature along the fold's direction d, signed
  (positive where the surface bends towards its normal): a least-squares fit of the second
  fundamental form to 2 (e.n) / |e|^2 over the ring's edges e;
- D, the length the law's full fold holds over the drawn (lowered) fold's, at their slopes
  a |k| (folds.length_of);
- the offset ``-sign(kappa_d) c`` along the normal, c = (D - 1) / |kappa_d| (an offset c
  away from the centre lengthens the surface along d by 1 + c |kappa_d|), at most ``cap``
  times the full fold's height a and at most a (|kappa_d| a) / FOLD_ROOM, so that it
  fades where the surface turns flat along d (no step where kappa_d changes sign).
The offset is interpolated over the fine mesh as the folds' amplitude is and added along
the interpolated coarse normals (as the geometry bake displaces).

Sample stages: blend.py's compressed region at frame 24 (5 levels), its area over its rest
area and the pairs of its fine triangles that pass through each other
(geometry.measure.self_intersections). ``--referee``: the converged referee's rows
(referee.sweep_report, the simulations cached) with the offset added to every geometry
bake of the shot (about 4 minutes a cap here). ``--figure``: the curtain sample's frame 24
rendered from its geometry bake (usdwrinkle render --no-wrinkles over the bake layer;
normals taken from the displaced triangles, alike on both sides), as built (left) and with
the offset at FIGURE_CAP (right).
"""
from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from .blend import _area, aligned_corners, stage_regions

ROOT = Path(__file__).resolve().parents[2]
STAGES = ("curtain", "shirt", "zeppelin")
CAPS = (0.5, 0.75, 1.0)
FIGURE_CAP = 0.75


def curvature_along(posed: np.ndarray, normals: np.ndarray, topology,
                    direction: np.ndarray) -> np.ndarray:
    """Each point's normal curvature along ``direction`` (projected into its tangent
    plane), positive where the surface bends towards the normal: the second fundamental
    form fitted over the ring (least squares of 2 (e.n) / |e|^2 against the edges'
    tangent directions); 0 where the ring has fewer than 3 points."""
    n = len(posed)
    offsets = np.asarray(topology.neighbor_offsets, np.int64)
    nb = np.asarray(topology.neighbor_indices, np.int64)
    src = np.repeat(np.arange(n), np.diff(offsets))
    nrm = normals / np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-30)
    axis = np.where(np.abs(nrm[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]])
    ta = np.cross(nrm, axis)
    ta /= np.linalg.norm(ta, axis=1, keepdims=True)
    tb = np.cross(nrm, ta)
    e = posed[nb] - posed[src]
    e2 = np.maximum(np.sum(e * e, 1), 1e-30)
    kappa = 2 * np.sum(e * nrm[src], 1) / e2
    x, y = np.sum(e * ta[src], 1), np.sum(e * tb[src], 1)
    length = np.maximum(np.hypot(x, y), 1e-30)
    x, y = x / length, y / length
    rows = np.stack([x * x, 2 * x * y, y * y], 1)
    ata = np.zeros((n, 3, 3))
    atb = np.zeros((n, 3))
    np.add.at(ata, src, rows[:, :, None] * rows[:, None, :])
    np.add.at(atb, src, rows * kappa[:, None])
    enough = np.diff(offsets) >= 3
    form = np.zeros((n, 3))
    form[enough] = np.linalg.solve(ata[enough] + 1e-12 * np.eye(3),
                                   atb[enough][..., None])[..., 0]
    d = direction - np.sum(direction * nrm, 1, keepdims=True) * nrm
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-30)
    dx, dy = np.sum(d * ta, 1), np.sum(d * tb, 1)
    return np.where(enough, form[:, 0] * dx * dx + 2 * form[:, 1] * dx * dy
                    + form[:, 2] * dy * dy, 0.0)


def deepening(posed, normals, topology, law: dict, drawn: np.ndarray,
              wave_vector: np.ndarray, height_profile, cap: float) -> np.ndarray:
    """Each coarse point's offset along its normal (module docstring). ``law``: the numpy
    reference's crush (its direction and over_room); ``drawn``: the amplitude the surface
    draws, ``wave_vector`` the engine's."""
    from usdwrinkle.method.contract import FOLD_ROOM
    from usdwrinkle.method.folds import gradient_of, length_of

    kappa = curvature_along(posed, normals, topology, law["direction"])
    drawn = np.asarray(drawn, np.float64)
    slope = np.linalg.norm(np.asarray(wave_vector, np.float64), axis=1)
    gradient = gradient_of(np.asarray(height_profile, np.float64))
    full = drawn * np.maximum(law["over_room"], 1.0)
    gain = length_of(gradient, full * slope) / np.maximum(length_of(gradient, drawn * slope),
                                                          1e-12)
    bend = np.maximum(np.abs(kappa), 1e-9)
    c = np.minimum(np.minimum((gain - 1.0) / bend, cap * full), full * bend * full / FOLD_ROOM)
    return np.where(np.abs(kappa) > 1e-9, -np.sign(kappa) * c, 0.0)


def _welded(at: np.ndarray) -> np.ndarray:
    """The fine faces of a region (per-face corner points) as indices of shared points."""
    key = np.round(at.reshape(-1, 3) * 1e7).astype(np.int64)
    return np.unique(key, axis=0, return_inverse=True)[1].reshape(-1, 3)


def measure_stage(name: str, caps=CAPS) -> list[dict]:
    from usdwrinkle.geometry.measure import self_intersections
    from usdwrinkle.reference.blend import blended_height

    rows = []
    for _, path, region in stage_regions(name, None):
        fields, law = region.fields, region.law
        drawn = fields["amplitude"].astype(np.float64)
        k, theta = aligned_corners(region.corners, fields["wave_vector"],
                                   fields["phase"].astype(np.float64))
        theta = theta[:, None, :] + np.einsum("mcj,mvcj->mvc", k, region.offset)
        h = blended_height(region.bary * drawn[region.corners][:, None, :], theta,
                           region.height)
        faces = _welded(region.at)
        inside = region.compressed & (law["over_room"] > 0)
        row = {"stage": name, "mesh": path, "lowered": float(np.mean(
            law["over_room"][inside] > 1.0 + 1e-6)) if inside.any() else 0.0, "caps": []}
        for cap in (0.0, *caps):
            low = deepening(region.posed, fields["normals"][:, :3].astype(np.float64),
                            region.topology, law, drawn, fields["wave_vector"],
                            region.height, cap)
            at = region.at + (h + np.einsum("mvc,mc->mv", region.bary,
                                            low[region.corners]))[..., None] * region.normal
            points = np.zeros((faces.max() + 1, 3))
            points[faces.ravel()] = at.reshape(-1, 3)
            row["caps"].append((cap, float(_area(at)[region.chosen].sum() / region.rest_area),
                                int(len(self_intersections(points, faces))),
                                float(np.percentile(np.abs(low[inside]), 90))
                                if inside.any() else 0.0))
        rows.append(row)
    return rows


def _offset_now(engine, path: str, cap: float) -> tuple[np.ndarray, np.ndarray]:
    """The offset of ``path``'s coarse points at the engine's computed frame (the numpy
    reference's crush on its posed points), and their posed normals."""
    from usdwrinkle.reference.crush import crush

    record = engine.meshes[path]
    computed = engine.read_fields(path)
    fields = computed.arrays()
    posed = fields["points"].astype(np.float64)
    normals = fields["normals"][:, :3].astype(np.float64)
    law = crush(record.rest_points, posed, record.topology, record.params.q,
                record.params.width, slack=record.params.slack, hold=record.params.hold,
                coarsening=record.params.coarsening)
    return deepening(posed, normals, record.topology, law, computed.drawn_amplitude,
                     fields["wave_vector"], record.params.height_profile, cap), normals


def _fine_weights(rest: np.ndarray, triangles: np.ndarray, levels: int):
    """(coarse corners, barycentrics) of each fine vertex of the geometry bake's
    subdivision (geometry.subdivide), and the fine mesh."""
    from usdwrinkle.geometry.subdivide import subdivide

    fine = subdivide(rest, triangles, levels)
    return triangles[fine.vertex_triangle], fine.vertex_bary.astype(np.float64), fine


def _offsets(stage_path: str, frames: int, cap: float) -> tuple:
    """(frames, coarse points) offsets of the stage's one wrinkled mesh over its shot,
    with its rest points and triangles."""
    from usdwrinkle.engine import WrinkleEngine

    engine = WrinkleEngine(stage_path)
    try:
        path = engine.wrinkled_paths[0]
        out = []
        for frame in range(1, frames + 1):
            engine.compute_frame(frame)
            out.append(_offset_now(engine, path, cap)[0])
        record = engine.meshes[path]
        return (np.array(out), record.rest_points.astype(np.float64),
                np.asarray(record.topology.triangles, np.int64))
    finally:
        engine.release()


def deepened_bake(cap: float):
    """oracle.bake with the offset added to the wrinkled geometry (module docstring)."""
    import functools

    from .oracle import bake
    from .stage import grid_order, levels

    def adjust(shot, stage, points, normals):
        offsets, rest, triangles = _offsets(stage, shot.frames, cap)
        corners, bary, fine = _fine_weights(rest, triangles, levels(shot))
        order = grid_order(shot, fine.points.astype(np.float64))
        on_fine = np.einsum("vc,fvc->fv", bary, offsets[:, corners])[:, order]
        return points + on_fine[..., None] * normals
    return functools.partial(bake, adjust=adjust)


def referee_rows(cache: Path, cap: float) -> list[str]:
    """The converged referee's table rows with the offset at ``cap``, then its phase by
    phase lines."""
    from . import referee

    plain = referee.bake
    referee.bake = deepened_bake(cap)  # sweep_row's and our_area's bakes
    try:
        text = referee.sweep_report(list(referee.SWEEP), cache, "converged")
    finally:
        referee.bake = plain
    lines = text.splitlines()
    return ([line for line in lines if line.startswith("| ") and not line.startswith("| shot")]
            + [""] + [line for line in lines if line.startswith("- ")])


def _deepened_layer(stage_path: str, layer: str, frame: int, cap: float) -> None:
    """Add the offset at ``cap`` to the fine meshes of the geometry bake ``layer`` at
    ``frame`` (cap 0: none), their normals from the displaced triangles."""
    from pxr import Usd, UsdGeom, Vt

    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.geometry.subdivide import fine_point_count
    from usdwrinkle.scene.topology import build_topology, vertex_normals

    baked = Usd.Stage.Open(layer)
    engine = WrinkleEngine(stage_path)
    try:
        engine.compute_frame(frame)
        for path in engine.wrinkled_paths:
            record = engine.meshes[path]
            offset, normals = _offset_now(engine, path, cap)
            mesh = UsdGeom.Mesh(baked.GetPrimAtPath(path + "_wrinkled"))
            points = np.asarray(mesh.GetPointsAttr().Get(frame), np.float64)
            faces = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(), np.int64)
            triangles = np.asarray(record.topology.triangles, np.int64)
            levels = next(level for level in range(11) if fine_point_count(
                len(record.rest_points), triangles, level) == len(points))
            corners, bary, _ = _fine_weights(record.rest_points, triangles, levels)
            along = np.einsum("vc,vcj->vj", bary, normals[corners])
            along /= np.linalg.norm(along, axis=1, keepdims=True)
            points += np.einsum("vc,vc->v", bary, offset[corners])[:, None] * along
            mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(points.astype(np.float32)), frame)
            shaded = vertex_normals(points, build_topology(np.full(len(faces) // 3, 3), faces,
                                                           points))
            mesh.GetNormalsAttr().Set(Vt.Vec3fArray.FromNumpy(shaded), frame)
    finally:
        engine.release()
    baked.GetRootLayer().Save()


def figure(out: Path, cap: float = FIGURE_CAP, frame: int = 24, name: str = "curtain") -> None:
    """A sample stage (the curtain) as built and deepened, side by side (module
    docstring)."""
    import tempfile

    import OpenImageIO as oiio

    from usdwrinkle import api

    stage = str(ROOT / "sample_stages" / f"{name}.usda")
    halves = []
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-deepen-") as scratch:
        for side in (0.0, cap):
            layer = api.bake(stage, f"{scratch}/geometry_{side:g}.usdc", frames=[frame],
                             geometry=True)
            _deepened_layer(stage, layer, frame, side)
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


def report(rows: list[dict], referee: dict, caps, seconds: float) -> str:
    from ..blocks import markers

    referee_caps = "".join(f" {cap:g}" for cap in referee)
    command = "python -m benchmarks.physics.deepen" + (
        f" --referee{referee_caps}" if referee else "") + " --write docs/physics.md"
    lines = [
        markers("deepen")[0], "", f"Made by `{command}` ({seconds:.0f} s here).", "",
        "Sample stages at frame 24, the compressed region: the share of its points whose fold "
        "the room lowers; then per cap (0: the law as built) the area over the rest area, "
        "the pairs of fine triangles that pass through each other and the 90th percentile "
        "of |offset| (m).", "",
        "| stage | lowered | " + " | ".join(f"cap {cap:g}" for cap in (0.0, *caps)) + " |",
        "|---|---|" + "---|" * (len(caps) + 1)]
    for row in rows:
        lines.append(f"| {row['stage']} | {row['lowered']:.0%} | " + " | ".join(
            f"{area:.3f}, {crossings}, {p90:.3f}" for _, area, crossings, p90 in row["caps"])
            + " |")
    for cap, table in referee.items():
        lines += ["", f"The converged referee with the offset at cap {cap:g} (columns as in "
                  "its table above; then phase by phase, ours / sim at the default W: "
                  "wavelength, height):", "",
                  "| shot | D (N m) | grid | window | W default, matched | wavelength "
                  "(default W) | height (matched) | correlation | crest motion | area: ours, "
                  "sim |", "|---|---|---|---|---|---|---|---|---|---|", *table]
    lines += ["", markers("deepen")[1]]
    return "\n".join(lines)


def main(argv=None) -> int:
    from ..blocks import add_write_option, emit

    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.deepen")
    add_write_option(parser, "deepen", "docs/physics.md")
    parser.add_argument("--caps", type=float, nargs="*", default=list(CAPS))
    parser.add_argument("--referee", type=float, nargs="*", default=[], metavar="CAP",
                        help="the converged referee's rows at these caps")
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    parser.add_argument("--figure", type=Path, default=None, metavar="PNG",
                        help="also draw the curtain sample as built and deepened")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    if args.figure is not None:
        figure(args.figure)
    rows = [row for stage in STAGES for row in measure_stage(stage, args.caps)]
    referee = {cap: referee_rows(args.cache, cap) for cap in args.referee}
    emit(args.write, "deepen", report(rows, referee, args.caps,
                                      time.perf_counter() - started))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
