"""Irregular folds (wrinkle:irregularity; docs/method.md, "Irregular folds"): three smooth
fields N over the rest surface shift each corner's phase by beta u . N (u its wave's rest
direction), the local wave is k + beta grad (u . N), and each amplitude is scaled by
|k| / |k'| so that the slope stays the fold law's. On the analytic sheet (uniform
compression, one wave) the displaced geometry and the maps follow that law point by point
(numpy: usdwrinkle/reference/blend.py); the wrinkled sheet keeps the regular folds'
length; the draw pass draws the taller folds; and the control is checked and authored
like the others. tests/test_blend.py checks the
shader's blend against its numpy reference on random triangles."""
from __future__ import annotations

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom

from usdwrinkle.cli.main import main
from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.method.contract import (
    IRREGULARITY_FACTOR_MAX,
    IRREGULARITY_FACTOR_MIN,
    IRREGULARITY_GAIN,
    IRREGULARITY_SCALE,
)
from usdwrinkle.method.profiles import default_profile
from usdwrinkle.reference.blend import irregularity_field, profile
from usdwrinkle.usd import schema

from helpers import MAPS_SIZE, MAPS_WIDTH, bake_maps, fold_law, maps_sheet_stage, read_pixels

RATIO = 0.7
IRREGULARITY = 0.3


