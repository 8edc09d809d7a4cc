"""usdwrinkle render STAGE OUTPUT: render frames headlessly to images."""
from __future__ import annotations

import argparse
import os
import time

from ..errors import UsdWrinkleError, print_stderr
from ..limits import LOCAL_WORKERS_PER_CORE
from ..outputs.images import EXR_COMPRESSIONS
from .common import (
    Reporter,
    add_shot_args,
    check_stage_args,
    composition_of,
    engine_options,
    refuse_overwriting_inputs,
    start_engine,
)
from .frames import frame_path, frame_paths, parse_frame_spec


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "render", help="render frames of a stage to images",
        description="Render wrinkled frames of a USD stage headlessly. OUTPUT holds a '#' frame "
                    "placeholder (out/shot.####.exr); the format follows the extension. EXR gets "
                    "R,G,B,A, wrinkle.height, wrinkle.amplitude, N.X,N.Y,N.Z and Z; PNG, JPEG "
                    "and TIFF get the 8-bit sRGB beauty. Meshes whose baked wave fields "
                    "('usdwrinkle bake') are in the stage are drawn from them, with no crush, "
                    "relax or preroll; a frame the bake does not hold (outside its range, or "
                    "missing inside it) is an error: bake it, or pass --recompute.")
    add_shot_args(p, "output image path with '#' frame placeholder")
    p.add_argument("--camera", metavar="PRIM",
                   help="camera prim path or name (default: the primary camera, then the first "
                        "camera, then an automatic framing of the bounds)")
    p.add_argument("--width", type=int, default=960, metavar="PX", help="image width (960)")
    p.add_argument("--height", type=int, metavar="PX",
                   help="image height (default: from the camera's aspect ratio)")
    p.add_argument("--samples", type=int, default=4, metavar="N",
                   help="multisamples per pixel for anti-aliased edges, a power of two (4; 1 "
                        "turns it off)")
    p.add_argument("--shade-samples", action=argparse.BooleanOptionalAction, default=True,
                   help="shade every multisample where it lies (the default): wrinkles a few "
                        "pixels across are averaged over the pixel, as a renderer's texture "
                        "filtering averages a baked map; --no-shade-samples shades each "
                        "pixel once, at its centroid (about 1.4x faster on llvmpipe, jagged "
                        "fold crests; README: render options)")
    p.add_argument("--write-threads", type=int, default=1, metavar="N",
                   help="threads that encode and write frames while the next ones render "
                        "(1; at most 2 frames in flight; 0 writes each frame before the next "
                        "is rendered)")
    exr = p.add_mutually_exclusive_group()
    exr.add_argument("--exr-half", dest="exr_half", action="store_true",
                     help="EXR: colour and normals as half float, as compositing keeps them; "
                          "depth and the wrinkle fields stay float (the default)")
    exr.add_argument("--exr-float", dest="exr_half", action="store_false",
                     help="EXR: every channel as 32-bit float (files about 60%% larger)")
    p.set_defaults(exr_half=True)
    p.add_argument("--exr-compression", choices=EXR_COMPRESSIONS,
                   default="zip", help="EXR compression; default zip (the fastest "
                                       "compressed encode measured, docs/benchmarks.md)")
    p.add_argument("--no-wrinkles", action="store_true",
                   help="render the same shading without wrinkles (comparison, timing)")
    p.add_argument("--skip-existing", action="store_true",
                   help="skip frames whose output file already exists and reads back as a whole "
                        "image of this size (resume a farm chunk); others are rendered again")
    p.add_argument("--recompute", action="store_true",
                   help="ignore baked wave fields in the stage and compute every mesh's "
                        "wrinkles (with the phase history preroll)")
    farm = p.add_argument_group(
        "farm", "render chunks of frames on a Dask cluster (pip install 'usdwrinkle[farm]')")
    farm.add_argument("--dask", nargs="?", const="local", metavar="SCHEDULER",
                      help="render on Dask: without SCHEDULER, a local cluster of worker "
                           "processes; with tcp://host:port, a running 'dask scheduler'. "
                           "Unless the stage already holds baked wave fields for every "
                           "frame, they are baked first, once, into usdwrinkle_bake/"
                           "STAGE_NAME.wrinkles.usdc beside the outputs (not among the "
                           "frames)")
    farm.add_argument("--chunk", type=int, metavar="N",
                      help="frames per task (default: 10, fewer when the shot is short, so "
                           "that every worker gets at least two chunks)")
    farm.add_argument("--workers", type=int, metavar="N",
                      help="worker processes of the local cluster (default: the CPU cores)")
    p.add_argument("--stats", metavar="FILE.json",
                   help="write per-frame timings (USD read, skin, crush, relax, draw, readback, "
                        "encode; ms) and the time waited for the writer to this JSON file; "
                        "each pass is then timed with glFinish between passes")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=run)


