"""Beyond the paper: crossing wrinkles under biaxial compression (a second wave system)
and tension wrinkles, against the analytic sheets and the laws in docs/method.md."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from usdwrinkle.authoring.api import WrinkleAPI
from usdwrinkle.cli.main import main
from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.method.contract import TENSION_REFERENCE_STRAIN, TENSION_SLOPE

from conftest import grid_sheet
from helpers import fold_law, point_cache_stage, rotation_matrix

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
WIDTH = 0.3


def sheet(scale, rotation=None, biaxial=None, tension=None, threshold=None):
    rest, counts, indices = grid_sheet(31, 31, 2.0)
    posed = rest * np.asarray(scale, np.float32)
    if rotation is not None:
        posed = (posed @ rotation.T + np.array([0.5, -1.0, 2.0])).astype(np.float32)
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=WIDTH)
    api = WrinkleAPI(stage.GetPrimAtPath("/Sheet"))
    if biaxial is not None:
        api.CreateBiaxialAttr(biaxial)
    if tension is not None:
        api.CreateTensionAttr(tension)
    if threshold is not None:
        api.CreateTensionThresholdAttr(threshold)
    return stage, rest


def fields_of(ctx, stage):
    engine = WrinkleEngine(stage, ctx=ctx)
    try:
        engine.compute_frame(1.0)
        return engine.read_fields("/Sheet")
    finally:
        engine.release()


def interior(rest, margin=0.15):
    return np.all(np.abs(rest[:, :2]) < 1 - margin, axis=1)


def law(ratio):
    """The fold law's height on the analytic sheet (slack 0)."""
    return float(fold_law(ratio, WIDTH)[0])


def law_k(ratio):
    """|k| of the fold law: the coarsened material wave, posed at ratio r."""
    return float(fold_law(ratio, WIDTH)[1])


def angle_to(vectors, axis):
    unit = vectors / np.linalg.norm(vectors, axis=1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.abs(unit @ axis), 0, 1)))


def test_biaxial_sheet_has_two_crossing_systems(gl_context):
    r1, r2 = 0.6, 0.8
    stage, rest = sheet([r1, r2, 1], biaxial=1.0)
    f = fields_of(gl_context, stage)
    inside = interior(rest)
    # system 1: the strongest compression (x); system 2: the other one (y)
    np.testing.assert_allclose(np.linalg.norm(f.wave_vector[inside], axis=1), law_k(r1),
                               rtol=0.03)
    np.testing.assert_allclose(np.linalg.norm(f.wave_vector2[inside], axis=1), law_k(r2),
                               rtol=0.03)
    np.testing.assert_allclose(f.amplitude[inside], law(r1), rtol=0.03)
    np.testing.assert_allclose(f.amplitude2[inside], law(r2), rtol=0.03)
    assert angle_to(f.wave_vector[inside], [1, 0, 0]).max() < 3.0
    assert angle_to(f.wave_vector2[inside], [0, 1, 0]).max() < 3.0


def test_the_biaxial_weight_scales_the_second_system(gl_context):
    stage, rest = sheet([0.6, 0.8, 1], biaxial=0.5)
    f = fields_of(gl_context, stage)
    np.testing.assert_allclose(f.amplitude2[interior(rest)], 0.5 * law(0.8), rtol=0.03)


def test_a_uniaxial_sheet_keeps_one_system(gl_context):
    stage, rest = sheet([0.7, 1, 1], biaxial=1.0)
    f = fields_of(gl_context, stage)
    inside = interior(rest)
    np.testing.assert_allclose(f.amplitude[inside], law(0.7), rtol=0.03)
    assert np.abs(f.amplitude2).max() < 1e-3 * law(0.7)


def test_biaxial_off_is_the_paper(gl_context):
    """wrinkle:biaxial = 0 (the fallback): no second system at all."""
    stage, _ = sheet([0.6, 0.8, 1])
    assert np.all(fields_of(gl_context, stage).amplitude2 == 0)


