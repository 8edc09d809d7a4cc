"""A GPU's image against llvmpipe's (issue 42, finding 9).

The goldens of test_render.py are defined on llvmpipe and skip elsewhere, so on a GPU no
test compared an image with anything. This one renders the shirt from a committed bake
(tests/goldens/shirt_bake.0024.usdc: the wave fields are read, not computed, so only
rasterisation and shading can differ between drivers) and compares it with the frame
llvmpipe made of the same bake. It runs on every GL: on llvmpipe it is a golden, on a GPU
it is the oracle. Measured on an NVIDIA H200 (driver 580, 2026-11-27): p99 1.2/255 with
one sample per pixel, 4.9 with the default 4 (shaded where each lies: see P99_CODES).
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
#: samples -> the 99th percentile of the per-pixel difference allowed, in 8-bit sRGB codes.
#: One sample per pixel compares the rasterisation and the shading alone (an H200, driver
#: 580: p99 1.2). With 4, each sample is shaded where it lies, and where GL puts the 4
#: samples of a pixel is the implementation's (the spec leaves it open: llvmpipe's pattern
#: is not NVIDIA's), so folds 2-3 pixels across, as the shirt's are at 240 px, average to
#: slightly different values (H200: p99 4.9; interior pixels alone 4.5)
P99_CODES = {1: 3.0, 4: 6.0}
#: the share of pixels whose coverage (alpha) may differ by more than half (silhouette
#: rasterisation)
EDGE_SHARE = 0.01


def _codes(rgba: np.ndarray) -> np.ndarray:
    """Straight-alpha sRGB codes (0..255, float) of premultiplied linear RGBA, and alpha."""
    alpha = rgba[..., 3:4]
    straight = np.where(alpha > 0, rgba[..., :3] / np.maximum(alpha, 1e-12), 0.0)
    return np.concatenate([255.0 * srgb_encode(np.clip(straight, 0, 1)),
                           255.0 * np.clip(alpha, 0, 1)], axis=2)


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
    assert p99 <= P99_CODES[samples], \
        f"{renderer}: p99 {p99:.2f}/255 against llvmpipe's frame ({samples} samples)"
    assert edge <= EDGE_SHARE, f"{renderer}: coverage differs on {edge:.2%} of pixels"
