"""What keeps Storm's texture deformation from usdwrinkle's (issue 56): the real-client
test's texture shot measured as it is, and again without what is not the network's.

    python -m benchmarks.texture_gap [--write README.md]

The shot is tests/test_realclients.py's: the plaid shirt at W = 0.28, frame 24, zoomed 3x on
the upper arm at 320 px (the plaid at its 960 px size), under one uniform white dome
(bakes.uniform_dome), through the shot's camera and one turned 30 degrees. Storm draws it
through the maps layer's MaterialX network (storm_parallax) and through the same network
without the wrinkles (storm_flat, bakes.unwrinkled_network); the wrinkle contribution is
their difference, against usdwrinkle's wrinkled minus plain frames.

It is rendered twice: with the plaid, and with the plaid's file swapped for a ramp texture
(RAMP: R and G saw-tooth ramps of s and t, 8 periods over [0, 1]; an EXR, read raw), from
which each renderer's texture coordinates are decoded per pixel. That shows:
- **where Storm reads the texture at other coordinates than we do without any wrinkle**
  (storm_flat against usdwrinkle's plain frame: more than RAMP_TOLERANCE of a period), or
  where its st jumps from pixel to pixel (more than JUMP of a period from its 3x3
  median). On llvmpipe these are the dotted lines along triangle edges that Storm draws
  with any MaterialX material;
- **the texture offset itself**: per pixel, Storm's (storm_parallax - storm_flat) against
  ours (wrinkled - plain), s and t, where Storm's st is right;
- **the texture filtering**: Storm's plaid is softer than ours. The plaid's correlation is
  measured again with our frames blurred (a Gaussian of BLUR px) to Storm's sharpness.

It prints the block (or writes it between the ``texture_gap`` markers of the given file).
About 12 minutes here (Storm's MaterialX renders). Needs the real-client Python
(realclients/__init__.py). A diagnosis, not a test: run it where Storm runs on a GPU to see
what is left of the gap there.
"""
from __future__ import annotations

import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from realclients.bakes import TEXTURE_SHOT, Contribution, erode, grey, read_rgba8, texture_views
from realclients.shots import over_layer

#: periods of the ramp texture's saw-tooth over [0, 1] of s (R) and of t (G)
PERIODS = 8
#: the ramp's values: LOW + SPAN * (the saw-tooth in [0, 1)); B holds MID (each pixel's
#: gain: under the dome a renderer draws the albedo times one exposure)
LOW, SPAN, MID = 0.2, 0.7, 0.5
#: a decoded coordinate this close to the saw-tooth's jump (share of a period) is not read
EDGE = 0.08
#: Storm's st is wrong where it differs from ours by more than this share of a period
#: (0.0025 in st) without wrinkles ...
RAMP_TOLERANCE = 0.02
#: ... or jumps from its 3x3 median by more than this
JUMP = 0.05
#: the Gaussian (px) that makes our plaid as soft as Storm's (their second differences
#: measured 0.6x ours; 0.5 px brings ours to Storm's)
BLUR = 0.5
TURNS = (0.0, 30.0)


def write_ramp(folder: Path) -> Path:
    """The ramp texture (RAMP in the module docstring), 1024 x 1024, as an EXR."""
    import OpenImageIO as oiio

    n = 1024
    centres = (np.arange(n) + 0.5) / n
    s, t = np.meshgrid(centres, centres[::-1])  # row 0 is the image's top: t = 1
    pixels = np.empty((n, n, 3), np.float32)
    pixels[..., 0] = LOW + SPAN * np.mod(PERIODS * s, 1.0)
    pixels[..., 1] = LOW + SPAN * np.mod(PERIODS * t, 1.0)
    pixels[..., 2] = MID
    path = folder / "ramp.exr"
    image = oiio.ImageBuf(oiio.ImageSpec(n, n, 3, oiio.FLOAT))
    image.set_pixels(oiio.ROI(), pixels)
    if not image.write(str(path)):
        raise OSError(f"cannot write {path}: {image.geterror()}")
    return path


