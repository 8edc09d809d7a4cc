"""A GPU's image against llvmpipe's (issue 42, finding 9).

The goldens of test_render.py are defined on llvmpipe and skip elsewhere, so on a GPU no
test compared an image with anything. This one renders the shirt from a committed bake
(tests/goldens/shirt_bake.0024.usdc: the wave fields are read, not computed, so only
rasterisation and shading can differ between drivers) and compares it with the frame
llvmpipe made of the same bake. It runs on every GL: on llvmpipe it is a golden, on a GPU
it is the oracle. Measured on an NVIDIA H200 (driver 580): p99 1.2/255 with one sample
per pixel, 4.9 with the default 4 on 2026-11-27; on 2026-12-04, with the folds that keep
the cloth's length (steeper, so the samples' placement weighs more), p99 0.38 with one
sample, and with 4 p99 6.66 but 0.98 outside the envelope (ENVELOPE_P99). The bake was made
again on 2026-12-04 (night), when the shirt's rig changed (dual quaternions; its points are
skinned from the stage); the H200's figures are the old bake's. Its frames were made
again on 2026-12-07, when the irregularity fallback became 0.15 (the bake authors none,
so it is drawn irregular since).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.images.colour import srgb_encode

GOLDENS = Path(__file__).resolve().parent / "goldens"
BAKE = GOLDENS / "shirt_bake.0024.usdc"
#: samples -> llvmpipe's frame of the bake at 240 px
GOLDEN = {4: GOLDENS / "shirt_bake.0024.exr", 1: GOLDENS / "shirt_bake.0024.s1.exr"}
#: the 99th percentile of the per-pixel difference allowed, in 8-bit sRGB codes, where the
#: samples lie where llvmpipe's do: one sample per pixel on every GL (the rasterisation and
#: the shading alone; an H200, driver 580: p99 1.2, then 0.38), and 4 on llvmpipe itself
P99_CODES = 3.0
#: With 4 samples on another GL: each sample is shaded where it lies, and where GL puts the
#: 4 samples of a pixel is the implementation's (the spec leaves it open: llvmpipe's pattern
#: is not NVIDIA's), so folds 2-3 pixels across, as the shirt's are at 240 px, average to
#: other values (H200: p99 4.9 on 2026-11-27; 6.66 on 2026-12-04, max 105, once the folds
#: kept the cloth's length). A pattern's choice moves a pixel's value within the range its
#: neighbours span, so there the bound is on how far a pixel lies outside the golden's 3x3
#: neighbourhood, per channel (H200, 2026-12-04: p99 0.98, max 16.5)
ENVELOPE_P99 = 2.0
#: the share of pixels whose coverage (alpha) may differ by more than half (silhouette
#: rasterisation)
EDGE_SHARE = 0.01


def _codes(rgba: np.ndarray) -> np.ndarray:
    """Straight-alpha sRGB codes (0..255, float) of premultiplied linear RGBA, and alpha."""
    alpha = rgba[..., 3:4]
    straight = np.where(alpha > 0, rgba[..., :3] / np.maximum(alpha, 1e-12), 0.0)
    return np.concatenate([255.0 * srgb_encode(np.clip(straight, 0, 1)),
                           255.0 * np.clip(alpha, 0, 1)], axis=2)


def beyond_neighbours(ours: np.ndarray, theirs: np.ndarray) -> np.ndarray:
    """Per pixel, how far (the worst channel) ``ours`` lies outside the range of
    ``theirs`` over the 3x3 neighbourhood (edges repeated): 0 inside it."""
    from numpy.lib.stride_tricks import sliding_window_view

    padded = np.pad(theirs, ((1, 1), (1, 1), (0, 0)), mode="edge")
    windows = sliding_window_view(padded, (3, 3), axis=(0, 1))
    low, high = windows.min(axis=(-2, -1)), windows.max(axis=(-2, -1))
    return np.maximum(low - ours, ours - high).clip(0).max(axis=2)


def test_the_envelope_is_zero_inside_and_the_distance_outside():
    theirs = np.zeros((4, 5, 3))
    theirs[1, 2] = (10, 20, 30)
    ours = theirs.copy()
    ours[2, 2] = (5, 25, 0)  # the neighbour's range there is 0..10, 0..20, 0..30
    ours[3, 4] = (0, 0, -2)  # below its (all-zero) range by 2
    got = beyond_neighbours(ours, theirs)
    assert got[2, 2] == 5 and got[3, 4] == 2
    assert np.count_nonzero(got) == 2


@pytest.mark.parametrize("samples", [1, 4])
def test_a_bake_renders_the_same_on_this_gl_as_on_llvmpipe(gl_context, regenerate_goldens,
                                                            samples):
    engine = WrinkleEngine(str(BAKE), ctx=gl_context)
    try:
        assert engine.baked_paths == ["/World/Arm/Sleeve"]  # drawn from the bake
        width, height = engine.resolution(240, None, 24.0)
        image = engine.render_frame(24.0, width, height, samples=samples)["color"].pixels
    finally:
        engine.release()
    renderer = gl_context.info.get("GL_RENDERER", "")
    golden_path = GOLDEN[samples]
    if regenerate_goldens:
        assert "llvmpipe" in renderer, "the golden is made on llvmpipe"
        spec = oiio.ImageSpec(image.shape[1], image.shape[0], 4, "float")
        out = oiio.ImageOutput.create(str(golden_path))
        assert out.open(str(golden_path), spec) and out.write_image(image) and out.close()
    golden = oiio.ImageBuf(str(golden_path)).get_pixels(oiio.FLOAT).reshape(image.shape)
    ours, theirs = _codes(image), _codes(golden)
    covered = (golden[..., 3] > 0.5) & (image[..., 3] > 0.5)
    assert covered.mean() > 0.05  # the shirt fills part of the frame
    diff = np.abs(ours - theirs)[covered].max(axis=1)
    p99 = float(np.percentile(diff, 99))
    edge = float((np.abs(ours[..., 3] - theirs[..., 3]) > 127).mean())
    if samples == 1 or "llvmpipe" in renderer:
        assert p99 <= P99_CODES, \
            f"{renderer}: p99 {p99:.2f}/255 against llvmpipe's frame ({samples} samples)"
    outside = float(np.percentile(beyond_neighbours(ours[..., :3], theirs[..., :3])[covered],
                                  99))
    assert outside <= ENVELOPE_P99, \
        f"{renderer}: p99 {outside:.2f}/255 outside llvmpipe's 3x3 range ({samples} samples)"
    assert edge <= EDGE_SHARE, f"{renderer}: coverage differs on {edge:.2%} of pixels"
