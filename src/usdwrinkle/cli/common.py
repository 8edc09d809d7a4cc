"""Arguments and checks shared by subcommands."""
from __future__ import annotations

import os

from ..process.errors import print_stderr, print_warning


def add_stage_args(parser) -> None:
    parser.add_argument("--all-meshes", action="store_true",
                        help="wrinkle every Mesh, as if WrinkleAPI were applied (with fallbacks)")
    parser.add_argument("--relax-iterations", type=int, metavar="N",
                        help="phase relaxation iterations per frame, 0..10,000 (overrides "
                             "wrinkle:relaxIterations)")
    parser.add_argument("--history-start", type=float, metavar="FRAME",
                        help="first frame of the shot's phase history (default: the stage's "
                             "start time code). Each frame starts from the previous frame's "
                             "phases, so a run that starts later first computes the frames "
                             "from here on; every chunk of a shot must use the same value")


def add_composition_args(parser) -> None:
    """How the stage is composed, without a shot file (scene/composition.py)."""
    group = parser.add_argument_group(
        "composition", "open the stage as a shot composes it, without writing a shot file")
    group.add_argument("--sublayer", action="append", metavar="LAYER", default=None,
                       help="a layer over the stage, e.g. overrides of a read-only .usdz "
                            "(repeatable; the first is the strongest)")
    group.add_argument("--variant", action="append", metavar="PRIM{SET=NAME}",
                       default=None,
                       help="a variant selection in USD's path syntax, e.g. "
                            "'/Kitchen{modelingVariant=Full}' (repeatable)")
    group.add_argument("--mask", metavar="PRIM[,PRIM...]",
                       help="open only these prims and their ancestors (a population mask, "
                            "as usdview's --mask)")


def shot_options(args):
    """The app.ShotOptions of the command's stage and composition options."""
    from ..app.options import ShotOptions

    return ShotOptions(all_meshes=getattr(args, "all_meshes", False),
                       relax_iterations=getattr(args, "relax_iterations", None),
                       history_start=getattr(args, "history_start", None),
                       sublayer=tuple(getattr(args, "sublayer", None) or ()),
                       variant=tuple(getattr(args, "variant", None) or ()),
                       mask=(args.mask,) if getattr(args, "mask", None) else ())


def add_frame_args(parser) -> None:
    parser.add_argument("--frames", metavar="SPEC",
                        help="frames to process, as usdrecord's FrameSpec: 1:48, 101:109x2, "
                             "1,5,10; at most 100,000 frames within +-1e9 (default: the "
                             "stage's start..end, or the default time)")


def add_shot_args(parser, output_help: str) -> None:
    """What render and bake both take: STAGE OUTPUT, --frames, the stage options and the
    composition options."""
    parser.add_argument("stage", help="the USD stage (.usd, .usda, .usdc, .usdz)")
    parser.add_argument("output", help=output_help)
    add_frame_args(parser)
    add_stage_args(parser)
    add_composition_args(parser)



def report_to(job, reporter, args) -> None:
    """Give a job the command's progress bars, header line and status lines."""
    command = args.command + (" on Dask" if getattr(args, "dask", None) is not None else "")
    job.progress = reporter.progress
    job.on_start = lambda: reporter.header(command, args.stage)
    job.say = None if reporter.quiet else print_stderr


class Reporter:
    """A command's warnings on stderr, each once, and a progress bar for multi-frame runs
    (unless quiet). As a context manager it is where usdwrinkle's logged warnings go
    (log.warnings_to) while the command runs."""

    def __init__(self, quiet: bool = False, library: bool = False):
        self.quiet = quiet
        #: called from Python (usdwrinkle.api): warnings go to the library's logger, so
        #: that the caller's own ``log.collect()`` or logging sees them, not to stderr
        self.library = library
        self.seen: set[str] = set()
        self._sink = None

    def __enter__(self) -> Reporter:
        from ..process.log import warnings_to

        if not self.library:
            self._sink = warnings_to(self.warn)
            self._sink.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self._sink is not None:
            self._sink.__exit__(*exc)
        self._sink = None

    def warn(self, message: str) -> None:
        if message in self.seen:
            return
        self.seen.add(message)
        if self.library:
            from ..process.log import warn

            warn(message)
        else:
            from .flags import flagged

            print_warning(flagged(message))  # a job's `field`: its flag

    def header(self, command: str, stage_path: str) -> None:
        """The line that starts a run's work (after every check that may refuse it, so a
        refusal stays one line), so that a farm log says what ran where: the version, the
        command, the stage, and the GL renderer (a GPU node or llvmpipe)."""
        if self.quiet:
            return
        from .. import __version__
        from ..app.environment import renderer_info
        from ..process.errors import print_stderr

        info = renderer_info()
        print_stderr(f"usdwrinkle: version {__version__}, {command} "
                     f"{os.path.abspath(stage_path)}, GL renderer {info['renderer']} "
                     f"(OpenGL {info['version']})")

    def progress(self, items, desc: str):
        if self.quiet or len(items) < 2:
            return items
        from ..process.progress import wrap  # a bar on a terminal, log lines in a farm's log

        return wrap(items, desc)