def irregular_sheet(tmp_path, irregularity, name="sheet.usda"):
    """The maps tests' analytic sheet (31 x 31 points over 2 units, W 0.3, compressed by
    RATIO along x), with ``irregularity`` authored."""
    path = maps_sheet_stage(tmp_path, RATIO, name=name)
    stage = Usd.Stage.Open(str(path))
    if irregularity is not None:
        stage.GetPrimAtPath("/Sheet").CreateAttribute(
            schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(float(irregularity))
    stage.Save()
    return path


def law(x, y, irregularity, phase):
    """The irregular fold law's height on the analytic sheet at posed (x, y): the one
    wave's a and k (the fold law's) along +x, its phase ``phase`` at the origin; its rest
    direction u = +x, so the phase moves by beta N_x at the rest point (x / RATIO, y, 0),
    and grad_p N_x = (dN_x/dX / RATIO, dN_x/dY); Lambda IRREGULARITY_SCALE W. (The wave's
    sign does not matter: (-k, -phi) has u = -x, and the fold profile is even.)"""
    a, k = (float(v) for v in fold_law(RATIO, MAPS_WIDTH))
    beta = IRREGULARITY_GAIN * irregularity
    rest = np.stack([x / RATIO, y, np.zeros_like(x)], -1)
    fields, gradients = irregularity_field(rest, 1.0 / (IRREGULARITY_SCALE * MAPS_WIDTH))
    field, gradient = fields[..., 0], gradients[..., 0, :]
    local = np.stack([k + beta * gradient[..., 0] / RATIO, beta * gradient[..., 1]], -1)
    factor = np.clip(k / np.linalg.norm(local, axis=-1), IRREGULARITY_FACTOR_MIN,
                     IRREGULARITY_FACTOR_MAX)
    return a * factor * profile(default_profile(), phase + k * x + beta * field), a, factor


def fitted_phase(x, y, height):
    """The regular wave's phase at the origin, fitted to a regular bake's heights (the
    relaxation settles it; the law does not say it)."""
    a, k = (float(v) for v in fold_law(RATIO, MAPS_WIDTH))
    trials = np.linspace(0, 2 * np.pi, 721)[:-1]
    misfit = [np.abs(a * profile(default_profile(), t + k * x) - height).mean()
              for t in trials]
    return float(trials[int(np.argmin(misfit))])


def fine_heights(tmp_path, irregularity, name):
    source = irregular_sheet(tmp_path, irregularity, name=f"{name}.usda")
    layer = tmp_path / f"{name}_geometry.usdc"
    assert main(["bake", str(source), str(layer), "--quiet", "--geometry",
                 "--levels", "3"]) == 0
    baked = Usd.Stage.Open(str(layer))
    points = np.asarray(UsdGeom.Mesh(baked.GetPrimAtPath("/Sheet_wrinkled"))
                        .GetPointsAttr().Get(1), np.float64)
    faces = np.asarray(UsdGeom.Mesh(baked.GetPrimAtPath("/Sheet_wrinkled"))
                       .GetFaceVertexIndicesAttr().Get(), np.int64).reshape(-1, 3)
    return points, faces


def test_the_geometry_and_the_maps_follow_the_irregular_law(gl_context, tmp_path):
    """bake --geometry and bake --maps of the analytic sheet at irregularity 0.3: every
    fine vertex's and every texel's height is the law's, within 2% of the regular
    amplitude, away from the free border; the field moves the folds (the regular wave
    misses the irregular heights by a third of a on average), and the factor reaches both
    its bounds there (0.5 and 2)."""
    regular, _ = fine_heights(tmp_path, None, "regular")
    inner = (np.abs(regular[:, 0]) < 0.75 * RATIO) & (np.abs(regular[:, 1]) < 0.75)
    phase = fitted_phase(regular[inner, 0], regular[inner, 1], regular[inner, 2])
    points, _ = fine_heights(tmp_path, IRREGULARITY, "irregular")
    x, y, z = points[inner, 0], points[inner, 1], points[inner, 2]
    expected, a, factor = law(x, y, IRREGULARITY, phase)
    assert np.abs(z - expected).max() <= 0.02 * a
    assert np.abs(z - regular[inner, 2]).mean() > 0.3 * a
    assert factor.min() == IRREGULARITY_FACTOR_MIN and factor.max() == IRREGULARITY_FACTOR_MAX

    layer = tmp_path / "maps.usda"
    assert bake_maps(irregular_sheet(tmp_path, IRREGULARITY, "maps_sheet.usda"), layer) == 0
    height = read_pixels(tmp_path / "maps_maps" / "Sheet.height.0001.exr")[..., 0]
    # texel (row, column) sits at st = ((column + 0.5) / size, 1 - (row + 0.5) / size)
    s = (np.arange(MAPS_SIZE) + 0.5) / MAPS_SIZE
    rest_x, rest_y = np.meshgrid(2 * s - 1, 1 - 2 * s)
    keep = (np.abs(rest_x) < 0.75) & (np.abs(rest_y) < 0.75)
    expected, a, _ = law(RATIO * rest_x[keep], rest_y[keep], IRREGULARITY, phase)
    assert np.abs(height[keep] - expected).max() <= 0.02 * a


def area(points, faces):
    corners = points[faces]
    return 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                         corners[:, 2] - corners[:, 0]), axis=1)


def test_irregular_folds_keep_the_length_of_the_regular_ones(gl_context, tmp_path):
    """The factor keeps each fold's slope: the displaced sheet's area inside the border
    stays within 1.5% of the regular folds' (which restore the rest length: docs/method.md,
    "Length restoration") at irregularity 0.2 and 0.4."""
    def inner_area(points, faces):
        centre = points[faces].mean(1)
        inside = (np.abs(centre[:, 0]) < 0.75 * RATIO) & (np.abs(centre[:, 1]) < 0.75)
        return area(points, faces)[inside].sum()

    regular = inner_area(*fine_heights(tmp_path, None, "regular"))
    for irregularity in (0.2, 0.4):
        ratio = inner_area(*fine_heights(tmp_path, irregularity, f"i{irregularity}")) / regular
        assert abs(ratio - 1) <= 0.015, (irregularity, ratio)


