"""The import graph of src/usdwrinkle, read from the source (nothing is imported).

    python tests/layering.py

prints each folder's (and top-level module's) imports of the others, the folder cycles
and the file circles (empty when the layers only look down), and what under render/
reaches pxr, and what in the package imports the checkout's benchmarks/ (nothing may: the
bench imports usdwrinkle, never the reverse). tests/test_layers.py enforces the rules.
Imports inside functions count: a lazy import is still a dependency. The package's own
__init__ (which registers the schema with USD) is left out: every module is reached
through it.
"""
from __future__ import annotations

import ast
import sys
from collections import defaultdict
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "usdwrinkle"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))
            if "__pycache__" not in p.parts}


def imports(known: dict[str, Path]) -> tuple[dict[str, set], set]:
    """({module: usdwrinkle modules it imports}, modules that import pxr themselves)."""
    graph: dict[str, set] = defaultdict(set)
    pxr = set()
    for name, path in known.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            targets = []
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")
                    base = base[:len(base) - node.level + 1]
                    stem = ".".join(base + ([node.module] if node.module else []))
                else:
                    stem = node.module or ""
                # "from . import x" and "from .pkg import mod" name modules too
                targets = [f"{stem}.{alias.name}" if f"{stem}.{alias.name}" in known else stem
                           for alias in node.names]
            for target in targets:
                if target == "pxr" or target.startswith("pxr."):
                    pxr.add(name)
                elif target in known and target != name:
                    graph[name].add(target)
                    # importing a.b.c runs a/__init__ and a/b/__init__ (not the root's)
                    parts = target.split(".")
                    for i in range(2, len(parts)):
                        parent = ".".join(parts[:i])
                        if parent in known and parent != name:
                            graph[name].add(parent)
    return graph, pxr


def importers(known: dict[str, Path], package: str) -> list[str]:
    """The modules that import ``package`` (absolute imports: it is outside the package)."""
    found = []
    for name, path in known.items():
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and not node.level:
                targets = [node.module or ""]
            else:
                continue
            if any(t == package or t.startswith(package + ".") for t in targets):
                found.append(name)
                break
    return found


def room(module: str) -> str:
    """The folder a module lives in (usdwrinkle.render.passes.skin -> render), or the
    top-level module itself (usdwrinkle.engine -> engine)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def room_graph(graph: dict[str, set]) -> dict[str, set]:
    rooms: dict[str, set] = defaultdict(set)
    for source, targets in graph.items():
        for target in targets:
            if room(source) != room(target):
                rooms[room(source)].add(room(target))
    return rooms


def cycles(graph: dict[str, set]) -> list[list[str]]:
    """The strongly connected components with more than one node (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []
    counter = [0]

    def visit(node):
        index[node] = low[node] = counter[0]
        counter[0] += 1
        stack.append(node)
        on_stack.add(node)
        for target in graph.get(node, ()):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10000)
    for node in sorted(set(graph) | {t for ts in graph.values() for t in ts}):
        if node not in index:
            visit(node)
    return sorted(found)


def reaches(graph: dict[str, set], start: str, targets: set) -> list[str]:
    """A path of imports from ``start`` to any module in ``targets`` ([] if none)."""
    seen, queue = {start: None}, [start]
    while queue:
        node = queue.pop(0)
        if node in targets:
            path = [node]
            while seen[path[-1]] is not None:
                path.append(seen[path[-1]])
            return path[::-1]
        for target in sorted(graph.get(node, ())):
            if target not in seen and target != "usdwrinkle":
                seen[target] = node
                queue.append(target)
    return []


def main() -> int:
    known = modules()
    graph, pxr = imports(known)
    graph.pop("usdwrinkle", None)
    rooms = room_graph(graph)
    print("imports between folders and top-level modules:")
    for name in sorted(rooms):
        print(f"  {name} -> {', '.join(sorted(rooms[name]))}")
    folder_cycles = cycles(rooms)
    file_circles = cycles(graph)
    print("folder cycles:", folder_cycles or "none")
    print("file circles:", file_circles or "none")
    render_pxr = {m: reaches(graph, m, pxr) for m in known if room(m) == "render"}
    render_pxr = {m: p for m, p in render_pxr.items() if p}
    print("render/ modules that reach pxr:", render_pxr or "none")
    bench = importers(known, "benchmarks")
    print("package modules that import benchmarks/:", bench or "none")
    return 1 if folder_cycles or file_circles or render_pxr or bench else 0


if __name__ == "__main__":
    sys.exit(main())
