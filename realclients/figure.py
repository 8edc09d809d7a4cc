"""The README's side-by-side figure: usdwrinkle's frame and Storm's (usdview's renderer)
of the same shot, through one camera, with their measured agreement.

    python -m realclients.figure docs/images/storm [--width 360]

writes ``NAME.png`` (usdwrinkle left, Storm right) for each shot of FIGURE_SHOTS and
prints one table row per shot, in the README's format. Needs the real-client Python
(realclients/__init__.py).
"""
from __future__ import annotations

import argparse
import shutil
import tempfile
from pathlib import Path

from .shots import PLAIN_SHOTS, Shot, compare_plain_frames

#: shot name -> frame shown
FIGURE_FRAMES = {"shirt": 24, "pillow": 24, "CesiumMan": 24, "test_lbs": 60}


def figure_shots() -> list[Shot]:
    by_name = {shot.name: shot for shot in PLAIN_SHOTS}
    return [Shot(name, by_name[name].stage, (frame,), by_name[name].all_meshes)
            for name, frame in FIGURE_FRAMES.items()]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m realclients.figure",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--width", type=int, default=360)
    args = parser.parse_args(argv)
    args.folder.mkdir(parents=True, exist_ok=True)
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
