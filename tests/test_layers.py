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


def test_the_package_does_not_import_the_benchmarks():
    """cli/bench.py used to put the checkout on sys.path and import benchmarks/, which
    imported cli.main back (a circle across the package's edge)."""
    known, _, _ = graph()
    assert layering.importers(known, "benchmarks") == []
    assert layering.importers(known, "pxr")  # the reader sees absolute imports


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
    assert "import benchmarks/: none" in result.stdout


def _parameters(function) -> list[str]:
    import inspect

    return [name for name in inspect.signature(function).parameters if name != "self"]


def test_every_bake_sink_has_the_one_protocol_and_few_parameters():
    """The primvars, the maps and the geometry are written through one protocol
    (outputs/sink.py: begin, add_frame, finish, commit, release), and neither the sinks,
    their writers nor frameloop.bake_layer take more than 5 parameters. No sink is handed the
    engine: a frame arrives as (frame, fields, resources)."""
    from usdwrinkle.frameloop import bake_layer
    from usdwrinkle.geometry.bake import GeometryBake
    from usdwrinkle.geometry.layer import FineMeshWriter
    from usdwrinkle.maps.bake import MapBake
    from usdwrinkle.maps.material import author_material
    from usdwrinkle.outputs.layers import LayerBaker, save_layer
    from usdwrinkle.outputs.sink import BakeSink

    protocol = ("begin", "add_frame", "finish", "commit", "release")
    for sink in (LayerBaker, MapBake, GeometryBake):
        for name in protocol:
            assert _parameters(getattr(sink, name)) == _parameters(getattr(BakeSink, name)), \
                (sink.__name__, name)
        assert _parameters(sink.__init__) == ["scene", "options"], sink.__name__
    for function in (FineMeshWriter.__init__, FineMeshWriter.define, FineMeshWriter.add_frame,
                     author_material, save_layer, bake_layer):
        assert len(_parameters(function)) <= 5, function.__qualname__


def test_test_modules_share_helpers_only_through_helpers_and_conftest():
    """Issue 25: test modules imported each other's helpers (test_cloth from test_bake
    and test_crush_relax, test_beyond and test_geometry from test_maps)."""
    import ast
    from pathlib import Path

    found = []
    for path in sorted(Path(__file__).parent.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            found += [f"{path.name}: {n}" for n in names if n.startswith("test_")]
    assert found == []


def test_no_bake_writer_reads_the_stage():
    """Issue 25: the writers (outputs/, maps/, geometry/) re-read the stage while they
    wrote (SkelRoots, default prim, bound materials, transforms, primvars). The scene
    now reads those facts once (scene/overrides.py) and the writers author from them:
    none imports the stage-reading modules of pxr (Usd, UsdShade, UsdSkel; UsdGeom for
    its tokens only) or the scene, and BakeScene hands them no stage."""
    import ast
    import dataclasses
    from pathlib import Path

    import usdwrinkle
    from usdwrinkle.outputs.sink import BakeScene

    package = Path(usdwrinkle.__file__).parent
    found = []
    for folder in ("outputs", "maps", "geometry"):
        for path in sorted((package / folder).glob("*.py")):
            where = f"{folder}/{path.name}"
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.ImportFrom) and node.module == "pxr":
                    found += [f"{where}: pxr.{a.name}" for a in node.names
                              if a.name in ("Usd", "UsdShade", "UsdSkel", "UsdLux")]
                if isinstance(node, ast.ImportFrom) and node.level and \
                        (node.module or "").split(".")[0] in ("scene", "engine", "frameloop"):
                    found += [f"{where}: ..{node.module}"]
                if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and \
                        node.value.id == "UsdGeom" and node.attr != "Tokens":
                    found.append(f"{where}: UsdGeom.{node.attr}")
                if isinstance(node, ast.Attribute) and node.attr == "stage":
                    found.append(f"{where}: .stage")
    assert found == []
    assert "stage" not in {f.name for f in dataclasses.fields(BakeScene)}