def tension_law(stretch, threshold=0.02, factor=1.0):
    strain = stretch - 1 - threshold
    wavelength = WIDTH * (strain / TENSION_REFERENCE_STRAIN) ** -0.25
    return wavelength, factor * TENSION_SLOPE * np.sqrt(strain) * wavelength


@pytest.mark.parametrize("stretch", [1.08, 1.2, 1.4])
def test_tension_sheet_follows_the_law(gl_context, stretch):
    stage, rest = sheet([stretch, 1, 1], tension=1.0)
    f = fields_of(gl_context, stage)
    inside = interior(rest)
    wavelength, amplitude = tension_law(stretch)
    assert angle_to(f.wave_vector[inside], [0, 1, 0]).max() < 3.0  # k across the pull
    np.testing.assert_allclose(np.linalg.norm(f.wave_vector[inside], axis=1),
                               2 * np.pi / wavelength, rtol=0.03)
    np.testing.assert_allclose(f.amplitude[inside], amplitude, rtol=0.03)


def test_no_tension_wrinkles_below_the_threshold_or_when_off(gl_context):
    """Below the threshold the fields are those of tension off (the compression model's
    float noise of a barely stretched sheet, r = 1 - 1e-7, included); tension = 0 gives no
    wrinkles on a sheet stretched by 20%."""
    for stretch, threshold in ((1.015, None), (1.08, 0.1)):
        on = fields_of(gl_context, sheet([stretch, 1, 1], tension=1.0, threshold=threshold)[0])
        off = fields_of(gl_context, sheet([stretch, 1, 1], tension=0.0,
                                          threshold=threshold)[0])
        np.testing.assert_array_equal(on.amplitude, off.amplitude)
        np.testing.assert_array_equal(on.wave_vector, off.wave_vector)
    off = fields_of(gl_context, sheet([1.2, 1, 1], tension=0.0)[0])
    assert np.abs(off.amplitude).max() < 1e-3 * WIDTH  # float noise: 0.01% of W


def test_compression_wins_where_it_is_larger(gl_context):
    """Stretched along x and compressed along y: both waves run along y; the larger
    amplitude (here the compression's) is the wave."""
    stage, rest = sheet([1.1, 0.7, 1], tension=1.0)
    f = fields_of(gl_context, stage)
    inside = interior(rest)
    assert law(0.7) > tension_law(1.1)[1]
    np.testing.assert_allclose(f.amplitude[inside], law(0.7), rtol=0.03)
    np.testing.assert_allclose(np.linalg.norm(f.wave_vector[inside], axis=1), law_k(0.7),
                               rtol=0.03)


@pytest.mark.parametrize("case", ["biaxial", "tension"])
def test_rigid_rotation_changes_nothing(gl_context, case):
    rotation = rotation_matrix([0.4, -0.3, 0.85], 1.3)
    kwargs = {"biaxial": 1.0} if case == "biaxial" else {"tension": 1.0}
    scale = [0.6, 0.8, 1] if case == "biaxial" else [1.25, 1, 1]
    plain = fields_of(gl_context, sheet(scale, **kwargs)[0])
    moved = fields_of(gl_context, sheet(scale, rotation, **kwargs)[0])
    for name in ("amplitude", "amplitude2"):
        a, b = getattr(plain, name), getattr(moved, name)
        assert np.abs(a - b).max() <= 0.01 * max(np.abs(a).max(), 1e-9), name
    for name in ("wave_vector", "wave_vector2"):
        a, b = getattr(plain, name) @ rotation.T, getattr(moved, name)
        assert np.abs(a - b).max() <= 0.01 * np.abs(a).max(), name


@pytest.mark.parametrize("stage_name,primvar", [("pillow", "primvars:wrinkle:phase2"),
                                                ("pull", "primvars:wrinkle:phase")])
