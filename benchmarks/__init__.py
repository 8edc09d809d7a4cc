"""usdwrinkle's benchmarks: the paper's timing table, scaling, baselines, end to end,
the farm rows, the peer row against usdview's Storm, triangulation and the floors,
measured in one run.

    usdwrinkle bench [--json PATH] [--markdown PATH] [--quick]
    python -m benchmarks ...

They live in the source checkout, not in the wheel: `usdwrinkle bench` runs them from a
checkout (cli/bench.py finds this folder).
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

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
from .report import history, markdown, targets
from .stages import default_corpus


def run_bench(quick: bool = False, corpus: Path | None = None, progress=print,
              before: str | None = None) -> dict:
    from usdwrinkle.render.context import create_context

    ctx = create_context()
    result = {"quick": quick, "machine": machine(ctx),
              "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    for key, step in (("paper_table", lambda: paper_table(quick, ctx)),
                      ("scaling", lambda: scaling(quick, ctx)),
                      ("skin_baseline", lambda: skin_baseline(quick, ctx)),
                      ("numpy_baseline", lambda: numpy_baseline(quick, ctx)),
                      ("end_to_end", lambda: end_to_end(quick, ctx, corpus))):
        progress(f"bench: {key.replace('_', ' ')}")
        result[key] = step()
    from . import farm as farm_bench
    progress("bench: preroll")
    result["preroll"] = farm_bench.preroll(quick, ctx)
    progress("bench: farm")
    result["farm"] = farm_bench.farm(quick, corpus)
    progress("bench: cpu render nodes")
    result["cpu_nodes"] = cpu_nodes(quick, corpus, ctx, before)
    progress("bench: wrinkle maps")
    from .renderers import displaced_geometry, wrinkle_maps
    result["wrinkle_maps"] = wrinkle_maps(quick, ctx)
    progress("bench: displaced geometry")
    result["displaced_geometry"] = displaced_geometry(quick, ctx, corpus)
    progress("bench: beyond the paper")
    from .beyond import overhead
    result["beyond"] = overhead(quick, ctx)
    progress("bench: against Storm")
    from .peers import storm_peer
    result["peers"] = storm_peer(quick, corpus)
    progress("bench: triangulation")
    result["triangulation"] = triangulation(quick)
    progress("bench: floors")
    result["floors"] = floors(ctx, result["skin_baseline"][-1]["vertices"])
    result["targets"] = targets(result)
    return result


def run(args) -> int:
    from usdwrinkle.outputs.atomic import atomic_path

    if args.from_json:
        result = json.loads(Path(args.from_json).read_text())
        result["targets"] = targets(result)  # the words of this report's version
    else:
        corpus = Path(args.corpus) if args.corpus else default_corpus()
        result = run_bench(args.quick, corpus,
                           progress=lambda m: print(m, file=sys.stderr, flush=True),
                           before=args.before)
        result["command"] = "usdwrinkle bench" + (" --quick" if args.quick else "") + (
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


def main(argv=None) -> int:
    """``python -m benchmarks``: the bench command's own parser."""
    from usdwrinkle.cli.main import main as usdwrinkle

    return usdwrinkle(["bench", *(sys.argv[1:] if argv is None else argv)])