def test_a_baked_frame_value_is_set_in_one_place():
    """Issue 25: "set the default at the default time, else a time sample" was written
    in three writers. outputs.layers.set_value is the one place; the maps' material sets
    its file inputs' default and samples on purpose (readers that ignore time samples
    get the first frame's file), and is the only other caller of SetTimeSample."""
    import ast
    from pathlib import Path

    import usdwrinkle

    package = Path(usdwrinkle.__file__).parent
    callers = []
    for path in sorted(package.rglob("*.py")):
        tree = ast.parse(path.read_text(), str(path))
        for function in ast.walk(tree):
            if not isinstance(function, ast.FunctionDef):
                continue
            for node in ast.walk(function):
                if isinstance(node, ast.Attribute) and node.attr == "SetTimeSample":
                    callers.append(f"{path.relative_to(package).as_posix()}:{function.name}")
    assert sorted(callers) == ["maps/material.py:author_material", "outputs/layers.py:set_value"]


# --- issue 44: the doors stand on the application layer --------------------------------

#: the rooms every layer may use: the process (errors, logging, time codes, the package's
#: data) and the stage metadata a layer carries
FOUNDATION = {"process", "layerinfo", "usdwrinkle", "__main__"}
#: the doors: each maps what its user gives onto the application layer's jobs
DOORS = {"api", "cli", "usdview", "paint"}
#: what a door may still import below the application layer: nothing (issue 44); an entry
#: here would have to name exactly what a door reaches, so that the list stays true
NOT_YET: dict[str, set[str]] = {}


def test_the_doors_stand_on_the_application_layer():
    """Every door (the command line, the Python API, usdview's plugin and the paint
    window) imports the jobs (app/), authoring, the brush's numpy geometry (brush/) and
    the foundation, nothing below. The
    farm is not a door but where a RenderJob runs its frames on Dask (issue 58: the farm
    branch was written in two doors): it stands below the jobs, and no door imports it."""
    _, edges, _ = graph()
    rooms = layering.room_graph(edges)
    for door in sorted(DOORS):
        below = rooms.get(door, set()) - DOORS - FOUNDATION - {"app", "authoring", "brush"}
        assert below == NOT_YET.get(door, set()), (door, sorted(below))
    assert "app" in rooms["api"] and "app" in rooms["usdview"] and "app" in rooms["cli"]
    assert not {"api", "cli", "usdview"} & rooms.get("app", set())  # app looks down
    assert "farm" in rooms["app"] and "app" not in rooms["farm"]
    assert not [door for door in DOORS if "farm" in rooms.get(door, set())]


def test_the_api_and_the_application_layer_are_typed():
    """mypy --strict over usdwrinkle/api.py and app/ (pyproject.toml's [tool.mypy])."""
    import os

    result = subprocess.run([sys.executable, "-m", "mypy", "--cache-dir", os.devnull],
                            capture_output=True, text=True, timeout=600,
                            cwd=layering.PACKAGE.parents[1])
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Success: no issues found" in result.stdout


def _strings(path):
    """(line, text) of the string constants of a module that are not docstrings (an
    f-string's literal parts included)."""
    import ast

    tree = ast.parse(path.read_text(), str(path))
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef,
                             ast.AsyncFunctionDef)) and node.body and \
                isinstance(node.body[0], ast.Expr) and \
                isinstance(node.body[0].value, ast.Constant):
            docstrings.add(id(node.body[0].value))
    return [(node.lineno, node.value) for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str)
            and id(node) not in docstrings]


#: modules outside cli/ that run the command line itself (usdview's plugin, where
#: usdwrinkle's dependencies do not import in usdview's Python: a command line it runs)
RUNS_THE_COMMAND_LINE = {"usdwrinkle.usdview"}


def test_the_library_names_fields_not_flags():
    """Issue 44: a Python caller got advice about flags it never passed. Outside cli/, a
    message names an option field in backquotes (`map_size`), and the command line prints
    it as its flag (cli/flags.py). Docstrings may still say which command uses a
    function."""
    import re

    flag = re.compile(r"(?<![\w-])--[a-z]")
    found = []
    for module, path in layering.modules().items():
        if layering.room(module) == "cli" or module in RUNS_THE_COMMAND_LINE:
            continue
        found += [f"{module}:{line}: {text!r}" for line, text in _strings(path)
                  if flag.search(text)]
    assert found == []
    # the reader sees what it looks for
    assert any("--" in text for _, text in _strings(layering.PACKAGE / "cli" / "render.py"))