def test_the_draw_pass_draws_the_wider_folds_taller(gl_context, tmp_path):
    """The draw pass runs the irregular blend: the regular sheet's height never passes
    the fold law's amplitude a; the irregular one's reaches 1.3 a where its folds are
    widest, and never passes IRREGULARITY_FACTOR_MAX a."""
    a = float(fold_law(RATIO, MAPS_WIDTH)[0])
    tallest = []
    for irregularity in (None, IRREGULARITY):
        engine = WrinkleEngine(str(irregular_sheet(tmp_path, irregularity)), ctx=gl_context)
        try:
            tallest.append(float(np.abs(engine.render_frame(1.0, 256, 256)
                                        ["wrinkle.height"].pixels).max()))
        finally:
            engine.release()
    assert tallest[0] <= a * (1 + 1e-4)
    assert 1.3 * a <= tallest[1] <= IRREGULARITY_FACTOR_MAX * a * (1 + 1e-4)


@pytest.mark.parametrize("value", [-0.1, 0.6])
def test_an_irregularity_out_of_range_is_refused(gl_context, tmp_path, capsys, value):
    """check and apply refuse an irregularity outside [0, IRREGULARITY_MAX] and name it."""
    path = irregular_sheet(tmp_path, value)
    assert main(["check", str(path), "--wrinkles-only"]) != 0
    assert "irregularity" in capsys.readouterr().out
    clean = irregular_sheet(tmp_path, None, name="clean.usda")
    before = clean.read_bytes()
    assert main(["apply", str(clean), "/Sheet", "--irregularity", str(value)]) != 0
    assert "irregularity" in capsys.readouterr().err
    assert clean.read_bytes() == before


def test_apply_authors_the_irregularity(tmp_path):
    path = irregular_sheet(tmp_path, None)
    assert main(["apply", str(path), "/Sheet", "--irregularity", "0.25"]) == 0
    stage = Usd.Stage.Open(str(path))  # held: its prims die with it
    assert stage.GetPrimAtPath("/Sheet").GetAttribute(schema.IRREGULARITY).Get() == \
        pytest.approx(0.25)