def ramp_stage(folder: Path) -> Path:
    """A layer over the texture shot's stage whose textures read the ramp instead."""
    from pxr import Sdf, UsdShade

    ramp = write_ramp(folder)
    path = folder / "shirt_ramp.usda"
    stage, layer = over_layer(TEXTURE_SHOT.stage.resolve(), path)
    swapped = 0
    for prim in stage.Traverse():
        if UsdShade.Shader(prim) and UsdShade.Shader(prim).GetIdAttr().Get() == "UsdUVTexture":
            prim.GetAttribute("inputs:file").Set(Sdf.AssetPath(str(ramp)))
            swapped += 1
    if not swapped:
        raise RuntimeError(f"{TEXTURE_SHOT.stage} has no UsdUVTexture to swap")
    layer.Save()
    return path


def _linear(codes: np.ndarray) -> np.ndarray:
    c = codes / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def decoded_st(path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(s, t as the saw-tooth's phase in [0, 1), covered) of a frame of the ramp."""
    rgba = read_rgba8(path).astype(np.float64)
    light = _linear(rgba[..., :3])
    gain = np.maximum(light[..., 2] / MID, 1e-6)
    return ((light[..., 0] / gain - LOW) / SPAN, (light[..., 1] / gain - LOW) / SPAN,
            rgba[..., 3] == 255)


def _wrap(x: np.ndarray) -> np.ndarray:
    return np.mod(x + 0.5, 1.0) - 0.5


def _median3(image: np.ndarray) -> np.ndarray:
    padded = np.pad(image, 1, mode="edge")
    h, w = image.shape
    return np.median(np.stack([padded[dy:dy + h, dx:dx + w] for dy in range(3)
                               for dx in range(3)]), axis=0)


def _blur(image: np.ndarray, sigma: float) -> np.ndarray:
    radius = int(3 * sigma) + 1
    kernel = np.exp(-0.5 * (np.arange(-radius, radius + 1) / sigma) ** 2)
    kernel /= kernel.sum()
    for axis in (0, 1):
        image = np.apply_along_axis(
            lambda v: np.convolve(np.pad(v, radius, mode="edge"), kernel, "valid"), axis,
            image)
    return image


def storm_st_wrong(ramp: dict) -> np.ndarray:
    """Where Storm's st is not ours without wrinkles, or jumps (module docstring)."""
    ours = decoded_st(ramp["ours_plain"])
    flat = decoded_st(ramp["storm_flat"])
    wrinkled = decoded_st(ramp["storm_parallax"])
    wrong = np.zeros(ours[2].shape, bool)
    for k in (0, 1):
        a, b = np.nan_to_num(ours[k]), np.nan_to_num(flat[k])
        readable = (a > EDGE) & (a < 1 - EDGE) & (b > EDGE) & (b < 1 - EDGE)
        wrong |= readable & (np.abs(_wrap(a - b)) > RAMP_TOLERANCE)
        for image in (flat, wrinkled):
            v = np.nan_to_num(image[k])
            wrong |= np.abs(_wrap(v - _median3(v))) > JUMP
    return wrong


def offsets(ramp: dict, where: np.ndarray) -> dict:
    """{"s" / "t": (correlation, slope of Storm's on ours, our RMS in st)} of the texture
    offsets, over the covered pixels in ``where`` that both renderers' ramps read."""
    images = {name: decoded_st(ramp[name]) for name in
              ("ours", "ours_plain", "storm_parallax", "storm_flat")}
    covered = erode(np.logical_and.reduce([image[2] for image in images.values()])) & where
    result = {}
    for k, axis in ((0, "s"), (1, "t")):
        inside = covered.copy()
        for image in images.values():
            inside &= (image[k] > EDGE) & (image[k] < 1 - EDGE)
        ours = _wrap(images["ours"][k] - images["ours_plain"][k])[inside] / PERIODS
        storm = _wrap(images["storm_parallax"][k] - images["storm_flat"][k])[inside] / PERIODS
        result[axis] = (float(np.corrcoef(ours, storm)[0, 1]),
                        float((ours * storm).sum() / (ours * ours).sum()),
                        float(np.sqrt((ours * ours).mean())))
    return result


def plaid(images: dict, where: np.ndarray | None = None, blur: float = 0.0) -> Contribution:
    """The plaid's wrinkle contribution (bakes.contribution), ours blurred by ``blur``
    px, over the pixels in ``where``."""
    ours, m1 = grey(images["ours"])
    ours_plain, m2 = grey(images["ours_plain"])
    storm, m3 = grey(images["storm_parallax"])
    storm_flat, m4 = grey(images["storm_flat"])
    if blur:
        ours, ours_plain = _blur(ours, blur), _blur(ours_plain, blur)
    mask = erode(m1 & m2 & m3 & m4)
    return Contribution(ours - ours_plain, storm - storm_flat,
                        mask if where is None else mask & where)


def measure(folder: Path) -> list[dict]:
    plaid_views = texture_views(folder / "plaid", turns=TURNS, zoom=3.0, lighting="dome")
    ramp_shot = replace(TEXTURE_SHOT, stage=ramp_stage(folder))
    ramp_views = texture_views(folder / "ramp", turns=TURNS, shot=ramp_shot, zoom=3.0,
                               lighting="dome")
    rows = []
    for degrees in TURNS:
        images, ramp = plaid_views.images[degrees], ramp_views.images[degrees]
        wrong = storm_st_wrong(ramp)
        covered = plaid(images).mask
        rows.append({
            "degrees": degrees, "wrong": float(wrong[covered].mean()),
            "as measured": plaid(images).correlation(),
            "right st": plaid(images, ~wrong).correlation(),
            "blurred": plaid(images, blur=BLUR).correlation(),
            "both": plaid(images, ~wrong, BLUR).correlation(),
            "offsets": offsets(ramp, ~wrong)})
    return rows


def report(rows: list[dict], seconds: float) -> str:
    from .blocks import markers

    begin, end = markers("texture_gap")
    lines = [begin, "", f"Made by `python -m benchmarks.texture_gap --write README.md` "
             f"({seconds:.0f} s here; GL {storm_renderer()}).", "",
             "| camera | plaid contribution, as measured | where Storm's st is right | "
             "ours blurred to Storm's sharpness | both | Storm's st wrong | texture offset "
             "s: correlation, slope | t: correlation, slope |",
             "|---|---|---|---|---|---|---|---|"]
    for row in rows:
        camera = "the shot's" if row["degrees"] == 0 else f"turned {row['degrees']:g} degrees"
        s, t = row["offsets"]["s"], row["offsets"]["t"]
        lines.append(f"| {camera} | {row['as measured']:.3f} | {row['right st']:.3f} | "
                     f"{row['blurred']:.3f} | {row['both']:.3f} | {100 * row['wrong']:.0f}% "
                     f"of the pixels | {s[0]:.3f}, {s[1]:.3f} | {t[0]:.3f}, {t[1]:.3f} |")
    lines += ["", end]
    return "\n".join(lines)


def storm_renderer() -> str:
    """The machine's GL renderer (EGL's default device, which Storm's EGL context takes
    too)."""
    import moderngl

    ctx = moderngl.create_standalone_context(backend="egl")
    try:
        return f"on {ctx.info['GL_RENDERER']}"
    finally:
        ctx.release()


def main(argv=None) -> int:
    import argparse

    from .blocks import emit

    parser = argparse.ArgumentParser(prog="python -m benchmarks.texture_gap",
                                     description="What keeps Storm from ours in the texture "
                                     "shot (about 10 minutes; needs the real-client Python).")
    parser.add_argument("--write", type=Path, default=None,
                        help="replace the texture_gap block of this file (README.md)")
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        rows = measure(Path(folder))
    emit(args.write, "texture_gap",
         report(rows, time.perf_counter() - started))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
