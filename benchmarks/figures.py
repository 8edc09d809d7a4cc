"""The README's figures of the other-renderer outputs, made by the commands they show.

    python -m benchmarks.figures [OUTDIR] [--only NAME...]   (default docs/images; NAME:
                                                             maps geometry beyond
                                                             irregularity relief)

- ``maps_shirt.png``: frame 24 of the shirt drawn with wrinkles, next to the full set's
  normal map that ``bake --maps`` wrote for that frame (MikkTSpace, in the sleeve's UVs:
  around the arm across, shoulder to cuff upwards).
- ``geometry_elbow.png``: the shirt's elbow at frame 24, cropped: shading-only wrinkles
  (``render shirt.usda``) next to the displaced render mesh of ``bake --geometry``
  (``render LAYER --no-wrinkles``), whose outline carries the folds.
- ``beyond_pillow.png``, ``beyond_pull.png``: frame 24 of the pillow with
  ``wrinkle:biaxial = 1`` next to the paper's one system, and of the pulled sheet with
  ``wrinkle:tension = 1`` next to tension off (the features switched in the stage's
  session layer, as benchmarks/beyond.py does).
- ``irregularity.png``: the shirt's sleeve at frame 24 with ``wrinkle:irregularity`` 0
  (the paper's regular waves), 0.15 and 0.3, authored in the stage's session layer: the
  cuff's painted gathers and the elbow's folds.
- ``relief.png``: the shirt's sleeve at frame 24 drawn on the coarse surface (``render``),
  with ``render --relief``, and the displaced render mesh of ``bake --geometry``
  (``render --no-wrinkles --sublayer LAYER``), through the shot's camera.
"""
from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHIRT = ROOT / "sample_stages" / "shirt.usda"


def _cli(*args: str) -> None:
    from usdwrinkle.cli.main import main

    code = main([*args, "--quiet"])
    if code:
        raise SystemExit(f"usdwrinkle {' '.join(args)} failed ({code})")


def _read(path) -> np.ndarray:
    import OpenImageIO as oiio

    return oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)


def _resize(path, size: tuple[int, int]) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBufAlgo.resize(oiio.ImageBuf(str(path)),
                                   roi=oiio.ROI(0, size[0], 0, size[1], 0, 1, 0, 3))
    return buf.get_pixels(oiio.FLOAT)


def _write(path, pixels: np.ndarray) -> None:
    import OpenImageIO as oiio

    rgb = np.clip(pixels[..., :3], 0, 1)
    data = np.ascontiguousarray(np.round(rgb * 255), np.uint8)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], 3, "uint8")
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(data)
    out.close()


def maps_figure(outdir: Path) -> Path:
    with tempfile.TemporaryDirectory() as folder:
        layer = os.path.join(folder, "shirt_maps.usda")
        _cli("bake", str(SHIRT), layer, "--maps", "normal", "--map-size", "1024")
        frame = os.path.join(folder, "frame.png")
        _cli("render", str(SHIRT), frame, "--frames", "24", "--width", "640", "--height",
             "480")
        image = _read(frame)
        alpha = image[..., 3:4]
        image = image[..., :3] * alpha + (1 - alpha)  # over white, as the README shows
        normal = _resize(os.path.join(folder, "shirt_maps_maps", "Sleeve.normal.0024.png"),
                         (480, 480))
    gap = np.ones((480, 16, 3), np.float32)
    path = outdir / "maps_shirt.png"
    _write(path, np.concatenate([image, gap, normal], axis=1))
    return path


def _frame_24(stage: str, out: str, size: tuple[int, int], extra: list[str],
              crop: tuple[slice, slice]) -> np.ndarray:
    """``usdwrinkle render STAGE OUT --frames 24`` at ``size`` with ``extra``, over white,
    cropped."""
    _cli("render", stage, out, "--frames", "24", "--width", str(size[0]), "--height",
         str(size[1]), *extra)
    image = _read(out)
    alpha = image[..., 3:4]
    return (image[..., :3] * alpha + (1 - alpha))[crop]