def check_render_args(args) -> None:
    """Refuse bad options before any stage is read."""
    from ..outputs.images import check_format
    from ..render.buffers import check_samples

    refuse_overwriting_inputs(args.stage, [args.output])
    check_format(args.output)
    if args.width <= 0 or (args.height is not None and args.height <= 0):
        raise UsdWrinkleError("--width and --height must be positive")
    check_samples(args.samples)
    if not 0 <= args.write_threads <= 8:
        raise UsdWrinkleError("--write-threads must be in 0..8")
    check_stage_args(args)
    if args.chunk is not None and args.chunk < 1:
        raise UsdWrinkleError("--chunk must be at least 1")
    if args.workers is not None:
        cores = os.cpu_count() or 1
        most = LOCAL_WORKERS_PER_CORE * cores
        if not 1 <= args.workers <= most:
            raise UsdWrinkleError(f"--workers must be in 1..{most} ({LOCAL_WORKERS_PER_CORE} "
                                  f"worker processes per CPU core, {cores} here: each holds "
                                  "its own GL context)")


def summary(written: int, width: int, height: int, output: str, frames: list[float],
            elapsed: float, baked: list[str], extra: str = "", skipped: int = 0) -> str:
    """The closing line of a render, serial or on a farm (``skipped``: frames that
    --skip-existing found complete)."""
    from ..timecode import format_frame

    last = f" .. {format_frame(frames[-1])}" if len(frames) > 1 else ""
    kept = f", kept {skipped} complete frame(s) (--skip-existing)" if skipped else ""
    text = (f"usdwrinkle: wrote {written} frame(s) {width}x{height} to "
            f"{frame_path(output, frames[0])}{last}{kept} in {elapsed:.1f} s{extra}")
    if baked:
        text += f"; baked wave fields: {', '.join(baked)}"
    return text


def _render_on_dask(args, reporter, stage, frames: list[float], outputs: list[str]) -> None:
    """--dask: the farm's typed request from the options, and the summary of its result."""
    from ..farm.client import FarmRender, render_on_dask
    from ..shot import ImageOptions

    job = FarmRender(
        stage_path=args.stage, output=args.output, frames=tuple(frames),
        outputs=tuple(outputs),
        engine=engine_options(args, camera=args.camera,
                              use_baked=not (args.recompute or args.no_wrinkles)),
        image=ImageOptions(args.width, args.height, args.samples, not args.no_wrinkles,
                           args.write_threads, args.exr_compression, args.exr_half,
                           args.shade_samples),
        frame_spec=args.frames, recompute=args.recompute, skip_existing=args.skip_existing,
        scheduler=args.dask, workers=args.workers, chunk=args.chunk)
    result = render_on_dask(job, stage, reporter)
    if not reporter.quiet:
        print_stderr(summary(result.written, result.width, result.height, args.output, frames,
                      result.elapsed, result.baked,
                      f" ({len(frames) / result.elapsed:.1f} fps over the whole run, "
                      f"{result.workers} Dask worker(s), chunks of {result.chunk})",
                      skipped=result.skipped))


def write_stats(path: str, stats: dict) -> None:
    """--stats: the timings as JSON, written atomically."""
    import json

    from ..outputs.atomic import atomic_path

    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8") as handle:
        json.dump(stats, handle, indent=1)


def _warn_unbaked(engine, reporter, args) -> None:
    """A farm chunk that renders a bake but finds wrinkled meshes without baked fields
    (a bake made without --all-meshes, say) computes them itself, with a preroll: say
    so, since that is what the farm recipe's bake exists to avoid."""
    from ..scene.baked import holds_bake

    if args.recompute or args.no_wrinkles or not holds_bake(engine.stage):
        return
    unbaked = [path for path in engine.wrinkled_paths if path not in engine.baked]
    if unbaked:
        start = engine.history_start()
        preroll = f", with a phase-history preroll from frame {start:g}" \
            if start is not None else ""
        reporter.warn(f"the stage holds a usdwrinkle bake, but {len(unbaked)} wrinkled "
                      f"mesh(es) have no baked wave fields in it; computing them here{preroll} "
                      "(other machines may compute them slightly differently: bake with the "
                      f"options the render uses, e.g. --all-meshes) ({unbaked[0]})")


def _warn_geometry(engine, reporter, args, frames: list[float]) -> None:
    """A ``bake --geometry`` layer carries the wrinkles in its displaced meshes: say so
    instead of advising --all-meshes (which would wrinkle them again), and say when frames
    fall outside the ones it baked (they show its nearest baked frame)."""
    import math

    from ..scene.baked import geometry_bake

    found = geometry_bake(engine.stage)
    if found is None:
        return
    layer, first, last = found
    if not args.no_wrinkles and not engine.wrinkled_paths:
        reporter.warn(f"the stage holds usdwrinkle's displaced geometry, whose wrinkles are in "
                      f"its meshes: render with --no-wrinkles (--all-meshes would wrinkle them "
                      f"a second time) ({layer})")
    if math.isnan(first) or math.isnan(last):
        return
    outside = [f for f in frames if not math.isnan(f) and not first <= f <= last]
    if outside:
        reporter.warn(f"{len(outside)} frame(s) lie outside the frames the displaced geometry "
                      f"was baked for ({first:g}..{last:g}), from {outside[0]:g}: they show its "
                      f"nearest baked frame ({layer})")


