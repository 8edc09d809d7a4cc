"""Generated blocks inside hand-written docs: ``<!-- NAME:begin -->`` ... ``<!-- NAME:end -->``
(benchmarks.lengths and benchmarks.stability write theirs into docs/method.md)."""
from __future__ import annotations

import re
from pathlib import Path


def markers(name: str) -> tuple[str, str]:
    return f"<!-- {name}:begin -->", f"<!-- {name}:end -->"


def emit(args: list[str], name: str, text: str) -> None:
    """``--write PATH``: replace the block ``name`` of PATH with ``text`` (which holds the
    markers); otherwise print ``text``."""
    if args[:1] != ["--write"]:
        print(text)
        return
    path = Path(args[1])
    begin, end = markers(name)
    doc = path.read_text()
    pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
    if not pattern.search(doc):
        raise SystemExit(f"{path} has no {begin} ... {end} block")
    path.write_text(pattern.sub(lambda _: text, doc))
    print(f"wrote {path}")
