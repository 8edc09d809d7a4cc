"""benchmarks/texture_gap.py's readings, on synthetic frames: the ramp texture decodes back
to the texture coordinates it was made from, and a pixel whose coordinates are wrong is
found (the diagnosis itself needs Storm: python -m benchmarks.texture_gap)."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio
import pytest

from benchmarks.texture_gap import (
    LOW,
    MID,
    PERIODS,
    RAMP_TOLERANCE,
    SPAN,
    decoded_st,
    storm_st_wrong,
    write_ramp,
)


def srgb_codes(linear: np.ndarray) -> np.ndarray:
    encoded = np.where(linear <= 0.0031308, 12.92 * linear,
                       1.055 * np.power(linear, 1 / 2.4) - 0.055)
    return np.clip(np.round(255 * encoded), 0, 255).astype(np.uint8)


def frame(path, s, t, gain=1.0):
    """An 8-bit sRGB RGBA frame of the ramp at texture coordinates (s, t), lit by
    ``gain``."""
    rgba = np.empty(s.shape + (4,), np.uint8)
    rgba[..., 0] = srgb_codes(gain * (LOW + SPAN * np.mod(PERIODS * s, 1.0)))
    rgba[..., 1] = srgb_codes(gain * (LOW + SPAN * np.mod(PERIODS * t, 1.0)))
    rgba[..., 2] = srgb_codes(np.full(s.shape, gain * MID))
    rgba[..., 3] = 255
    image = oiio.ImageBuf(oiio.ImageSpec(s.shape[1], s.shape[0], 4, oiio.UINT8))
    image.set_pixels(oiio.ROI(), rgba)
    assert image.write(str(path))
    return str(path)


def test_the_ramp_decodes_to_the_coordinates_it_was_made_from(tmp_path):
    ramp = oiio.ImageBuf(str(write_ramp(tmp_path))).get_pixels(oiio.FLOAT)
    assert ramp.shape == (1024, 1024, 3)
    # the texel at column i, row j (row 0 the top) holds s = (i + 0.5) / 1024, t = 1 - ...
    assert ramp[0, 1, 0] == pytest.approx(LOW + SPAN * np.mod(PERIODS * 1.5 / 1024, 1), abs=1e-6)
    assert ramp[0, 0, 1] == pytest.approx(LOW + SPAN * np.mod(PERIODS * (1 - 0.5 / 1024), 1),
                                          abs=1e-6)
    rng = np.random.default_rng(3)
    s, t = rng.random((40, 60)), rng.random((40, 60))
    decoded_s, decoded_t, covered = decoded_st(frame(tmp_path / "f.png", s, t, gain=0.8))
    assert covered.all()
    readable = (np.mod(PERIODS * s, 1) > 0.05) & (np.mod(PERIODS * s, 1) < 0.95)
    # 8 bits, the exposure read from 8-bit B: within 0.015 of a period (a code's step at
    # the ramp's bright end), under RAMP_TOLERANCE, whatever the exposure
    assert RAMP_TOLERANCE > 0.015
    np.testing.assert_allclose(decoded_s[readable], np.mod(PERIODS * s, 1)[readable],
                               atol=0.015)
    readable = (np.mod(PERIODS * t, 1) > 0.05) & (np.mod(PERIODS * t, 1) < 0.95)
    np.testing.assert_allclose(decoded_t[readable], np.mod(PERIODS * t, 1)[readable],
                               atol=0.015)


def test_pixels_read_at_other_coordinates_are_found(tmp_path):
    """A smooth st, as both renderers draw it, with Storm's flat frame wrong along a line of
    pixels (its dotted triangle edges): those are found, and no pixel off the line."""
    y, x = np.mgrid[0:48, 0:64]
    s, t = 0.002 * x + 0.01, 0.0015 * y + 0.3
    wrong_s = s.copy()
    line = (x == 2 * (y // 2) + 5) & (y > 4) & (y < 40)
    wrong_s[line] += 0.01  # 8% of a period
    names = {"ours_plain": (s, t), "storm_flat": (wrong_s, t), "storm_parallax": (s, t)}
    frames = {name: frame(tmp_path / f"{name}.png", *st) for name, st in names.items()}
    found = storm_st_wrong(frames)
    assert found[line].mean() > 0.9
    near = np.zeros_like(line)
    for dx in (-1, 0, 1):
        near |= np.roll(line, dx, axis=1)
    assert not (found & ~near).any()
