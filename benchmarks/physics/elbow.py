"""The demo's elbow beside a cloth simulation of the same sleeve motion (issue 55, item 6).

    python -m benchmarks.physics.elbow [--out docs/images] [--fabric cotton]
                                       [--frames 12,18,24] [--cache .physics-cache]
                                       [--no-figure]

A fine sleeve of the shirt's own shape (sample_stages/shirt.usda: radius 0.38 and length 3
units along x), scaled to a sleeve of radius 10 cm (SCALE m per unit: the sweep's sleeve,
sweep.py), is simulated by the Newton referee (Newton's VBD, the sweep's cloth at a 1
cm grid, with gravity along the shirt's -y). Its end rings ride on the shirt's two joints
(UsdSkel's skinning transforms of the shoulder and the elbow, frame by frame, after half a
second of settling at the rest pose); inside it an arm of two capsules (0.8 of the
sleeve's radius) follows the two bones, as the sweep's arm does. The simulated sleeve,
scaled back into the shirt's units and given the shirt's plaid on its material
coordinates, is rendered by usdwrinkle (no wrinkles: a plain mesh) through the shirt's
camera beside usdwrinkle's own frames of the shirt. Writes OUT/elbow_sim.png (top row:
usdwrinkle on the coarse shirt; bottom row: the simulated sleeve). First it prints the
simulated folds at the elbow frame by frame (fold_table): whether they coarsen as the
elbow closes. About 3 minutes on this 2-core machine (the simulation cached in --cache).
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from .shots import Shot
from .simulate import simulate_newton
from .sweep import NOISE, SweepShot, _smooth_noise

ROOT = Path(__file__).resolve().parents[2]
SHIRT = ROOT / "sample_stages" / "shirt.usda"
SLEEVE = "/World/Arm/Sleeve"
SKELETON = "/World/Arm/Skel"
RADIUS, LENGTH, ELBOW_X = 0.38, 3.0, 1.5   # the shirt's sleeve, in its units
SCALE = 0.10 / RADIUS                        # m per shirt unit: a sleeve of radius 10 cm
SPACING = 0.01                               # m, the referee's grid
FPS = 48                                     # simulated frames a second: 2 per shirt frame
SETTLE = 24                                  # simulated frames at the rest pose first
ARM = 0.8                                    # the arm's radius over the sleeve's


def to_sim(points: np.ndarray) -> np.ndarray:
    """Shirt units (y up) -> the simulation's metres (z up): (x, y, z) -> s (x, -z, y)."""
    p = np.asarray(points, np.float64)
    return SCALE * np.stack([p[..., 0], -p[..., 2], p[..., 1]], -1)


def from_sim(points: np.ndarray) -> np.ndarray:
    p = np.asarray(points, np.float64) / SCALE
    return np.stack([p[..., 0], p[..., 2], -p[..., 1]], -1)


def skinning(frames) -> list[np.ndarray]:
    """UsdSkel's skinning transforms of the shirt's joints (shoulder, elbow) at each frame:
    (2, 4, 4) row-vector matrices from the rest pose to the posed one."""
    from pxr import Usd, UsdSkel

    stage = Usd.Stage.Open(str(SHIRT))
    query = UsdSkel.Cache().GetSkelQuery(UsdSkel.Skeleton(stage.GetPrimAtPath(SKELETON)))
    return [np.array([np.array(m) for m in query.ComputeSkinningTransforms(float(f))])
            for f in frames]


def _apply(matrix: np.ndarray, points: np.ndarray) -> np.ndarray:
    return points @ matrix[:3, :3] + matrix[3, :3]