def test_irregular_folds_ride_with_the_cloth_under_rigid_motion(gl_context, tmp_path):
    """The field lives on the rest surface: the analytic sheet posed, then turned and
    moved rigidly, bakes the same irregular fine mesh turned and moved (within 1e-5 of
    the sheet's size, as the regular folds: tests/test_geometry.py)."""
    from conftest import grid_sheet
    from helpers import point_cache_stage, rotation_matrix

    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([RATIO, 1, 1], np.float32)
    rotation = rotation_matrix([0.2, 0.9, -0.4], 0.8)
    shift = np.array([1.0, -0.5, 2.0])
    fine = {}
    for name, points in (("plain", posed), ("moved", posed @ rotation.T + shift)):
        stage = point_cache_stage(rest, {1: np.asarray(points, np.float32)}, counts, indices,
                                  width=MAPS_WIDTH)
        stage.GetPrimAtPath("/Sheet").CreateAttribute(
            schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(IRREGULARITY)
        source = tmp_path / f"{name}.usda"
        stage.GetRootLayer().Export(str(source))
        layer = tmp_path / f"{name}_g.usdc"
        assert main(["bake", str(source), str(layer), "--quiet", "--geometry",
                     "--levels", "2"]) == 0
        baked = Usd.Stage.Open(str(layer))
        fine[name] = np.asarray(UsdGeom.Mesh(baked.GetPrimAtPath("/Sheet_wrinkled"))
                                .GetPointsAttr().Get(1), np.float64)
    extent = np.ptp(fine["plain"], axis=0).max()
    assert np.abs(fine["moved"] - (fine["plain"] @ rotation.T + shift)).max() <= 1e-5 * extent


def test_irregular_folds_keep_the_crests_stable_under_a_joint_change(gl_context, tmp_path):
    """The shirt at irregularity 0.3 under the stability bars (benchmarks.stability,
    tests/test_stability.py): every joint turned 0.01 degrees about z moves the crests on
    at most 2% of its wrinkled pixels at frames 8-24, 0.1 degrees on at most 5%. Measured
    on 2026-12-05 over z and 8 random axes: at most 0.03% and 0.9% (0.3% and 3.8% while
    the shift's directions were taken through each triangle's map)."""
    from benchmarks import stability
    from usdwrinkle.layerinfo import copy_stage_info

    path = str(tmp_path / "shirt.usda")
    layer = Sdf.Layer.CreateNew(path)
    layer.subLayerPaths.append(str(stability.SHIRT))
    copy_stage_info(Sdf.Layer.FindOrOpen(str(stability.SHIRT)), layer)
    stage = Usd.Stage.Open(layer)
    stage.OverridePrim(stability.SLEEVE).CreateAttribute(
        schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(IRREGULARITY)
    stage.Save()
    shares = stability.perturbation(path, str(tmp_path), ctx=gl_context)
    assert all(v <= 0.02 for v in shares[0.01].values()), shares
    assert all(v <= 0.05 for v in shares[0.1].values()), shares


def test_the_second_wave_system_runs_irregular_too(gl_context):
    """The pillow sample (wrinkle:biaxial, the TWO_SYSTEMS variant) at irregularity 0.3:
    both systems take their shift; the frame's heights move, stay finite, and stay within
    IRREGULARITY_FACTOR_MAX times the regular frame's tallest (each corner's amplitude is
    scaled by at most that)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    heights = []
    for value in (0.0, IRREGULARITY):  # authored: the fallback is irregular since 2026-12-07
        stage = Usd.Stage.Open(str(root / "sample_stages" / "pillow.usda"))
        stage.SetEditTarget(stage.GetSessionLayer())
        stage.OverridePrim("/World/Pillow").CreateAttribute(
            schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(value)
        engine = WrinkleEngine(stage, ctx=gl_context)
        try:
            assert engine.meshes["/World/Pillow"].params.biaxial > 0
            heights.append(engine.render_frame(24.0, 160, 120)["wrinkle.height"].pixels[..., 0]
                           .copy())
        finally:
            engine.release()
    regular, irregular = heights
    assert np.all(np.isfinite(irregular))
    assert np.abs(irregular - regular).mean() > 0.2 * np.abs(regular).mean()
    assert np.abs(irregular).max() <= IRREGULARITY_FACTOR_MAX * np.abs(regular).max() * 1.001


def test_a_render_from_the_pillow_s_bake_draws_its_irregular_second_system(tmp_path):
    """The pillow (wrinkle:biaxial: two wave systems) at irregularity 0.3: the irregular
    blend reads each system's rest direction and compression, so the bake writes the second
    system's too (primvars:wrinkle:direction2, compression2), and a render from the bake
    equals the direct render. Without them the baked render differed on 11% of its pixels,
    by up to 0.61 (2026-12-07)."""
    from pathlib import Path

    from helpers import rendered_frames

    sample = Path(__file__).resolve().parents[1] / "sample_stages" / "pillow.usda"
    source = tmp_path / "pillow.usda"
    Sdf.Layer.FindOrOpen(str(sample)).Export(str(source))
    stage = Usd.Stage.Open(str(source))
    stage.GetPrimAtPath("/World/Pillow").CreateAttribute(
        schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(IRREGULARITY)
    stage.Save()
    layer = tmp_path / "pillow_bake.usda"
    assert main(["bake", str(source), str(layer), "--frames", "24", "--quiet"]) == 0
    baked = Usd.Stage.Open(str(layer))
    prim = baked.GetPrimAtPath("/World/Pillow")
    direction2 = np.asarray(prim.GetAttribute("primvars:wrinkle:direction2").Get(24))
    compression2 = np.asarray(prim.GetAttribute("primvars:wrinkle:compression2").Get(24))
    assert np.linalg.norm(direction2, axis=1).max() > 0.5 and compression2.min() < 1.0
    images = rendered_frames({"direct": source, "baked": layer}, tmp_path)
    assert np.abs(images["direct"][..., :3] - images["baked"][..., :3]).max() < 1e-4
