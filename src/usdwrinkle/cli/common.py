"""Arguments and checks shared by subcommands."""
from __future__ import annotations

import os
import sys

from ..errors import UsdWrinkleError


def add_stage_args(parser) -> None:
    parser.add_argument("--all-meshes", action="store_true",
                        help="wrinkle every Mesh, as if WrinkleAPI were applied (with fallbacks)")
    parser.add_argument("--relax-iterations", type=int, metavar="N",
                        help="phase relaxation iterations per frame (overrides "
                             "wrinkle:relaxIterations)")
    parser.add_argument("--history-start", type=float, metavar="FRAME",
                        help="first frame of the shot's phase history (default: the stage's "
                             "start time code). Each frame starts from the previous frame's "
                             "phases, so a run that starts later first computes the frames "
                             "from here on; every chunk of a shot must use the same value")


def stage_layer_paths(stage) -> set[str]:
    paths = set()
    for layer in stage.GetUsedLayers():
        real = layer.realPath
        if real:
            paths.add(os.path.realpath(real))
    return paths


def refuse_overwriting_inputs(stage_path: str, outputs: list[str], stage=None) -> None:
    """Never write over the input stage or any layer it uses."""
    protected = {os.path.realpath(stage_path)}
    if stage is not None:
        protected |= stage_layer_paths(stage)
    for out in outputs:
        if os.path.realpath(out) in protected:
            raise UsdWrinkleError(f"output '{out}' is an input layer of the stage; "
                                  "choose another output path")


class Reporter:
    """Warnings to stderr (unless quiet) and a progress bar for multi-frame runs."""

    def __init__(self, quiet: bool = False):
        self.quiet = quiet
        self.seen: set[str] = set()

    def warn(self, message: str) -> None:
        if message in self.seen:
            return
        self.seen.add(message)
        print(f"usdwrinkle: warning: {message}", file=sys.stderr)

    def progress(self, items, desc: str):
        if self.quiet or len(items) < 2:
            return items
        from tqdm import tqdm
        return tqdm(items, desc=desc, unit="frame", file=sys.stderr, dynamic_ncols=True)


def engine_options(args, stage_path: str | None = None, camera: str | None = None,
                   use_baked: bool = True):
    """The EngineOptions of a render or bake run (shot.py)."""
    from ..shot import EngineOptions

    return EngineOptions(os.path.abspath(stage_path or args.stage),
                         all_meshes=args.all_meshes, relax_iterations=args.relax_iterations,
                         camera=camera, history_start=args.history_start, use_baked=use_baked)


def start_engine(args, reporter: Reporter, stage, camera: str | None = None,
                 use_baked: bool = True):
    """The WrinkleEngine of a render or bake run, with the stage options and a preroll bar."""
    engine = engine_options(args, camera=camera, use_baked=use_baked).create(stage,
                                                                             reporter.warn)
    engine.preroll_progress = lambda steps: reporter.progress(steps, "preroll")
    return engine
