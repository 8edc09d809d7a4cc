"""Arguments and checks shared by subcommands."""
from __future__ import annotations

import os

from ..errors import UsdWrinkleError, print_warning


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


def composition_of(args):
    """The Composition of the command's options (empty without them)."""
    from ..scene.composition import Composition

    mask = getattr(args, "mask", None)
    if isinstance(mask, str):
        mask = [part.strip() for part in mask.split(",") if part.strip()]
    return Composition(tuple(getattr(args, "sublayer", None) or ()),
                       tuple(getattr(args, "variant", None) or ()), tuple(mask or ()))


def add_shot_args(parser, output_help: str) -> None:
    """What render and bake both take: STAGE OUTPUT, --frames, the stage options and the
    composition options."""
    from .frames import add_frame_args

    parser.add_argument("stage", help="the USD stage (.usd, .usda, .usdc, .usdz)")
    parser.add_argument("output", help=output_help)
    add_frame_args(parser)
    add_stage_args(parser)
    add_composition_args(parser)


def check_stage_args(args) -> None:
    """Refuse stage options out of range (add_stage_args), before any stage is read."""
    from ..limits import MAX_RELAX_ITERATIONS
    from .frames import check_time_code

    if args.relax_iterations is not None and not \
            0 <= args.relax_iterations <= MAX_RELAX_ITERATIONS:
        raise UsdWrinkleError(f"--relax-iterations must be in 0..{MAX_RELAX_ITERATIONS:,}")
    if args.history_start is not None:
        check_time_code(args.history_start, "--history-start")


from ..scene.stage import refuse_overwriting_inputs  # noqa: E402,F401  (the CLI's name)


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
        from ..log import warnings_to

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
            from ..log import warn

            warn(message)
        else:
            print_warning(message)

    def header(self, command: str, stage_path: str) -> None:
        """The line that starts a run's work (after every check that may refuse it, so a
        refusal stays one line), so that a farm log says what ran where: the version, the
        command, the stage, and the GL renderer (a GPU node or llvmpipe)."""
        if self.quiet:
            return
        from .. import __version__
        from ..errors import print_stderr
        from ..render.context import renderer_info

        info = renderer_info()
        print_stderr(f"usdwrinkle: version {__version__}, {command} "
                     f"{os.path.abspath(stage_path)}, GL renderer {info['renderer']} "
                     f"(OpenGL {info['version']})")

    def progress(self, items, desc: str):
        if self.quiet or len(items) < 2:
            return items
        from ..progress import wrap  # a bar on a terminal, log lines in a farm's log

        return wrap(items, desc)


def engine_options(args, stage_path: str | None = None, camera: str | None = None,
                   use_baked: bool = True):
    """The EngineOptions of a render or bake run (shot.py)."""
    from ..shot import EngineOptions

    return EngineOptions(os.path.abspath(stage_path or args.stage),
                         all_meshes=args.all_meshes, relax_iterations=args.relax_iterations,
                         camera=camera, history_start=args.history_start, use_baked=use_baked,
                         profile=bool(getattr(args, "stats", None)),
                         composition=composition_of(args) or None)


def start_engine(args, reporter: Reporter, stage, camera: str | None = None,
                 use_baked: bool = True):
    """The WrinkleEngine of a render or bake run, with the stage options and a preroll bar."""
    from ..scene.params import units_notes

    engine = engine_options(args, camera=camera, use_baked=use_baked).create(
        stage, lambda steps: reporter.progress(steps, "preroll"))
    for note in units_notes(engine.stage, {path: engine.meshes[path]
                                           for path in engine.wrinkled_paths}):
        reporter.warn(note)
    return engine
