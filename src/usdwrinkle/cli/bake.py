"""usdwrinkle bake STAGE OUTPUT_LAYER: write the wrinkle fields back to USD."""
from __future__ import annotations

import time

from .common import (
    Reporter,
    add_shot_args,
    check_stage_args,
    refuse_overwriting_inputs,
    start_engine,
)
from .frames import parse_frame_spec


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "bake", help="bake the wrinkle fields of every frame into a USD layer",
        description="Compute the wrinkles of a stage and write them as per-vertex primvars "
                    "(primvars:wrinkle:amplitude, compression, waveVector, phase, direction; "
                    "interpolation vertex) with a time sample per frame. By default the "
                    "output layer sublayers the input, so 'usdview OUTPUT_LAYER' shows the "
                    "shot with the baked data.")
    add_shot_args(p, "the layer to write (.usda, .usdc or .usd)")
    p.add_argument("--with-points", action="store_true",
                   help="also write the posed points, normals and extent in each mesh's local "
                        "space (as UsdSkelBakeSkinning), and retype the affected SkelRoots to "
                        "Xform so that the composed stage is not skinned twice")
    p.add_argument("--display-color", choices=("amplitude", "compression"),
                   help="also write primvars:displayColor (vertex) as a viridis ramp of that "
                        "field, for usdview's default shading")
    p.add_argument("--sparse", action="store_true",
                   help="write the overs alone, without sublayering the input")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    # The bake is one process on purpose: each frame's phases start from the previous
    # frame's (phase history), so its frames cannot be computed apart (README, farms).
    p.set_defaults(run=run)


def run(args) -> int:
    from ..outputs.atomic import check_writable
    from ..outputs.layers import check_layer_path
    from ..scene.stage import open_stage, stage_frames
    from ..shot import bake_layer, frame_spec_text

    check_stage_args(args)
    refuse_overwriting_inputs(args.stage, [args.output])
    check_layer_path(args.output)
    reporter = Reporter(args.quiet)
    # everything that can be refused without the GPU is checked first
    stage = open_stage(args.stage)
    refuse_overwriting_inputs(args.stage, [args.output], stage)
    check_writable([args.output])
    frames = parse_frame_spec(args.frames) if args.frames else stage_frames(stage)
    # a bake always computes: fields already baked into the input are not its input
    engine = start_engine(args, reporter, stage, use_baked=False)
    try:
        started = time.perf_counter()
        count = bake_layer(engine, args.stage, args.output, frames,
                           args.frames or frame_spec_text(frames),
                           with_points=args.with_points, display_color=args.display_color,
                           sparse=args.sparse, warn=reporter.warn,
                           progress=lambda items: reporter.progress(items, "bake"))
        if not args.quiet:
            print(f"usdwrinkle: baked {count} mesh(es) x {len(frames)} frame(s) to "
                  f"{args.output} in {time.perf_counter() - started:.1f} s", flush=True)
    finally:
        engine.release()
    return 0