def shirt_sleeve(fabric: str = "cotton", spacing: float = SPACING,
                 shirt_frames=range(1, 25)) -> tuple[SweepShot, dict]:
    """The sweep shot of the shirt's sleeve, and {shirt frame: simulated frame}."""
    radius, length = RADIUS * SCALE, LENGTH * SCALE
    cols = max(8, int(round(2 * np.pi * radius / spacing / 8)) * 8)
    rows = int(round(length / spacing)) + 1
    around = np.arange(cols) * (2 * np.pi / cols)   # from +y towards +z, as the shirt's
    along = np.linspace(0.0, LENGTH, rows)
    A, X = np.meshgrid(around, along)
    material = np.stack([A * radius, X * SCALE], -1).reshape(-1, 2)
    noise = _smooth_noise(material, 5)
    noise *= NOISE / np.sqrt(np.mean(noise ** 2))
    r = RADIUS + noise.reshape(rows, cols) / SCALE
    rest = np.stack([X, r * np.cos(A), r * np.sin(A)], -1).reshape(-1, 3)
    clean = np.stack([X, RADIUS * np.cos(A), RADIUS * np.sin(A)], -1).reshape(-1, 3)
    pinned = np.zeros((rows, cols), bool)
    pinned[0] = pinned[-1] = True
    pinned = pinned.ravel()
    wrist = np.zeros((rows, cols), bool)
    wrist[rows // 2:] = True          # the pinned ring at x = 3 rides on the elbow joint
    wrist = wrist.ravel()
    shirt_frames = list(shirt_frames)
    transforms = skinning(shirt_frames)
    sim_frame = {f: SETTLE + 2 * (f - shirt_frames[0]) + 1 for f in shirt_frames}
    keys, capsules = [(1, to_sim(rest))], []
    arm = ARM * RADIUS
    bones = [(np.array([-0.1, 0, 0]), np.array([ELBOW_X, 0, 0]), 0),
             (np.array([ELBOW_X, 0, 0]), np.array([LENGTH + 0.1, 0, 0]), 1)]

    def capsules_at(m):
        return [(to_sim(_apply(m[j], p0)), to_sim(_apply(m[j], p1)), arm * SCALE)
                for p0, p1, j in bones]

    capsules.append(capsules_at(np.stack([np.eye(4)] * 2)))
    for f, m in zip(shirt_frames, transforms, strict=True):
        posed = np.where(wrist[:, None], _apply(m[1], rest), _apply(m[0], rest))
        keys.append((sim_frame[f], to_sim(posed)))
        capsules.append(capsules_at(m))
    frames = sim_frame[shirt_frames[-1]]
    shot = Shot(f"shirt-elbow-{fabric}", rows, cols, True, to_sim(rest), material, pinned,
                frames, True, keys, {"bend": (sim_frame[shirt_frames[0]], frames)},
                f"the shirt's sleeve as a {fabric} sleeve of radius 10 cm on the shirt's "
                "joints")
    return SweepShot(shot, fabric, to_sim(clean), capsules), sim_frame


#: the rows either side of the elbow that fold_table measures over (1 cm each)
ELBOW_ROWS = 12


def fold_table(shot: Shot, points: np.ndarray, sim_frame: dict, frames) -> list[dict]:
    """The simulated folds at the elbow, per shirt frame: over the band of 2 ELBOW_ROWS + 1
    rows around the elbow (the whole circumference) and over its inner third (a third of
    the circumference around the column whose low-passed surface is shortest along the
    sleeve at the elbow): the mean and least axial stretch r of the low-pass (the coarse
    compression), the material wavelength and the RMS fold height (measure.wavelength,
    measure.rms)."""
    from .coarse import lowpass
    from .measure import rms, sim_height, wavelength

    index = [sim_frame[f] - 1 for f in frames]
    low = lowpass(shot, points[index])
    heights = sim_height(shot, points[index], low)
    rows, cols = shot.rows, shot.cols
    along = np.diff(shot.material.reshape(rows, cols, 2)[:, :, 1], axis=0)
    mid = rows // 2
    out = []
    for i, frame in enumerate(frames):
        grid = low[i].reshape(rows, cols, 3)
        stretch = np.ones((rows, cols))
        stretch[:-1] = np.linalg.norm(np.diff(grid, axis=0), axis=-1) / along
        band = np.zeros((rows, cols), bool)
        band[mid - ELBOW_ROWS: mid + ELBOW_ROWS + 1] = True
        # the inner third: a third of the circumference around the column shortest at the
        # elbow, tapered (Hann) across for the wavelength: a hard-edged strip of columns
        # read a 6 cm ring fold as 3.7 cm (the edges' leakage)
        third = cols // 3
        centre = int(np.argmin(stretch[mid - 5: mid + 6].mean(0)))
        columns = (centre - third // 2 + np.arange(third)) % cols
        inner = np.zeros((rows, cols), bool)
        inner[mid - ELBOW_ROWS: mid + ELBOW_ROWS + 1, columns] = True
        taper = np.zeros((rows, cols))
        taper[mid - ELBOW_ROWS: mid + ELBOW_ROWS + 1, columns] = np.hanning(third + 2)[1:-1]
        row = {"frame": frame}
        for name, mask, weight in (("band", band, band), ("inner", inner, taper)):
            row[name] = (float(stretch[mask].mean()), float(stretch[mask].min()),
                         wavelength(shot, heights[i], weight.ravel()),
                         rms(heights[i], mask.ravel()))
        out.append(row)
    return out


def sim_stage(path: Path, shot: Shot, points: np.ndarray, sim_frame: dict) -> None:
    """The shirt stage with its skinned sleeve deactivated and the simulated one beside
    it, in the shirt's units, with the shirt's plaid on its material coordinates."""
    from pxr import Sdf, Usd, UsdGeom, UsdShade, Vt

    stage = Usd.Stage.CreateNew(str(path))
    stage.GetRootLayer().subLayerPaths.append(str(SHIRT))  # its textures resolve beside it
    stage.SetStartTimeCode(min(sim_frame))
    stage.SetEndTimeCode(max(sim_frame))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    stage.SetTimeCodesPerSecond(24)
    stage.SetFramesPerSecond(24)
    stage.SetDefaultPrim(stage.GetPrimAtPath("/World"))
    stage.OverridePrim("/World/Arm").SetActive(False)
    mesh = UsdGeom.Mesh.Define(stage, "/World/SimSleeve")
    quads = shot.quads()
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4] * len(quads)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(quads.ravel().tolist()))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.catmullClark)  # smooth, as the shirt
    mesh.CreateDoubleSidedAttr(True)
    for f, s in sim_frame.items():
        mesh.GetPointsAttr().Set(Vt.Vec3fArray.FromNumpy(
            from_sim(points[s - 1]).astype(np.float32)), Usd.TimeCode(f))
    # st: around / circumference, along / length (the shirt's layout), per face corner so
    # that the seam's last column reads s = 1
    cols = shot.cols
    col = np.arange(shot.rows * cols) % cols
    row = np.arange(shot.rows * cols) // cols
    corner = quads.ravel()
    s = col[corner].astype(np.float64)
    first = np.repeat(col[quads[:, 0]], 4)
    s = np.where((s == 0) & (first == cols - 1), cols, s) / cols
    t = row[corner] / (shot.rows - 1)
    st = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray,
                                                 UsdGeom.Tokens.faceVarying)
    st.Set(Vt.Vec2fArray.FromNumpy(np.stack([s, t], 1).astype(np.float32)))
    UsdShade.MaterialBindingAPI.Apply(mesh.GetPrim()).Bind(
        UsdShade.Material(stage.GetPrimAtPath("/World/Looks/Plaid")))
    stage.GetRootLayer().Save()


