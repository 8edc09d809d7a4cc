"""Render pass: goldens on the reference rasteriser (llvmpipe) plus property checks."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle.engine import WrinkleEngine

from conftest import REPO, grid_sheet
from helpers import fold_law, point_cache_stage

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
GOLDENS = Path(__file__).resolve().parent / "goldens"
FAILURES = Path(__file__).resolve().parent / "_failures"
#: per-channel tolerance on linear colour, and the share of pixels allowed beyond it
PIXEL_TOLERANCE = 0.02
SHARE_TOLERANCE = 0.005


def reference_rasterizer(ctx) -> bool:
    return "llvmpipe" in ctx.info.get("GL_RENDERER", "")


def save(path: Path, pixels: np.ndarray) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], "float")
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(np.ascontiguousarray(pixels, np.float32))
    out.close()


@pytest.mark.parametrize("stage_name,frame", [("shirt", 24), ("zeppelin", 24), ("curtain", 24),
                                              ("flag", 1), ("pillow", 24), ("pull", 24)])
def test_golden_frames(gl_context, regenerate_goldens, stage_name, frame):
    if not reference_rasterizer(gl_context):
        pytest.skip("goldens are defined on Mesa llvmpipe only (pygfx's convention)")
    engine = WrinkleEngine(str(SAMPLES / f"{stage_name}.usda"), ctx=gl_context)
    try:
        width, height = engine.resolution(240, None, float(frame))
        buffers = engine.render_frame(float(frame), width, height)
    finally:
        engine.release()
    image = np.concatenate([buffers["color"].pixels, buffers["wrinkle.height"].pixels], axis=2)
    golden_path = GOLDENS / f"{stage_name}.{frame:04d}.exr"
    if regenerate_goldens or not golden_path.exists():
        if not regenerate_goldens:
            pytest.fail(f"missing golden {golden_path.name}: run pytest --regenerate-goldens")
        save(golden_path, image)
    golden = oiio.ImageBuf(str(golden_path)).get_pixels(oiio.FLOAT).reshape(image.shape)
    # compare colour and the wrinkle height, each against its own scale
    scale = np.array([1, 1, 1, 1, max(np.abs(golden[..., 4]).max(), 1e-6)])
    diff = np.abs(image - golden) / scale
    bad = np.any(diff > PIXEL_TOLERANCE, axis=2)
    if bad.mean() > SHARE_TOLERANCE:
        save(FAILURES / f"{stage_name}.{frame:04d}.diff.exr", diff)
        save(FAILURES / f"{stage_name}.{frame:04d}.actual.exr", image)
    assert bad.mean() <= SHARE_TOLERANCE, f"{bad.mean():.2%} of pixels differ"
    assert np.abs(golden[..., 4]).max() > 0.005  # the golden itself shows wrinkles


def test_no_wrinkle_where_uncompressed(gl_context):
    """A sheet that is only stretched (r = 1 everywhere) has zero height at every pixel."""
    rest, counts, indices = grid_sheet(15, 15, 2.0)
    stretched = rest * np.array([1.3, 1.1, 1.0], np.float32)
    stage = point_cache_stage(rest, {1: stretched}, counts, indices, width=0.3)
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        buffers = engine.render_frame(1.0, 96, 96)
    finally:
        engine.release()
    assert (buffers["color"].pixels[..., 3] > 0).mean() > 0.1
    assert np.all(buffers["wrinkle.height"].pixels == 0)


def test_height_is_bounded_by_amplitude(gl_context):
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([0.6, 1, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=0.3, amplitude_scale=0.7)
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        buffers = engine.render_frame(1.0, 128, 128)
    finally:
        engine.release()
    height = buffers["wrinkle.height"].pixels
    law = 0.7 * float(fold_law(0.6, 0.3)[0])  # s times the fold law's height
    assert np.abs(height).max() <= law * (1 + 1e-4)
    # and it reaches close to it
    assert np.abs(height).max() > 0.9 * law


def test_buffers_handed_out_are_never_overwritten(gl_context):
    """The framebuffer reuses its readback arrays only when nobody holds them."""
    engine = WrinkleEngine(str(SAMPLES / "flag.usda"), ctx=gl_context)
    try:
        # the flag's waves must be longer than the band limit's 4 pixels to show (at
        # 64 x 48 they fade out and every frame is the same picture)
        first = engine.render_frame(1.0, 160, 120, samples=1)
        kept = {name: buf.pixels.copy() for name, buf in first.items()}
        second = engine.render_frame(12.0, 160, 120, samples=1)
        third = engine.render_frame(24.0, 160, 120, samples=1)
    finally:
        engine.release()
    for name, pixels in kept.items():
        np.testing.assert_array_equal(first[name].pixels, pixels, err_msg=name)
    # the later frames differ from the first, so an overwrite would have shown (the flag
    # is static: its frames 12 and 24 may be the same picture once its phases settle)
    assert not np.array_equal(second["color"].pixels, kept["color"])
    assert not np.array_equal(third["color"].pixels, kept["color"])


def test_shade_samples_average_the_pixel(tmp_path):
    """render shades each of the 4 multisamples where it lies (the default), so a pixel
    is the average over its area: the pulled sheet (waves many pixels long, so that no
    band limit differs between the two sizes) at 320x200 against a numpy 4x4 box average
    of the same frame drawn at 1280x800 with one sample per pixel (measured: mean colour
    error 0.0004 shaded per sample, 0.004 shaded once per pixel; p99 0.0037 and 0.038).
    --no-shade-samples shades once per pixel; with one sample per pixel the switch
    changes nothing."""
    from usdwrinkle.cli.main import main

    from helpers import read_pixels

    def draw(name, width, height, *extra):
        out = tmp_path / f"{name}.####.exr"
        assert main(["render", str(REPO / "sample_stages" / "pull.usda"), str(out),
                     "--frames", "24", "--width", str(width), "--height", str(height),
                     "--quiet", *extra]) == 0
        return read_pixels(tmp_path / f"{name}.0024.exr")[..., :4]   # R, G, B, A first

    fine = draw("fine", 1280, 800, "--samples", "1")
    reference = fine.reshape(200, 4, 320, 4, 4).mean(axis=(1, 3))
    errors = {}
    for name, extra in {"pixel": ("--no-shade-samples",), "sample": ()}.items():
        image = draw(name, 320, 200, *extra)
        inside = (reference[..., 3] > 0.999) & (image[..., 3] > 0.999)
        assert inside.sum() > 25000
        errors[name] = np.abs(image[..., :3] - reference[..., :3]).max(axis=2)[inside]
    assert errors["sample"].mean() <= 0.001 and np.percentile(errors["sample"], 99) <= 0.01
    assert errors["sample"].mean() * 4 <= errors["pixel"].mean()
    single = draw("single", 320, 200, "--samples", "1")
    single_once = draw("single_once", 320, 200, "--samples", "1", "--no-shade-samples")
    assert np.array_equal(single, single_once)


def test_shade_samples_shades_only_where_folds_turn(tmp_path):
    """render's default shades a pixel's multisamples one by one only where the folds turn
    its normal within it (draw.glsl: turn_across_pixel); a pixel without a wave is shaded
    once, exactly as --no-shade-samples shades it. The pulled sheet at frame 24 has both:
    the wrinkled pixels differ, the others are the same to the bit."""
    from usdwrinkle.cli.main import main

    from helpers import read_pixels

    def draw(name, *extra):
        out = tmp_path / f"{name}.####.exr"
        assert main(["render", str(REPO / "sample_stages" / "pull.usda"), str(out),
                     "--frames", "24", "--width", "320", "--height", "200", "--quiet",
                     "--exr-float", *extra]) == 0
        return read_pixels(tmp_path / f"{name}.0024.exr")

    default, once = draw("default"), draw("once", "--no-shade-samples")
    channels = list(oiio.ImageBuf(str(tmp_path / "default.0024.exr")).spec().channelnames)
    amplitude = default[..., channels.index("wrinkle.amplitude")]
    # no wave in the pixel nor in its neighbours (an edge pixel blends two triangles)
    plain = np.ones_like(amplitude, bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            plain &= np.roll(amplitude, (dy, dx), axis=(0, 1)) == 0
    covered = default[..., channels.index("A")] > 0
    rgb = [channels.index(c) for c in "RGB"]
    assert (plain & covered).sum() > 2000 and (~plain & covered).sum() > 20000
    np.testing.assert_array_equal(default[plain][:, rgb], once[plain][:, rgb])
    differs = np.abs(default[..., rgb] - once[..., rgb]).max(axis=-1) > 1e-4
    assert differs[~plain & covered].mean() > 0.5


@pytest.mark.parametrize("name", ["cosine", "sharp", "rounded"])
def test_profile_curvature_is_the_largest_second_derivative(name):
    """The sample-shading test's max |H''| (render/resources.py) against numpy's second
    derivative of the preset, sampled 64 times finer: cos has 1."""
    from usdwrinkle.method.profiles import derive_gradient, preset_at, profile_preset
    from usdwrinkle.render.resources import profile_curvature

    fine = np.linspace(0.0, 2 * np.pi, 256 * 64, endpoint=False)
    values = preset_at(name, fine)
    span = 0.5 * (values.max() - values.min())   # the preset's normalisation to [-1, 1]
    second = np.gradient(np.gradient(values / span, fine), fine)
    expected = np.abs(second[64:-64]).max()
    got = profile_curvature(derive_gradient(profile_preset(name)))
    assert got == pytest.approx(expected, rel=0.05), (got, expected)
    if name == "cosine":
        assert got == pytest.approx(1.0, rel=1e-3)