def geometry_figure(outdir: Path) -> Path:
    with tempfile.TemporaryDirectory() as folder:
        layer = os.path.join(folder, "shirt_geometry.usdc")
        _cli("bake", str(SHIRT), layer, "--geometry")
        images = [_frame_24(stage, os.path.join(folder, f"frame{i}.png"), (1280, 960), extra,
                            (slice(380, 900), slice(360, 880)))
                  for i, (stage, extra) in enumerate(((str(SHIRT), []),
                                                      (layer, ["--no-wrinkles"])))]
    gap = np.ones((images[0].shape[0], 16, 3), np.float32)
    path = outdir / "geometry_elbow.png"
    _write(path, np.concatenate([images[0], gap, images[1]], axis=1))
    return path


def _render_stage(stage, width: int, height: int) -> np.ndarray:
    """Frame 24 of an open stage, over white."""
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.images.colour import srgb_encode

    engine = WrinkleEngine(stage)
    try:
        color = engine.render_frame(24.0, width, height)["color"].pixels
    finally:
        engine.release()
    alpha = np.clip(color[..., 3:4], 0, 1)
    straight = np.divide(color[..., :3], alpha, out=np.zeros_like(color[..., :3]),
                         where=alpha > 0)
    return srgb_encode(np.clip(straight, 0, 1)) * alpha + (1 - alpha)


def beyond_figures(outdir: Path) -> list[Path]:
    from .beyond import _stage

    paths = []
    for name in ("pillow", "pull"):
        images = [_render_stage(_stage(name, on), 560, 400) for on in (True, False)]
        gap = np.ones((400, 16, 3), np.float32)
        path = outdir / f"beyond_{name}.png"
        _write(path, np.concatenate([images[0], gap, images[1]], axis=1))
        paths.append(path)
    return paths


def irregularity_figure(outdir: Path) -> Path:
    from pxr import Sdf, Usd

    from usdwrinkle.usd import schema

    images = []
    for value in (0.0, 0.15, 0.3):
        stage = Usd.Stage.Open(str(SHIRT))
        stage.SetEditTarget(stage.GetSessionLayer())
        stage.OverridePrim("/World/Arm/Sleeve").CreateAttribute(
            schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(value)
        images.append(_render_stage(stage, 900, 600)[120:560, 330:600])
    gap = np.ones((images[0].shape[0], 16, 3), np.float32)
    path = outdir / "irregularity.png"
    _write(path, np.concatenate([images[0], gap, images[1], gap, images[2]], axis=1))
    return path


def relief_figure(outdir: Path) -> Path:
    with tempfile.TemporaryDirectory() as folder:
        layer = os.path.join(folder, "shirt_geometry.usdc")
        _cli("bake", str(SHIRT), layer, "--geometry", "--frames", "24")
        images = [_frame_24(str(SHIRT), os.path.join(folder, f"frame{i}.png"), (1080, 720),
                            extra, (slice(70, 640), slice(250, 790)))
                  for i, extra in enumerate(([], ["--relief"],
                                             ["--no-wrinkles", "--sublayer", layer]))]
    gap = np.ones((images[0].shape[0], 16, 3), np.float32)
    path = outdir / "relief.png"
    _write(path, np.concatenate([images[0], gap, images[1], gap, images[2]], axis=1))
    return path


FIGURES = {"maps": maps_figure, "geometry": geometry_figure, "beyond": beyond_figures,
           "irregularity": irregularity_figure, "relief": relief_figure}


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="python -m benchmarks.figures")
    parser.add_argument("outdir", nargs="?", type=Path, default=ROOT / "docs" / "images")
    parser.add_argument("--only", nargs="+", choices=sorted(FIGURES), default=list(FIGURES))
    args = parser.parse_args(sys.argv[1:] if argv is None else argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    for name in args.only:
        made = FIGURES[name](args.outdir)
        for path in made if isinstance(made, list) else [made]:
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
