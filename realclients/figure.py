"""The README's side-by-side figures, each with its measured agreement.

    python -m realclients.figure docs/images/storm [--width 360]

writes ``NAME.png`` (usdwrinkle left, Storm right: plain frames through one camera) for
each shot of FIGURE_SHOTS and prints one table row per shot, in the README's format.

    python -m realclients.figure --bakes docs/images/renderers [--width 360]

writes ``NAME.png`` for each shot of bakes.MAP_SHOTS: usdwrinkle's render, then Storm's
renders of the bake outputs (maps layer; geometry layer with the render purpose;
display-colour layer, as usdview shows them by default), then Cycles' (maps layer;
geometry layer), textures flattened to one grey (bakes.py says why), and prints a table
row per shot. Cycles' lights are scaled by CYCLES_LIGHT_SCALE at import: Blender's USD
importer does not read UsdLux distant-light intensities as Storm does; the figure
compares wrinkles, not exposure. Needs the real-client Python (realclients/__init__.py).

    python -m realclients.figure --texture docs/images/renderers [--demo-width]

writes ``texture.png`` (issue 56's shot, the shirt at W = 0.28; with ``--demo-width``
``texture_demo.png``, the bundled shirt at its own W): the plaid shirt's upper arm at
frame 24 (960 px frames, cropped):
usdwrinkle, Storm through ``--maps normal,parallax``'s MaterialX network, Cycles through
the Blender add-on, Storm through the UsdPreviewSurface alone, and prints their
correlations (bakes.texture_views).
"""
from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

from .bakes import CYCLES_HEAD_LIGHT, CYCLES_LIGHT_SCALE
from .shots import PLAIN_SHOTS, Shot, compare_plain_frames

#: shot name -> frame shown
FIGURE_FRAMES = {"shirt": 24, "pillow": 24, "CesiumMan": 24, "test_lbs": 60}


def figure_shots() -> list[Shot]:
    by_name = {shot.name: shot for shot in PLAIN_SHOTS}
    return [Shot(name, by_name[name].stage, (frame,), by_name[name].all_meshes)
            for name, frame in FIGURE_FRAMES.items()]


