"""render --relief: the draw pass sees the folds where the view ray meets them
(draw.glsl's RELIEF; docs/method.md, "Relief"). The oracle is the displaced geometry
(bake --geometry), which Storm draws as usdwrinkle does (the real-client tier), seen
through the same camera."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Gf, Usd, UsdGeom

from usdwrinkle.cli.main import main
from usdwrinkle.scene.topology import triangle_neighbors

from helpers import maps_sheet_stage, read_exr

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


def brute_neighbors(tri: np.ndarray) -> list[list[set]]:
    """Per triangle and corner, every other triangle that has the edge opposite it."""
    out = []
    for t, (a, b, c) in enumerate(tri):
        row = []
        for u, v in ((b, c), (c, a), (a, b)):
            row.append({s for s, other in enumerate(tri) if s != t and u in other and v in other})
        out.append(row)
    return out


def test_triangle_neighbors_across_each_edge():
    from usdwrinkle.authoring.builders import grid_sheet
    from usdwrinkle.scene.topology import triangulate

    rest, counts, indices = grid_sheet(5, 4, 1.0)
    tri = triangulate(counts, indices, rest)[0]
    got = triangle_neighbors(tri)
    want = brute_neighbors(tri)
    for t in range(len(tri)):
        for c in range(3):
            if want[t][c]:
                assert got[t, c] in want[t][c], (t, c)
            else:
                assert got[t, c] == -1, (t, c)  # the sheet's border
    # three triangles on one edge (a fin): each takes the next, round
    fin = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    np.testing.assert_array_equal(triangle_neighbors(fin)[:, 2], [1, 2, 0])
    assert triangle_neighbors(np.zeros((0, 3), int)).shape == (0, 3)


def slanted_sheet(tmp_path: Path, degrees: float) -> Path:
    """The maps tests' analytic sheet compressed to 0.6 along x (crests along y), seen by
    a camera turned ``degrees`` about y from the sheet's normal, across the crests."""
    source = maps_sheet_stage(tmp_path, 0.6)
    stage = Usd.Stage.Open(str(source))
    camera = UsdGeom.Camera.Define(stage, "/Camera")
    turn = np.radians(degrees)
    xform = UsdGeom.Xformable(camera)
    xform.AddTranslateOp().Set(Gf.Vec3d(4.0 * np.sin(turn), 0.0, 4.0 * np.cos(turn)))
    xform.AddRotateYOp().Set(float(degrees))
    stage.GetRootLayer().Save()
    return source


def render(source: Path, out: Path, *args: str) -> dict:
    assert main(["render", str(source), str(out), "--frames", "1", "--width", "320",
                 "--height", "240", "--camera", "/Camera", "--quiet", *args]) == 0
    return read_exr(out)


def unit_normals(channels: dict) -> np.ndarray:
    n = np.stack([channels["N.X"], channels["N.Y"], channels["N.Z"]], -1)
    return n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-12)


def luminance(channels: dict) -> np.ndarray:
    return 0.2126 * channels["R"] + 0.7152 * channels["G"] + 0.0722 * channels["B"]


def covered(*frames: dict, margin: int = 3) -> np.ndarray:
    """Pixels every frame covers, ``margin`` pixels in from any frame's outline."""
    mask = np.logical_and.reduce([frame["A"] > 0.999 for frame in frames])
    for _ in range(margin):
        mask &= np.roll(mask, 1, 0) & np.roll(mask, -1, 0) & np.roll(mask, 1, 1) & \
            np.roll(mask, -1, 1)
    return mask


@pytest.fixture(scope="module")
def slanted(gl_context, tmp_path_factory):
    folder = tmp_path_factory.mktemp("relief")
    source = slanted_sheet(folder, 55.0)
    assert main(["bake", str(source), str(folder / "geometry.usdc"), "--quiet", "--geometry",
                 "--frames", "1"]) == 0
    return {"plain": render(source, folder / "plain.exr"),
            "relief": render(source, folder / "relief.exr", "--relief"),
            "displaced": render(source, folder / "displaced.exr", "--no-wrinkles",
                                "--sublayer", str(folder / "geometry.usdc"))}


def test_relief_shows_the_sheet_as_its_displaced_geometry_stands(slanted):
    """At 55 degrees across the crests, half of each fold's flank faces away from the
    camera. Drawn on the coarse surface those flanks stand as black bands (the issue's
    "thick black rings"): the normals differ from the displaced mesh's by 52 degrees at
    the median. With the relief the crests hide them: measured 2026-12-06, normals within
    0.24 degrees at the median, 6.8 at the 90th percentile (the crests' outlines),
    luminance correlation 0.925 against the plain draw's 0.283."""
    mask = covered(*slanted.values())
    assert mask.sum() > 20000
    truth = unit_normals(slanted["displaced"])
    angle = {name: np.degrees(np.arccos(np.clip(np.sum(unit_normals(slanted[name]) * truth,
                                                       -1), -1.0, 1.0)))[mask]
             for name in ("plain", "relief")}
    assert np.median(angle["relief"]) < 1.0
    assert np.percentile(angle["relief"], 90) < 10.0
    assert np.median(angle["plain"]) > 30.0  # the oracle tells the two apart
    look = luminance(slanted["displaced"])[mask]
    relief = np.corrcoef(luminance(slanted["relief"])[mask], look)[0, 1]
    plain = np.corrcoef(luminance(slanted["plain"])[mask], look)[0, 1]
    assert relief >= 0.85, relief
    assert plain <= 0.5, plain


