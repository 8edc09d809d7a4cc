"""usdwrinkle render STAGE OUTPUT: render frames headlessly to images."""
from __future__ import annotations

import argparse

from ..app.frames import frame_path
from ..app.options import AOVS_TEXT, EXR_COMPRESSIONS
from ..process.errors import print_stderr
from .common import Reporter, add_shot_args, report_to, shot_options


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "render", help="render frames of a stage to images",
        description="Render wrinkled frames of a USD stage headlessly. OUTPUT holds a '#' frame "
                    "placeholder (out/shot.####.exr); the format follows the extension. EXR gets "
                    "R,G,B,A, wrinkle.height, wrinkle.amplitude, N.X,N.Y,N.Z and Z (--aovs "
                    "picks fewer); PNG, JPEG and TIFF get the 8-bit sRGB beauty. Meshes whose "
                    "baked wave fields ('usdwrinkle bake') are in the stage are drawn from "
                    "them, with no crush, relax or preroll; a frame the bake does not hold "
                    "(outside its range, or "
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
                   help="where folds turn the normal within a pixel, shade each multisample "
                        "where it lies (the default): wrinkles a few pixels across are "
                        "averaged over the pixel, as a renderer's texture filtering averages "
                        "a baked map; other pixels are shaded once. --no-shade-samples "
                        "shades every pixel once, at its centroid (1.06x faster on "
                        "llvmpipe, jagged fold crests; README: render options)")
    p.add_argument("--relief", action="store_true",
                   help="draw the folds where the view ray meets them, as the displaced "
                        "geometry stands, not where it meets the coarse surface: the flanks "
                        "that face away hide behind the crests instead of standing as dark "
                        "bands, and the texture is seen where the ray lands. Costs up to "
                        "32 blend lookups a pixel where steep folds are seen at a slant "
                        "(README: render options). Renderers reading the maps do not do this")
    p.add_argument("--write-threads", type=int, metavar="N",
                   help="threads that encode and write frames while the next ones render, "
                        "0..64 (default: every CPU core but one, at least 1; for EXR those "
                        "cores are shared with OpenEXR's own threads per file, a quarter of "
                        "the cores, at most 4: 4 writer threads of 4 on 16 cores, "
                        "USDWRINKLE_EXR_THREADS overrides them; with --dask, 1 per worker; 0 "
                        "writes each frame before the next is rendered). Frames in flight: "
                        "one per thread and one more, within a quarter of the available "
                        "memory")
    p.add_argument("--readback-buffers", type=int, metavar="K",
                   help="GPU buffers that frames are resolved into, 1..8 (default: 3 on a "
                        "GPU, 1 on llvmpipe, where the CPU computes the frame anyway): frame "
                        "f is copied out of the GPU after a fence, on a thread of its own, "
                        "while frames f + 1 .. f + K - 1 compute; 1 reads each frame back as "
                        "soon as it is drawn. The files are the same")
    exr = p.add_mutually_exclusive_group()
    exr.add_argument("--exr-half", dest="exr_half", action="store_true",
                     help="EXR: colour and normals as half float, as compositing keeps them; "
                          "depth and the wrinkle fields stay float (the default)")
    exr.add_argument("--exr-float", dest="exr_half", action="store_false",
                     help="EXR: every channel as 32-bit float (files about 60%% larger)")
    p.set_defaults(exr_half=True)
    p.add_argument("--exr-compression", choices=EXR_COMPRESSIONS,
                   default="zip", help="EXR compression; default zip, the fastest lossless "
                                       "compression that keeps files small; none encodes "
                                       "about 5x faster into 8x larger files (a fast local "
                                       "disk may prefer it); dwaa is lossy "
                                       "(docs/benchmarks.md: encoding)")
    p.add_argument("--aovs", metavar="LIST",
                   help=f"EXR: the AOVs each frame stores, comma-separated from {AOVS_TEXT} "
                        "(default: all). Fewer AOVs are fewer planes to resolve, read back "
                        "and encode: a 1080p frame of color alone encodes 3.3x faster "
                        "(README: render). PNG, JPEG and TIFF store color only")
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
                        "encode; ms), the time waited for the writer and the GPU, and the "
                        "loop's wall and CPU seconds to this JSON file; each pass is then "
                        "timed with glFinish between passes, unless --no-stats-passes")
    p.add_argument("--stats-passes", action=argparse.BooleanOptionalAction, default=True,
                   help="with --stats, time each pass (the default; glFinish between passes "
                        "keeps the GPU from working ahead); --no-stats-passes writes the "
                        "frame loop's times alone, as a render without --stats runs")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary")
    p.set_defaults(run=run)


def shot_of(args):
    """The app.Shot of the command's stage and stage options."""
    from ..app.shot import Shot

    return Shot(args.stage, shot_options(args))


def render_job(args, reporter: Reporter | None = None):
    """The app.RenderJob of the command's options."""
    from ..app.options import RenderOptions
    from ..app.render import RenderJob

    options = RenderOptions(
        camera=args.camera, width=args.width, height=args.height, samples=args.samples,
        shade_samples=args.shade_samples, relief=args.relief, write_threads=args.write_threads,
        readback_buffers=args.readback_buffers,
        exr_half=args.exr_half, exr_compression=args.exr_compression, aovs=args.aovs,
        no_wrinkles=args.no_wrinkles, skip_existing=args.skip_existing,
        recompute=args.recompute, stats=args.stats, stats_passes=args.stats_passes,
        dask=args.dask, workers=args.workers, chunk=args.chunk)
    job = RenderJob(shot_of(args), args.output, args.frames, options)
    if reporter is not None:
        report_to(job, reporter, args)
    return job


def summary(result, output: str) -> str:
    """The closing line of a render (an app.RenderResult), serial or on a farm."""
    frames = result.frames
    text = (f"usdwrinkle: wrote {len(result.written)} frame(s) {result.width}x"
            f"{result.height} to {frame_path(output, frames[0])}")
    if len(frames) > 1:  # the first file and the last ('.. 24' read as a count)
        text += f" .. {frame_path(output, frames[-1])}"
    if result.skipped:
        text += f", kept {result.skipped} complete frame(s) (--skip-existing)"
    text += f" in {result.elapsed:.1f} s"
    if result.workers:
        text += (f" ({len(frames) / result.elapsed:.1f} fps over the whole run, "
                 f"{result.workers} Dask worker(s), chunks of {result.chunk})")
    if result.baked:
        text += f"; baked wave fields: {', '.join(result.baked)}"
    return text


def run(args) -> int:
    render_shot(args)
    return 0


def render_shot(args) -> list[str]:
    """The render command's work; returns the file of each frame of the shot (written, or
    kept by --skip-existing)."""
    reporter = Reporter(args.quiet, library=getattr(args, "library", False))
    with reporter:
        job = render_job(args, reporter)
        result = job.run()
        if not args.quiet:
            print_stderr(summary(result, args.output))
    return result.outputs
