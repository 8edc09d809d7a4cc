"""The layers only look down (issue 25): no folder cycle and no file circle in
src/usdwrinkle, render/ reaches no pxr, and outputs/ does not import render/. The import
graph is read from the source by tests/layering.py (``python tests/layering.py`` prints
it), lazy imports inside functions included."""
from __future__ import annotations

import subprocess
import sys

import layering


def graph():
    known = layering.modules()
    edges, pxr = layering.imports(known)
    edges.pop("usdwrinkle", None)
    return known, edges, pxr


def test_no_folder_cycle_and_no_file_circle():
    _, edges, _ = graph()
    assert layering.cycles(layering.room_graph(edges)) == []
    assert layering.cycles(edges) == []


def test_render_reaches_no_pxr():
    known, edges, pxr = graph()
    for module in known:
        if layering.room(module) == "render":
            assert layering.reaches(edges, module, pxr) == [], module


def test_outputs_does_not_import_render():
    known, edges, _ = graph()
    for module in known:
        if layering.room(module) == "outputs":
            assert not [t for t in edges.get(module, ()) if layering.room(t) == "render"], module


def test_the_graph_is_read_right():
    """The reader finds what is there: a module of render/ imports scene.records, and
    scene.stage imports pxr (so an empty result above is not a blind reader)."""
    known, edges, pxr = graph()
    assert "usdwrinkle.scene.records" in edges["usdwrinkle.render.resources"]
    assert "usdwrinkle.scene.stage" in pxr
    assert layering.reaches(edges, "usdwrinkle.engine", pxr)
    assert layering.cycles({"a": {"b"}, "b": {"a"}, "c": {"a"}}) == [["a", "b"]]


def test_the_command_says_so():
    result = subprocess.run([sys.executable, str(layering.Path(layering.__file__))],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stdout
    assert "folder cycles: none" in result.stdout and "file circles: none" in result.stdout