def view_directions(source: Path, width: int, height: int) -> np.ndarray:
    """Per pixel centre, the unit vector from the surface towards the eye of the stage's
    /Camera at frame 1, as the engine frames the render with it."""
    from usdwrinkle.scene.camera import towards_eye, usd_camera

    stage = Usd.Stage.Open(str(source))
    record = usd_camera(stage.GetPrimAtPath("/Camera"), Usd.TimeCode(1.0), width / height)
    return towards_eye(record, width, height)


def test_no_bent_normal_faces_away_from_the_eye(slanted, tmp_path):
    """The horizon (contract.HORIZON_COSINE, docs/method.md): drawn on the coarse surface,
    a normal the folds bend away from the eye is turned back until its cosine with the
    view is HORIZON_COSINE. At 55 degrees across the crests, 43% of the sheet's pixels
    are turned (measured 2026-12-06; before, their normals' least cosine was -0.44, and
    the preview surface cut its specular off where it crossed 0: dark beads and bands).
    The displaced geometry's own normals all face the eye (least cosine 0.29)."""
    from usdwrinkle.method.contract import HORIZON_COSINE

    height, width = slanted["plain"]["A"].shape
    towards_eye = view_directions(slanted_sheet(tmp_path, 55.0), width, height)
    mask = covered(*slanted.values())
    cosine = {name: np.sum(unit_normals(slanted[name]) * towards_eye, -1)[mask]
              for name in ("plain", "displaced")}
    assert cosine["displaced"].min() > 0.2  # the oracle: a seen surface faces the eye
    assert cosine["plain"].min() >= HORIZON_COSINE - 0.01, cosine["plain"].min()
    assert np.mean(cosine["plain"] < HORIZON_COSINE + 0.02) > 0.3  # the case is exercised


def beside_displaced(stage: Path, tmp_path: Path, width: int, *draws) -> dict:
    """A sample stage's frame 24 rendered for each (name, render options) in ``draws``,
    and "displaced": its displaced geometry (bake --geometry) through the same camera."""
    geometry = str(tmp_path / "geometry.usdc")
    assert main(["bake", str(stage), geometry, "--quiet", "--geometry", "--frames", "24"]) == 0
    frames = {}
    for name, args in (*draws, ("displaced", ("--no-wrinkles", "--sublayer", geometry))):
        out = tmp_path / f"{name}.exr"
        assert main(["render", str(stage), str(out), "--frames", "24", "--width", str(width),
                     "--quiet", *args]) == 0
        frames[name] = read_exr(out)
    return frames


def test_the_pillows_plain_draw_nearer_its_displaced_geometry(gl_context, tmp_path):
    """The squeezed pillow's front at frame 24, drawn on the coarse surface: with the
    horizon its look is nearer the displaced geometry's (luminance correlation over the
    pixels both cover; measured 2026-12-06 at 360 px: 0.641, against 0.554 before; 8% of
    its pixels had normals facing away from the eye)."""
    frames = beside_displaced(SAMPLES / "pillow.usda", tmp_path, 360, ("plain", ()))
    mask = covered(*frames.values())
    assert mask.sum() > 15000
    plain = np.corrcoef(luminance(frames["plain"])[mask],
                        luminance(frames["displaced"])[mask])[0, 1]
    assert plain >= 0.6, plain


def test_relief_sees_more_crest_than_valley(slanted):
    """The seen height (the height AOV) leans to the crests: the valleys behind them are
    hidden. Drawn on the coarse surface it averages about the wave's own mean (measured
    2026-12-06: 0.03 of the largest amplitude; with the relief 0.34)."""
    mask = covered(*slanted.values())
    plain = slanted["plain"]["wrinkle.height"][mask]
    relief = slanted["relief"]["wrinkle.height"][mask]
    amplitude = slanted["plain"]["wrinkle.amplitude"][mask].max()
    assert relief.mean() - plain.mean() > 0.1 * amplitude


def test_relief_without_wrinkles_is_the_plain_frame(gl_context, tmp_path):
    source = slanted_sheet(tmp_path, 55.0)
    plain = render(source, tmp_path / "plain.exr", "--no-wrinkles")
    relief = render(source, tmp_path / "relief.exr", "--no-wrinkles", "--relief")
    for name in ("R", "G", "B", "A", "N.X", "N.Y", "N.Z"):
        np.testing.assert_array_equal(relief[name], plain[name])


def test_the_shirts_relief_looks_like_its_displaced_geometry(gl_context, tmp_path):
    """The demo's frame 24: the draw pass with the relief is nearer the displaced
    geometry's look than without it (luminance correlation over the pixels all three
    cover; measured 2026-12-06 at 540 px: 0.895 with it, 0.845 without; 0.904 and
    0.851 at 1080 px)."""
    frames = beside_displaced(SAMPLES / "shirt.usda", tmp_path, 540, ("plain", ()),
                              ("relief", ("--relief",)))
    mask = covered(*frames.values())
    look = luminance(frames["displaced"])[mask]
    relief = np.corrcoef(luminance(frames["relief"])[mask], look)[0, 1]
    plain = np.corrcoef(luminance(frames["plain"])[mask], look)[0, 1]
    assert relief >= plain + 0.03 and relief >= 0.85, (relief, plain)
