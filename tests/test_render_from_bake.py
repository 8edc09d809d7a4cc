"""Rendering from baked wave fields: equal to rendering directly (with the phase history),
independent of the machine that baked, and strict about fields that do not fit."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Vt

from usdwrinkle.cli.main import main

from helpers import EXR_CHANNELS, SLEEVE, edited_copy, read_exr, set_sample

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT = str(SAMPLES / "shirt.usda")
WIDTH = "128"


def render(stage, out, frames, *extra):
    assert main(["render", str(stage), str(out), "--frames", frames, "--width", WIDTH,
                 "--quiet", *extra]) == 0


def assert_same(a_path, b_path, tol=1e-5):
    """Every channel within ``tol`` (the frame-independence tolerance); inf where both are."""
    a, b = read_exr(a_path), read_exr(b_path)
    for name in EXR_CHANNELS:
        same_inf = np.isinf(a[name]) & np.isinf(b[name])
        with np.errstate(invalid="ignore"):
            assert np.all(same_inf | (np.abs(a[name] - b[name]) <= tol)), name


@pytest.fixture(scope="module")
def shirt_bake(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bake")
    layer = folder / "shirt_wrinkles.usda"
    assert main(["bake", SHIRT, str(layer), "--quiet"]) == 0
    return layer


@pytest.mark.parametrize("with_points", [False, True])
def test_render_from_bake_equals_direct_render(gl_context, tmp_path, with_points):
    layer = tmp_path / "bake.usda"
    assert main(["bake", SHIRT, str(layer), "--quiet"]
                + (["--with-points"] if with_points else [])) == 0
    render(SHIRT, tmp_path / "direct.####.exr", "24")       # with its 23-frame preroll
    render(layer, tmp_path / "baked.####.exr", "24")        # no preroll
    render(layer, tmp_path / "range.####.exr", "20:24")
    assert_same(tmp_path / "direct.0024.exr", tmp_path / "baked.0024.exr")
    assert_same(tmp_path / "direct.0024.exr", tmp_path / "range.0024.exr")
    height = read_exr(tmp_path / "baked.0024.exr")["wrinkle.height"]
    assert np.abs(height).max() > 1e-3  # the wrinkles are there


def test_summary_names_the_baked_meshes(gl_context, tmp_path, shirt_bake, capsys):
    assert main(["render", str(shirt_bake), str(tmp_path / "s.####.png"), "--frames", "3:4",
                 "--width", "64"]) == 0
    out = capsys.readouterr().err
    assert f"baked wave fields: {SLEEVE}" in out
    assert main(["render", str(shirt_bake), str(tmp_path / "s.####.png"), "--frames", "3:4",
                 "--width", "64", "--recompute"]) == 0
    assert "baked wave fields" not in capsys.readouterr().err


def perturbed_copy(layer: Path, out: Path, seed: int = 7) -> Path:
    """The bake as another GL implementation might have made it: the same waves to float
    rounding, phases that drifted apart (docs/method.md measures ~1.2 rad median between
    llvmpipe and the float64 reference over 24 frames)."""
    rng = np.random.default_rng(seed)
    phase_path = Sdf.Path(f"{SLEEVE}.primvars:wrinkle:phase")
    wave_path = Sdf.Path(f"{SLEEVE}.primvars:wrinkle:waveVector")

    def perturb(copy):
        for frame in copy.ListTimeSamplesForPath(phase_path):
            phase = np.asarray(copy.QueryTimeSample(phase_path, frame), np.float64)
            drift = 1.2 * np.sin(np.arange(len(phase)) * 0.05) + rng.normal(0, 0.05, len(phase))
            copy.SetTimeSample(phase_path, frame, Vt.FloatArray.FromNumpy(
                (phase + drift).astype(np.float32)))
            wave = np.asarray(copy.QueryTimeSample(wave_path, frame), np.float64)
            wave *= 1 + rng.normal(0, 1e-6, wave.shape)
            copy.SetTimeSample(wave_path, frame,
                               Vt.Vec3fArray.FromNumpy(wave.astype(np.float32)))

    return edited_copy(layer, out, perturb)


def test_a_bake_from_another_machine_renders_identically_from_the_layer(
        gl_context, tmp_path, shirt_bake):
    other = perturbed_copy(shirt_bake, tmp_path / "other_machine.usda")
    # chunks of a farm: a frame alone, the same frame inside a range, in any order
    render(other, tmp_path / "alone.####.exr", "17")
    render(other, tmp_path / "range.####.exr", "24,17,9")
    a, b = read_exr(tmp_path / "alone.0017.exr"), read_exr(tmp_path / "range.0017.exr")
    for name in EXR_CHANNELS:
        assert np.array_equal(a[name], b[name]), name  # bit for bit: no state, no history
    # the layer's crests are drawn, not this machine's: the heights differ from the
    # original bake's where the phases were moved ...
    render(shirt_bake, tmp_path / "ours.####.exr", "17")
    ours = read_exr(tmp_path / "ours.0017.exr")["wrinkle.height"]
    theirs = a["wrinkle.height"]
    hit = np.isfinite(ours) & (np.abs(ours) + np.abs(theirs) > 0)
    assert np.mean(np.abs(ours[hit] - theirs[hit])) > 0.1 * np.mean(np.abs(ours[hit]))
    # ... and --recompute ignores the layer's fields: back to this machine's render
    render(other, tmp_path / "recomputed.####.exr", "17", "--recompute")
    assert_same(tmp_path / "ours.0017.exr", tmp_path / "recomputed.0017.exr")


def _drop_sample(frame):
    def edit(layer):
        for name in ("amplitude", "waveVector", "phase", "direction", "compression"):
            layer.EraseTimeSample(Sdf.Path(f"{SLEEVE}.primvars:wrinkle:{name}"), frame)
    return edit


def _remove_phase(layer):
    prim = layer.GetPrimAtPath(SLEEVE)
    prim.RemoveProperty(prim.attributes["primvars:wrinkle:phase"])


@pytest.mark.parametrize("edit,frames,message", [
    (set_sample("amplitude", 3, lambda v: v[:-5]), "1:4",
     f"baked field has {455 - 5} values for 455 points (or the wrong type) "
     f"({SLEEVE}.primvars:wrinkle:amplitude at frame 3)"),
    (set_sample("phase", 2,
                lambda v: np.where(np.arange(len(v)) == 7, np.nan, v).astype(np.float32)),
     "1:4", f"baked field is not finite (NaN or Inf) ({SLEEVE}.primvars:wrinkle:phase at frame 2)"),
    (set_sample("waveVector", 4, lambda v: np.full_like(v, np.inf)), "4",
     f"baked field is not finite (NaN or Inf) ({SLEEVE}.primvars:wrinkle:waveVector at frame 4)"),
    (_drop_sample(5), "4:6",
     f"frame missing from the baked range 1..24; bake this frame, or pass --recompute "
     f"({SLEEVE}.primvars:wrinkle:amplitude at frame 5)"),
    (lambda layer: None, "23:26",
     f"frame outside the baked range 1..24; bake this frame, or pass --recompute "
     f"({SLEEVE}.primvars:wrinkle:amplitude at frame 25)"),
    (_remove_phase, "1",
     "incomplete baked wave fields: this primvar is missing (re-bake, or pass --recompute) "
     f"({SLEEVE}.primvars:wrinkle:phase)"),
])
def test_bad_baked_fields_are_one_line_errors(gl_context, tmp_path, shirt_bake, capsys, edit,
                                              frames, message):
    layer = edited_copy(shirt_bake, tmp_path / "broken.usda", edit)
    out = tmp_path / "frames"
    code = main(["render", str(layer), str(out / "s.####.png"), "--frames", frames,
                 "--width", "64", "--quiet"])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err == [f"usdwrinkle: error: {message}"]
    if "range" in message:  # refused before any frame is drawn
        assert not out.exists() or not list(out.iterdir())


def test_frames_outside_the_bake_render_with_recompute(gl_context, tmp_path, shirt_bake):
    render(shirt_bake, tmp_path / "r.####.exr", "23:25", "--recompute")
    render(SHIRT, tmp_path / "d.####.exr", "25")
    assert_same(tmp_path / "r.0025.exr", tmp_path / "d.0025.exr")


def test_a_bake_of_part_of_a_camera_less_shot_is_framed_as_the_shot(gl_context, corpus,
                                                                    tmp_path):
    """Automatic framing takes the bounds over the shot's range. A bake's layer holds the
    baked frames' range only, so a bake of frames 10-12 of CesiumMan (no camera) was
    framed otherwise than the shot: 3.5% of the pixels differed. The bake now records the
    shot's range (customLayerData usdwrinkle.shotStart/shotEnd) for framing."""
    usdz = corpus / "usd-wg" / "CesiumMan.usdz"
    layer = tmp_path / "part.usdc"
    assert main(["bake", str(usdz), str(layer), "--all-meshes", "--frames", "10:12",
                 "--quiet"]) == 0
    from pxr import Sdf

    data = Sdf.Layer.FindOrOpen(str(layer)).customLayerData["usdwrinkle"]
    assert (data["shotStart"], data["shotEnd"]) == (1.0, 48.0)
    render(usdz, tmp_path / "direct.####.exr", "10:12", "--all-meshes")
    render(layer, tmp_path / "baked.####.exr", "10:12")
    for frame in (10, 12):
        assert_same(tmp_path / f"direct.{frame:04d}.exr", tmp_path / f"baked.{frame:04d}.exr")