def test_frame_independence(gl_context, tmp_path, stage_name, primvar):
    """Frame 24 alone equals frame 24 of 1..24, for both systems' fields."""
    source = SAMPLES / f"{stage_name}.usda"
    mesh = "/World/Pillow" if stage_name == "pillow" else "/World/Sheet"
    layers = {}
    for name, frames in (("whole", "1:24"), ("alone", "24")):
        layers[name] = tmp_path / f"{name}.usdc"
        assert main(["bake", str(source), str(layers[name]), "--frames", frames,
                     "--quiet"]) == 0
    names = ["primvars:wrinkle:amplitude", "primvars:wrinkle:phase", primvar]
    if stage_name == "pillow":
        names += ["primvars:wrinkle:amplitude2", "primvars:wrinkle:waveVector2"]
    stages = {name: Usd.Stage.Open(str(path)) for name, path in layers.items()}  # held
    whole = stages["whole"].GetPrimAtPath(mesh)
    alone = stages["alone"].GetPrimAtPath(mesh)
    for name in names:
        a = np.asarray(whole.GetAttribute(name).Get(24))
        b = np.asarray(alone.GetAttribute(name).Get(24))
        assert a.shape == b.shape and np.abs(a - b).max() <= 1e-4 * max(np.abs(a).max(), 1), name


def test_pillow_bake_holds_the_second_system_and_renders_from_it(gl_context, tmp_path):
    """The bake writes amplitude2, waveVector2 and phase2, and a render from the bake
    equals the direct render."""
    source = SAMPLES / "pillow.usda"
    layer = tmp_path / "pillow_bake.usda"
    assert main(["bake", str(source), str(layer), "--quiet"]) == 0
    baked = Usd.Stage.Open(str(layer))
    prim = baked.GetPrimAtPath("/World/Pillow")
    amplitude2 = np.asarray(prim.GetAttribute("primvars:wrinkle:amplitude2").Get(24))
    assert amplitude2.max() > 0.01
    assert UsdGeom.Primvar(prim.GetAttribute("primvars:wrinkle:phase2")).GetInterpolation() \
        == UsdGeom.Tokens.vertex
    from helpers import rendered_frames

    images = rendered_frames({"direct": source, "baked": layer}, tmp_path)
    assert np.abs(images["direct"][..., :3] - images["baked"][..., :3]).max() < 1e-4


@pytest.mark.parametrize("args,fragment", [
    (["--biaxial", "1.5"], "biaxial weight must be in 0..1"),
    (["--tension", "-1"], "tension factor must be in 0.."),
    (["--tension-threshold", "2"], "tension threshold must be in 0..1"),
])
def test_apply_refuses_out_of_range_values(tmp_path, capsys, args, fragment):
    stage, _ = sheet([1, 1, 1])
    source = tmp_path / "s.usda"
    stage.GetRootLayer().Export(str(source))
    assert main(["apply", str(source), "/Sheet", *args]) == 2
    assert fragment in capsys.readouterr().err


def test_apply_and_check_learn_the_new_attributes(tmp_path, capsys):
    stage, _ = sheet([1, 1, 1])
    source = tmp_path / "s.usda"
    stage.GetRootLayer().Export(str(source))
    assert main(["apply", str(source), "/Sheet", "--biaxial", "0.7", "--tension", "2",
                 "--tension-threshold", "0.05"]) == 0
    applied = Usd.Stage.Open(str(source))
    prim = applied.GetPrimAtPath("/Sheet")
    assert prim.GetAttribute("wrinkle:biaxial").Get() == pytest.approx(0.7)
    assert prim.GetAttribute("wrinkle:tension").Get() == pytest.approx(2.0)
    assert prim.GetAttribute("wrinkle:tensionThreshold").Get() == pytest.approx(0.05)
    assert main(["check", str(source)]) in (0, 1)
    capsys.readouterr()
    bad = Usd.Stage.Open(str(source))
    bad.GetPrimAtPath("/Sheet").GetAttribute("wrinkle:biaxial").Set(3.0)
    bad.Save()
    assert main(["check", str(source)]) == 1
    assert "biaxial weight must be in 0..1" in capsys.readouterr().out
