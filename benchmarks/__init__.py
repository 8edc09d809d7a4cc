"""usdwrinkle's benchmarks: the paper's timing table, scaling, baselines, end to end,
the farm rows, the peer row against usdview's Storm, the paint window, triangulation and
the floors, measured in one run.

    python -m benchmarks [--json PATH] [--markdown PATH] [--quick] ...

They live in the source checkout, not in the wheel, and import usdwrinkle as any user
would; nothing in the package imports them. ``usdwrinkle bench ...`` (an editable install)
runs this same command in a child process.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

# the sections are imported where they run: a module of this package run on its own
# (benchmarks.misfit --before runs itself against another checkout's usdwrinkle) imports
# none of them


def run_bench(quick: bool = False, corpus: Path | None = None, progress=print,
              before: str | None = None, checkpoint=None) -> dict:
    """Every section in turn; ``checkpoint(result)`` after each (the sections so far: a
    run stopped by a time limit keeps what it measured)."""
    from usdwrinkle.render.context import create_context

    from .cpu_nodes import cpu_nodes
    from .floors import floors
    from .measure import (
        end_to_end,
        machine,
        numpy_baseline,
        paper_table,
        scaling,
        skin_baseline,
        triangulation,
    )
    from .report import targets

    ctx = create_context()
    result = {"quick": quick, "machine": machine(ctx),
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}

    def floors_row():
        return floors(ctx, result["skin_baseline"][-1]["vertices"])

    def farm_row():
        from . import farm as farm_bench
        return farm_bench.farm(quick, corpus)

    def preroll_row():
        from . import farm as farm_bench
        return farm_bench.preroll(quick, ctx)

    def renderers(name):
        from . import renderers as module
        return (module.wrinkle_maps(quick, ctx) if name == "maps" else
                module.displaced_geometry(quick, ctx, corpus))

    def beyond_row():
        from .beyond import overhead
        return overhead(quick, ctx)

    def peers_row():
        from .peers import storm_peer
        return storm_peer(quick, corpus)

    def paint_row():
        from .paint import paint
        return paint(quick, ctx, corpus)

    sections = (("paper_table", "paper table", lambda: paper_table(quick, ctx)),
                ("scaling", "scaling", lambda: scaling(quick, ctx)),
                ("skin_baseline", "skin baseline", lambda: skin_baseline(quick, ctx)),
                ("numpy_baseline", "numpy baseline", lambda: numpy_baseline(quick, ctx)),
                ("end_to_end", "end to end", lambda: end_to_end(quick, ctx, corpus)),
                ("preroll", "preroll", preroll_row),
                ("farm", "farm", farm_row),
                ("cpu_nodes", "cpu render nodes", lambda: cpu_nodes(quick, corpus, ctx,
                                                                     before)),
                ("wrinkle_maps", "wrinkle maps", lambda: renderers("maps")),
                ("displaced_geometry", "displaced geometry", lambda: renderers("geometry")),
                ("beyond", "beyond the paper", beyond_row),
                ("peers", "against Storm", peers_row),
                ("paint", "the paint window", paint_row),
                ("triangulation", "triangulation", lambda: triangulation(quick)),
                ("floors", "floors", floors_row))
    for key, label, step in sections:
        progress(f"bench: {label}")
        result[key] = step()
        if checkpoint is not None:
            checkpoint(result)
    result["targets"] = targets(result)
    return result


def run(args) -> int:
    from usdwrinkle.outputs.atomic import atomic_path

    from .report import history, markdown, targets
    from .stages import default_corpus

    if args.from_json:
        result = _saved_run(args.from_json)
        result["targets"] = targets(result)  # the words of this report's version
    else:
        corpus = Path(args.corpus) if args.corpus else default_corpus()
        from usdwrinkle.process.log import silenced

        def checkpoint(partial: dict) -> None:
            if args.json:  # the sections so far, should the run be stopped
                with atomic_path(args.json) as tmp:
                    Path(tmp).write_text(json.dumps({**partial, "partial": True}, indent=2,
                                                    default=float) + "\n")

        with silenced():  # the shots' degraded-input warnings are not the bench's output
            result = run_bench(args.quick, corpus,
                               progress=lambda m: print(m, file=sys.stderr, flush=True),
                               before=args.before, checkpoint=checkpoint)
        result["command"] = "python -m benchmarks" + (" --quick" if args.quick else "") + (
            f" --json {args.json}" if args.json else "") + (
            f" --markdown {args.markdown}" if args.markdown != "docs/benchmarks.md" else "") + (
            " --before CHECKOUT" if args.before else "")
        if args.label:
            result["label"] = args.label
    result["history"] = history(Path(args.history))
    text = markdown(result)
    if args.markdown == "-":
        sys.stdout.write(text)
    else:
        with atomic_path(args.markdown) as tmp:
            Path(tmp).write_text(text)
        print(f"usdwrinkle: wrote {args.markdown}", file=sys.stderr)
    if args.json and not args.from_json:
        with atomic_path(args.json) as tmp:
            Path(tmp).write_text(json.dumps(result, indent=2, default=float) + "\n")
    return 0


def _saved_run(path: str) -> dict:
    """A run saved with --json, or a one-line error naming what is wrong with the file."""
    from usdwrinkle.process.errors import UsdWrinkleError

    try:
        result = json.loads(Path(path).read_text())
    except OSError as exc:
        raise UsdWrinkleError(f"cannot read --from-json '{path}': {exc.strerror}") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise UsdWrinkleError(f"--from-json '{path}' is not JSON ({exc})") from None
    missing = [key for key in ("machine", "paper_table", "skin_baseline", "numpy_baseline",
                               "scaling", "end_to_end")
               if not isinstance(result, dict) or key not in result]
    if missing:
        raise UsdWrinkleError(f"--from-json '{path}' is not a saved run of python -m "
                              f"benchmarks --json (it lacks {', '.join(missing)})")
    return result


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m benchmarks",
        description="Measure the real pipeline: the paper's five cases, scaling in vertices "
                    "and pixels, UsdSkel's CPU skinning and a numpy crush+relax as baselines, "
                    "CesiumMan end to end, the farm rows, triangulation of hostile meshes and "
                    "the rasteriser's floors. Writes a markdown report (and JSON). Runs from "
                    "a source checkout; `usdwrinkle bench` is the same command.")
    p.add_argument("--json", metavar="PATH", help="also write the results as JSON")
    p.add_argument("--markdown", metavar="PATH",
                   help="markdown report (default docs/benchmarks.md, or with --quick "
                        "bench-quick.md in the current folder, so that a smoke test never "
                        "overwrites the committed figures; '-' for stdout)")
    p.add_argument("--quick", action="store_true",
                   help="reduced sizes and frames: a smoke test, not figures to quote")
    p.add_argument("--label", metavar="TEXT",
                   help="name this run in the JSON (kept in docs/bench/ for before/after)")
    p.add_argument("--history", metavar="DIR", default="docs/bench",
                   help="folder of labelled JSON runs to tabulate (docs/bench)")
    p.add_argument("--before", metavar="CHECKOUT",
                   help="a checkout of an earlier usdwrinkle (e.g. a git worktree): the CPU "
                        "render nodes section also runs its default EXR render, in turn with "
                        "this one's, as the before row")
    p.add_argument("--from-json", metavar="PATH",
                   help="measure nothing: rewrite the markdown report from a saved run")
    p.add_argument("--corpus", metavar="DIR",
                   help="folder with usd-wg/CesiumMan.usdz (default ../shared/corpus or "
                        "$USDWRINKLE_CORPUS)")
    return p


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    args = build_parser().parse_args(argv)
    if args.markdown is None:
        args.markdown = "bench-quick.md" if args.quick else "docs/benchmarks.md"
    return args


def main(argv: list[str] | None = None) -> int:
    """``python -m benchmarks``: errors as usdwrinkle's one line, exit 2."""
    from usdwrinkle.process.errors import UsdWrinkleError, print_stderr

    args = parse_args(argv)
    try:
        return run(args)
    except UsdWrinkleError as exc:
        print_stderr(f"benchmarks: error: {exc.one_line()}")
        return 2