def test_no_time_is_nan():
    """Issue 44: the default time was NaN in 27 places (a comparison with NaN is silently
    false). A frame is now a float or None (timecode.Frame): nothing tests a time for
    NaN, and nothing makes a NaN frame."""
    import re

    time_names = r"(frame|frames\[\d\]|time|first|last|start|end|offset|other)"
    tested = re.compile(rf"isnan\(\s*{time_names}\b")
    made = re.compile(r"\[float\(\"nan\"\)\]|frame\w* = (math\.nan|float\(\"nan\"\))")
    found = [f"{module}:{number}: {line.strip()}"
             for module, path in layering.modules().items()
             for number, line in enumerate(path.read_text().splitlines(), 1)
             if tested.search(line) or made.search(line)]
    assert found == []
    assert tested.search("if math.isnan(frame):") and made.search('return [float("nan")]')


def test_the_blender_addon_stands_alone():
    """Issue 56: the Blender add-on runs in Blender's Python, where usdwrinkle and its
    dependencies are not installed: it imports Blender's bpy, the pxr Blender bundles and
    the standard library, nothing else; it is a legacy add-on file (bl_info, register,
    unregister) that Blender's Install from Disk takes."""
    import ast

    path = layering.PACKAGE / "blender" / "usdwrinkle_blender.py"
    tree = ast.parse(path.read_text(), str(path))
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, "a relative import"
            imported.add((node.module or "").split(".")[0])
    assert imported - sys.stdlib_module_names == {"bpy", "pxr"}
    names = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)} | \
        {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets
         if isinstance(t, ast.Name)}
    assert {"bl_info", "register", "unregister"} <= names
    _, edges, _ = graph()
    assert not [m for m, targets in edges.items() for t in targets
                if layering.room(t) == "blender"]  # and nothing imports it


def _trees():
    import ast

    for path in sorted(layering.PACKAGE.rglob("*.py")):
        relative = path.relative_to(layering.PACKAGE)
        room = relative.parts[0] if len(relative.parts) > 1 else relative.stem
        yield relative, room, ast.parse(path.read_text())


def _inside(node) -> bool:
    import ast

    return isinstance(node, ast.Name) and node.id in ("self", "cls")


def test_nothing_outside_the_engine_reaches_into_it():
    """Issue 58: the engine's scene delegate and render delegate are its own; every
    other module asks the engine (frame_range, is_posed, local_to_world, ...)."""
    import ast

    reached = [f"{relative}:{node.lineno} {ast.unparse(node)}"
               for relative, _, tree in _trees() if str(relative) != "engine.py"
               for node in ast.walk(tree)
               if isinstance(node, ast.Attribute) and node.attr in ("scene", "render_delegate")
               and not _inside(node.value)]
    assert reached == []


def test_no_room_calls_another_rooms_underscored_name():
    """Issue 58: an underscored name is its room's own. A module may use ``x._name`` or
    import ``_name`` only where ``_name`` is defined in its own room (a folder of
    src/usdwrinkle, or a root module)."""
    import ast

    trees = list(_trees())
    defined: dict[str, set] = {}
    for _, room, tree in trees:
        for node in ast.walk(tree):
            name = None
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                name = node.name
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                name = node.attr
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                name = node.id
            if name and name.startswith("_") and not name.startswith("__"):
                defined.setdefault(name, set()).add(room)
    foreign = []
    for relative, room, tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and not _inside(node.value):
                names = [node.attr]
            elif isinstance(node, ast.ImportFrom) and (node.level or (node.module or "")
                                                       .startswith("usdwrinkle")):
                names = [alias.name for alias in node.names]
            else:
                continue
            foreign += [f"{relative}:{node.lineno} {name} (of {sorted(defined[name])})"
                        for name in names if name.startswith("_")
                        and not name.startswith("__") and name in defined
                        and room not in defined[name]]
    assert foreign == []
    assert "_posed" in defined  # the scan reads definitions (app/paint_session.py's cache)
