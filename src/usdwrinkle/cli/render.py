"""usdwrinkle render STAGE OUTPUT: render frames headlessly to images."""
from __future__ import annotations

import os
import time

from .common import (
    Reporter,
    add_stage_args,
    at_frame,
    refuse_overwriting_inputs,
    start_engine,
)
from .frames import add_frame_args, check_output_pattern, frame_path, parse_frame_spec


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "render", help="render frames of a stage to images",
        description="Render wrinkled frames of a USD stage headlessly. OUTPUT holds a '#' frame "
                    "placeholder (out/shot.####.exr); the format follows the extension. EXR gets "
                    "R,G,B,A, wrinkle.height, wrinkle.amplitude, N.X,N.Y,N.Z and Z; PNG, JPEG "
                    "and TIFF get the 8-bit sRGB beauty.")
    p.add_argument("stage", help="the USD stage (.usd, .usda, .usdc, .usdz)")
    p.add_argument("output", help="output image path with '#' frame placeholder")
    add_frame_args(p)
    p.add_argument("--camera", metavar="PRIM",
                   help="camera prim path or name (default: the primary camera, then the first "
                        "camera, then an automatic framing of the bounds)")
    p.add_argument("--width", type=int, default=960, metavar="PX", help="image width (960)")
    p.add_argument("--height", type=int, metavar="PX",
                   help="image height (default: from the camera's aspect ratio)")
    p.add_argument("--samples", type=int, default=4, metavar="N",
                   help="multisamples per pixel for anti-aliased edges (4; 1 turns it off)")
    add_stage_args(p)
    p.add_argument("--no-wrinkles", action="store_true",
                   help="render the same shading without wrinkles (comparison, timing)")
    p.add_argument("--skip-existing", action="store_true",
                   help="skip frames whose output file already exists (resume a farm chunk)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=run)


def run(args) -> int:
    from ..engine import format_frame
    from ..errors import UsdWrinkleError
    from ..outputs.images import aovs_for, check_format, write_image
    from ..scene.stage import open_stage, stage_frames

    refuse_overwriting_inputs(args.stage, [args.output])
    check_format(args.output)
    if args.width <= 0 or (args.height is not None and args.height <= 0):
        raise UsdWrinkleError("--width and --height must be positive")
    if args.samples < 1:
        raise UsdWrinkleError("--samples must be at least 1")
    if args.relax_iterations is not None and args.relax_iterations < 0:
        raise UsdWrinkleError("--relax-iterations must be >= 0")
    reporter = Reporter(args.quiet)
    # everything that can be refused without the GPU is checked first
    stage = open_stage(args.stage)
    frames = parse_frame_spec(args.frames) if args.frames else stage_frames(stage)
    check_output_pattern(args.output, frames)
    outputs = [frame_path(args.output, f) for f in frames]
    refuse_overwriting_inputs(args.stage, outputs, stage)
    engine = start_engine(args, reporter, stage, args.camera)
    try:
        if not engine.wrinkled_paths and not args.no_wrinkles:
            reporter.warn("no mesh has WrinkleAPI applied; rendering without wrinkles "
                          "(use --all-meshes to wrinkle every mesh)")
        width, height = engine.resolution(args.width, args.height, frames[0])
        started = time.perf_counter()
        written = 0
        for frame, path in reporter.progress(list(zip(frames, outputs, strict=True)), "render"):
            if args.skip_existing and os.path.exists(path):
                continue
            with at_frame(frame):
                buffers = engine.render_frame(frame, width, height, not args.no_wrinkles,
                                              args.samples, aovs_for(path))
            write_image(path, buffers)
            written += 1
        if not args.quiet:
            elapsed = time.perf_counter() - started
            print(f"usdwrinkle: wrote {written} frame(s) {width}x{height} to "
                  f"{frame_path(args.output, frames[0])}"
                  f"{' .. ' + format_frame(frames[-1]) if len(frames) > 1 else ''} "
                  f"in {elapsed:.1f} s", flush=True)
    finally:
        engine.release()
    return 0