def render(stage: Path, out: Path, frames: list[int], width: int) -> list[np.ndarray]:
    import OpenImageIO as oiio

    pattern = out / f"{stage.stem}.####.png"
    subprocess.run([sys.executable, "-m", "usdwrinkle", "render", str(stage), str(pattern),
                    "--frames", ",".join(map(str, frames)), "--width", str(width), "--quiet"],
                   check=True)
    return [oiio.ImageBuf(str(out / f"{stage.stem}.{f:04d}.png")).get_pixels(
        oiio.FLOAT) for f in frames]


def figure(top: list[np.ndarray], bottom: list[np.ndarray], path: Path) -> None:
    """Two rows of the frames, cropped to where either row covers."""
    import OpenImageIO as oiio

    covered = np.zeros(top[0].shape[:2], bool)
    for image in top + bottom:
        covered |= image[..., 3] > 0 if image.shape[2] == 4 else image.sum(-1) < 2.9
    ys, xs = np.nonzero(covered)
    pad = 8
    y0, y1 = max(ys.min() - pad, 0), min(ys.max() + pad, covered.shape[0])
    x0, x1 = max(xs.min() - pad, 0), min(xs.max() + pad, covered.shape[1])
    rows = [np.concatenate([im[y0:y1, x0:x1, :3] for im in row], 1) for row in (top, bottom)]
    grid = np.ascontiguousarray(np.concatenate(rows, 0), np.float32)
    buf = oiio.ImageBuf(oiio.ImageSpec(grid.shape[1], grid.shape[0], 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), grid)
    if not buf.write(str(path)):
        raise RuntimeError(buf.geterror())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.physics.elbow")
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "images")
    parser.add_argument("--fabric", default="cotton")
    parser.add_argument("--frames", default="12,18,24")
    parser.add_argument("--width", type=int, default=640)
    parser.add_argument("--cache", type=Path, default=ROOT / ".physics-cache")
    parser.add_argument("--no-figure", action="store_true",
                        help="print the elbow's folds (fold_table) only, draw no figure")
    args = parser.parse_args(argv)
    frames = [int(f) for f in args.frames.split(",")]
    sweep_shot, sim_frame = shirt_sleeve(args.fabric)
    points, seconds, stretch = simulate_newton(sweep_shot, args.cache,
                                               solver={"fps": FPS}, progress=True)
    print(f"simulated {sweep_shot.shot.name}: {points.shape[1]} points, {len(points)} frames, "
          f"{seconds:.0f} s, edge strain p99 {stretch:.3f}")
    print("the simulated folds at the elbow (fold_table): the low-pass's axial stretch r "
          "(mean, least), the material wavelength, the RMS fold height")
    for row in fold_table(sweep_shot.shot, points, sim_frame, range(8, 25, 2)):
        print(f"  frame {row['frame']}: " + "; ".join(
            f"{name} r {r:.2f} (least {least:.2f}), {100 * wl:.1f} cm, {1000 * h:.1f} mm"
            for name, (r, least, wl, h) in ((key, row[key]) for key in ("band", "inner"))))
    if args.no_figure:
        return 0
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-elbow-") as scratch:
        folder = Path(scratch)
        stage = folder / "shirt_sim.usda"
        sim_stage(stage, sweep_shot.shot, points, sim_frame)
        ours = render(SHIRT, folder, frames, args.width)
        theirs = render(stage, folder, frames, args.width)
        args.out.mkdir(parents=True, exist_ok=True)
        figure(ours, theirs, args.out / "elbow_sim.png")
    print(f"wrote {args.out / 'elbow_sim.png'}")
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    raise SystemExit(main())