def bake_figure(folder: Path, width: int, scratch: Path) -> None:
    import dataclasses

    import numpy as np

    from . import cycles
    from .bakes import MAP_SHOTS, bake_views
    from .compare import compare, read_rgba8, side_by_side

    print("| shot | usdwrinkle; Storm: maps, geometry, display colour; Cycles: maps, "
          "geometry | maps (Storm, worst tile) | geometry (Storm) |")
    print("|---|---|---|---|")
    for shot in MAP_SHOTS:
        shot = dataclasses.replace(shot, width=max(width, shot.width * width // 640))
        views = bake_views(shot, scratch / shot.name, display_color=True)
        p, images = views.prepared, views.images
        height = read_rgba8(images["ours"]).shape[0]
        jobs = [{"stage": str(p.base(f"{kind}.usda")), "camera": p.camera,
                 "frame": shot.frame, "width": shot.width, "height": height,
                 "out": str(p.base(f"cycles_{kind}.png")), "samples": 32,
                 "light_scale": CYCLES_LIGHT_SCALE,
                 "camera_light": CYCLES_HEAD_LIGHT if p.camera_light else None,
                 "purposes": ["default", "render"] if kind == "geometry" else None}
                for kind in ("maps", "geometry")]
        failed = {k: v for k, v in cycles(jobs).items() if v != "ok"}
        if failed:
            raise RuntimeError(f"Cycles could not render {shot.name}: {failed}")
        panels = [images["ours"], images["storm_maps"], images["storm_geometry"],
                  images["storm_display"], *(job["out"] for job in jobs)]
        target = folder / f"{shot.name}.png"
        side_by_side(panels, target)
        # as the real-client test compares them: without the pixels the draw turned to the
        # horizon, which a normal map cannot
        maps = views.maps()
        maps.mask &= ~views.horizon_turned()
        worst = min(c for c, _ in maps.tiles().values())
        geometry = compare(images["ours_geometry"], images["storm_geometry"]).correlation
        print(f"| {shot.name} | ![{shot.name}]({target}) | {worst:.3f} | "
              f"{np.round(geometry, 3):.3f} |")


#: the texture figure's crop of the 960 x 640 frame (rows, columns): the upper arm
TEXTURE_CROP = (slice(120, 460), slice(380, 660))


def texture_figure(folder: Path, scratch: Path, demo: bool = False) -> None:
    """texture.png: the upper arm through usdwrinkle, Storm (the MaterialX network),
    Cycles (the Blender add-on) and Storm (the UsdPreviewSurface alone), under the
    stage's lights (Cycles without shadows, as the others draw); issue 56's shot (the
    shirt at W = 0.28), or with ``demo`` texture_demo.png, the bundled shirt as it is."""
    from .bakes import DEMO_TEXTURE_SHOT, TEXTURE_SHOT, texture_views
    from .compare import read_rgba8, side_by_side

    shot = DEMO_TEXTURE_SHOT if demo else TEXTURE_SHOT
    # Storm's four 960-pixel views took over 10 minutes on llvmpipe (2 cores, 2026-12-03)
    views = texture_views(scratch, turns=(0.0,), shot=shot, clients=("storm", "cycles"),
                          samples=64, storm_timeout=2400)
    images = views.images[0.0]
    panels = []
    for label in ("ours", "storm_parallax", "cycles_parallax", "storm_normal"):
        crop = scratch / f"crop_{label}.png"
        _write_rgba8(read_rgba8(images[label])[TEXTURE_CROP], crop)
        panels.append(crop)
    target = folder / ("texture_demo.png" if demo else "texture.png")
    side_by_side(panels, target)
    for label in ("storm_parallax", "cycles_parallax", "storm_normal", "cycles_stock"):
        c = views.contribution(0.0, label)
        print(f"{target}: {label}: correlation {c.correlation():.3f}, fine part "
              f"{c.high_pass_correlation():.3f}")


def _write_rgba8(pixels, path: Path) -> None:
    import numpy as np
    import OpenImageIO as oiio

    pixels = np.ascontiguousarray(pixels)
    buf = oiio.ImageBuf(oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2],
                                       oiio.UINT8))
    buf.set_pixels(oiio.ROI(0, pixels.shape[1], 0, pixels.shape[0], 0, 1, 0,
                            pixels.shape[2]), pixels)
    buf.write(str(path))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m realclients.figure",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--width", type=int, default=360)
    parser.add_argument("--bakes", action="store_true",
                        help="the bake outputs in Storm and Cycles beside usdwrinkle")
    parser.add_argument("--texture", action="store_true",
                        help="the texture deformation in Storm (--maps parallax) and in "
                             "Cycles (the Blender add-on) beside usdwrinkle")
    parser.add_argument("--demo-width", action="store_true",
                        help="with --texture: the bundled shirt at its own W (0.1; "
                             "texture_demo.png) instead of issue 56's shot (W = 0.28)")
    args = parser.parse_args(argv)
    args.folder.mkdir(parents=True, exist_ok=True)
    if args.texture:
        with tempfile.TemporaryDirectory() as scratch:
            texture_figure(args.folder, Path(scratch), demo=args.demo_width)
        return 0
    if args.bakes:
        with tempfile.TemporaryDirectory() as scratch:
            bake_figure(args.folder, args.width, Path(scratch))
        return 0
    with tempfile.TemporaryDirectory() as scratch:
        comparisons = compare_plain_frames(figure_shots(), Path(scratch), width=args.width)
        print("| shot | frame | usdwrinkle (left) and Storm (right) | correlation | mean "
              "difference |")
        print("|---|---|---|---|---|")
        for c in comparisons:
            target = args.folder / f"{c.shot.name}.png"
            shutil.copyfile(str(c.ours).replace(".ours.png", ".sbs.png"), target)
            print(f"| {c.shot.name} | {c.frame:g} | ![{c.shot.name}]({target}) | "
                  f"{c.match.correlation:.3f} | {c.match.mean_abs:.1f}/255 |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