def run(args) -> int:
    render_shot(args)
    return 0


def render_shot(args) -> list[str]:
    """The render command's work; returns the file of each frame of the shot (written, or
    kept by --skip-existing). usdwrinkle.api.render calls it too."""
    check_render_args(args)
    with Reporter(args.quiet, library=getattr(args, "library", False)) as reporter:
        return _render_shot(args, reporter)


def _render_shot(args, reporter) -> list[str]:
    from ..imagefiles import is_complete_image
    from ..outputs.atomic import check_writable, sweep_dead_temporaries
    from ..scene.baked import geometry_bake
    from ..scene.stage import (
        inherited_range_note,
        open_stage,
        outside_range_note,
        stage_frames,
    )
    from ..shot import NO_WRINKLED_MESH, ImageOptions, render_frames, unapplied_note

    # everything that can be refused without the GPU is checked first
    stage = open_stage(args.stage, composition_of(args))
    frames = parse_frame_spec(args.frames) if args.frames else stage_frames(stage)
    if not args.frames and (note := inherited_range_note(stage)):
        reporter.warn(note)
    outputs = frame_paths(args.output, frames)
    extra = [args.stats] if args.stats else []
    if args.stats and os.path.realpath(args.stats) in {os.path.realpath(o) for o in outputs}:
        raise UsdWrinkleError(f"--stats '{args.stats}' is the path of a frame this run "
                              "writes; choose another file for the timings")
    refuse_overwriting_inputs(args.stage, outputs + extra, stage)
    check_writable(outputs + extra)
    sweep_dead_temporaries(outputs)  # what a killed run of these frames left behind
    if args.dask is not None:
        if args.stats:
            reporter.warn("--stats applies to a serial render; ignored with --dask")
        _render_on_dask(args, reporter, stage, frames, outputs)
        return outputs
    if args.chunk is not None or args.workers is not None:
        reporter.warn("--chunk and --workers apply to --dask only; ignored")
    # --no-wrinkles draws no waves, so it needs no baked frames either
    engine = start_engine(args, reporter, stage, args.camera,
                          use_baked=not (args.recompute or args.no_wrinkles))
    try:
        engine.check_baked(frames)
        computed = not args.no_wrinkles and any(path not in engine.baked
                                                for path in engine.wrinkled_paths)
        if computed and args.frames and args.history_start is None and \
                (note := outside_range_note(stage, frames)):
            reporter.warn(note)  # a preroll from the shot's start (not for baked frames)
        _warn_unbaked(engine, reporter, args)
        unapplied = None if args.all_meshes or args.no_wrinkles else \
            unapplied_note(engine.stage)
        if unapplied:
            reporter.warn(unapplied)
        _warn_geometry(engine, reporter, args, frames)
        if not engine.wrinkled_paths and not args.no_wrinkles and \
                geometry_bake(engine.stage) is None and unapplied is None:
            reporter.warn("the stage has no Mesh to wrinkle; rendering without wrinkles"
                          if args.all_meshes else NO_WRINKLED_MESH)
        mapped = [path for path in engine.wrinkled_paths
                  if engine.meshes[path].material.wrinkle_maps]
        if mapped and not args.no_wrinkles:
            reporter.warn(f"{len(mapped)} mesh(es) have baked wrinkle maps in their material "
                          f"and are drawn with wrinkles too, so their wrinkles show twice; "
                          f"pass --no-wrinkles to draw the maps alone ({mapped[0]})")
        width, height = engine.resolution(args.width, args.height, frames[0])
        image = ImageOptions(width, height, args.samples, not args.no_wrinkles,
                             args.write_threads, args.exr_compression, args.exr_half,
                             args.shade_samples)
        engine.check_relax_work(frames, not args.no_wrinkles)  # a refusal: before the header
        reporter.header(args.command, args.stage)
        started = time.perf_counter()
        stats = {} if args.stats else None
        written = render_frames(
            engine, image, frames, outputs,
            skip=(lambda path: is_complete_image(path, width, height)) if args.skip_existing
            else (lambda path: False),
            progress=lambda items: reporter.progress(items, "render"), stats=stats)
        if stats is not None:
            write_stats(args.stats, stats)
        if not args.quiet:
            print_stderr(summary(len(written), width, height, args.output, frames,
                          time.perf_counter() - started, engine.baked_paths,
                          skipped=len(frames) - len(written) if args.skip_existing else 0))
    finally:
        engine.release()
    return outputs
