"""Generated blocks inside hand-written docs: ``<!-- NAME:begin -->`` ... ``<!-- NAME:end -->``
(benchmarks.lengths and benchmarks.stability write theirs into docs/method.md)."""
from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from pathlib import Path


def markers(name: str) -> tuple[str, str]:
    return f"<!-- {name}:begin -->", f"<!-- {name}:end -->"


def stage_block_head(name: str, seconds: float) -> list[str]:
    """The first lines of the docs/physics.md block of ``python -m
    benchmarks.physics.NAME``: its begin marker and the command that made it."""
    return [markers(name)[0], "", f"Made by `python -m benchmarks.physics.{name} --write "
            f"docs/physics.md` ({seconds:.0f} s here).", ""]


def add_write_option(parser, name: str, doc: str) -> None:
    """The ``--write PATH`` option of a block's command (``args.write``, a Path or None)."""
    parser.add_argument("--write", type=Path, default=None, metavar="PATH",
                        help=f"replace the {name} block of PATH ({doc})")


def emit(write: str | Path | None, name: str, text: str) -> None:
    """``write``: replace the block ``name`` of that file with ``text`` (which holds the
    markers); None: print ``text``."""
    if write is None:
        print(text)
        return
    path = Path(write)
    begin, end = markers(name)
    doc = path.read_text()
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    if not pattern.search(doc):
        raise SystemExit(f"{path} has no {begin} ... {end} block")
    path.write_text(pattern.sub(lambda _: text, doc))
    print(f"wrote {path}")


def stage_block_main(argv, name: str, stages: Sequence[str],
                     measure: Callable[[str, object], list[dict]],
                     report: Callable[[list[dict], float], str]) -> int:
    """The command of a block measured per sample stage (``python -m
    benchmarks.physics.NAME [--write docs/physics.md] [--only STAGE ...]``):
    ``measure(stage, ctx)`` gives its rows on one GL context, ``report(rows, seconds)``
    the block."""
    import argparse
    import time

    import moderngl

    parser = argparse.ArgumentParser(prog=f"python -m benchmarks.physics.{name}")
    add_write_option(parser, name, "docs/physics.md")
    parser.add_argument("--only", nargs="*", default=None)
    args = parser.parse_args(argv)
    started = time.perf_counter()
    ctx = moderngl.create_standalone_context(backend="egl", require=430)
    rows = [row for stage in args.only or stages for row in measure(stage, ctx)]
    emit(args.write, name,
         report(rows, time.perf_counter() - started))
    return 0
