"""The usdview plugin's commands, driven by a stand-in for usdviewApi (usd-core has no
Usdviewq)."""
from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Usd, UsdGeom

from usdwrinkle import usdview

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


def stand_in(stage, frame, selected=(), camera=None):
    status = []
    api = SimpleNamespace(stage=stage, frame=Usd.TimeCode(frame), selectedPrims=list(selected),
                          prim=selected[0] if selected else None, cameraPrim=camera,
                          PrintStatus=status.append)
    return api, status


def test_bake_current_frame_writes_the_session_layer(gl_context):
    stage = Usd.Stage.Open(str(SAMPLES / "zeppelin.usda"))
    api, status = stand_in(stage, 12)
    baked = usdview.bake_current_frame(api, ctx=gl_context)
    assert baked == ["/World/Zeppelin/Hull"]
    session = stage.GetSessionLayer()
    assert session.GetPrimAtPath("/World/Zeppelin/Hull")
    assert not stage.GetRootLayer().dirty  # nothing went into the asset
    hull = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Zeppelin/Hull"))
    amplitude = np.asarray(hull.GetPrimvar("wrinkle:amplitude").Get(12))
    colors = np.asarray(hull.GetPrimvar("displayColor").Get(12))
    assert amplitude.shape == (506,) and amplitude.max() > 0
    assert colors.shape == (506, 3)
    # more amplitude, lighter (viridis runs dark to bright)
    order = np.argsort(amplitude)
    assert colors[order[-1]].sum() > colors[order[0]].sum()
    assert "baked 1 mesh(es) at frame 12" in status[-1]


def test_bake_uses_the_selection(gl_context):
    stage = Usd.Stage.Open(str(SAMPLES / "curtain.usda"))
    cloth = stage.GetPrimAtPath("/World/Curtain")
    api, _ = stand_in(stage, 5, selected=[cloth])
    assert usdview.bake_current_frame(api, ctx=gl_context) == ["/World/Curtain/Cloth"]


def test_bake_says_when_nothing_is_wrinkled(gl_context, corpus):
    stage = Usd.Stage.Open(str(corpus / "openusd-usdskel" / "lbs.usda"))
    api, status = stand_in(stage, 3)
    assert usdview.bake_current_frame(api, ctx=gl_context) == []
    assert "no mesh" in status[-1]


def test_render_current_frame_writes_and_opens(gl_context, tmp_path):
    stage = Usd.Stage.Open(str(SAMPLES / "shirt.usda"))
    camera = stage.GetPrimAtPath("/World/main_cam")
    api, status = stand_in(stage, 24, camera=camera)
    opened = []
    paths = usdview.render_current_frame(api, outdir=str(tmp_path), opener=opened.append,
                                         width=160, ctx=gl_context)
    assert [Path(p).suffix for p in paths] == [".exr", ".png"]
    assert opened == [paths[1]]
    spec = oiio.ImageInput.open(paths[0]).spec()
    assert (spec.width, spec.height) == (160, 106)  # 160 / 1.5, rounded down as usdrecord
    assert "wrinkle.height" in spec.channelnames
    assert "rendered" in status[-1]


def test_render_current_frame_starts_one_engine_for_both_files(gl_context, tmp_path,
                                                               monkeypatch):
    """Issue 58: usdview rendered the frame twice, each time with its own engine and
    phase-history preroll; the EXR and the PNG now share one engine, and the PNG is still
    the frame `render` writes alone."""
    from usdwrinkle import api
    from usdwrinkle.app.shot import Shot

    started = []
    start_engine = Shot.start_engine

    def counted(self, *args, **kwargs):
        started.append(args)
        return start_engine(self, *args, **kwargs)

    monkeypatch.setattr(Shot, "start_engine", counted)
    stage = Usd.Stage.Open(str(SAMPLES / "shirt.usda"))
    viewer, _ = stand_in(stage, 24, camera=stage.GetPrimAtPath("/World/main_cam"))
    paths = usdview.render_current_frame(viewer, outdir=str(tmp_path / "viewer"),
                                         opener=lambda path: None, width=160, ctx=gl_context)
    assert len(paths) == 2 and len(started) == 1
    alone = api.render(SAMPLES / "shirt.usda", tmp_path / "alone.png", frames=[24], width=160,
                       camera="/World/main_cam")
    assert Path(paths[1]).read_bytes() == Path(alone[0]).read_bytes()


def test_plugin_registers_a_wrinkles_menu():
    commands, menus = [], {}

    class Registry:
        def registerCommandPlugin(self, name, display, callback):  # noqa: N802
            commands.append((name, display, callback))
            return name

    class Menu:
        def __init__(self):
            self.items = []

        def addItem(self, item):  # noqa: N802
            self.items.append(item)

    class Builder:
        def findOrCreateMenu(self, name):  # noqa: N802
            return menus.setdefault(name, Menu())

    container = usdview.WrinklePluginContainer()
    container.registerPlugins(Registry(), None)
    container.configureView(Registry(), Builder())
    assert [c[1] for c in commands] == ["Bake current frame", "Render current frame",
                                        "Paint...", "Live (on/off)"]
    assert commands[0][2] is usdview.bake_current_frame
    assert commands[2][2] is usdview.paint_current_stage
    assert commands[3][2] is usdview.toggle_live
    assert menus["Wrinkles"].items == ["Wrinkles.BakeCurrentFrame", "Wrinkles.RenderCurrentFrame",
                                       "Wrinkles.Paint", "Wrinkles.Live"]


def test_plug_info_names_the_container():
    info = json.loads((Path(usdview.plugin_dir()) / "plugInfo.json").read_text())
    plugin = info["Plugins"][0]
    assert plugin["Type"] == "python" and plugin["Name"] == "usdwrinkle.usdview"
    types = plugin["Info"]["Types"]
    assert "usdwrinkle.usdview.WrinklePluginContainer" in types
    assert types["usdwrinkle.usdview.WrinklePluginContainer"]["bases"] == [
        "pxr.Usdviewq.plugin.PluginContainer"]


PLAIN_SCRIPT = r"""
import json, sys
from types import SimpleNamespace
from pxr import Usd
import usdwrinkle.usdview as plugin

stage = Usd.Stage.Open(sys.argv[1])
status = []
api = SimpleNamespace(stage=stage, frame=Usd.TimeCode(12), selectedPrims=[], prim=None,
                      cameraPrim=None, PrintStatus=status.append)
baked = plugin.bake_current_frame(api)
amplitude = stage.GetPrimAtPath("/World/Zeppelin/Hull").GetAttribute(
    "primvars:wrinkle:amplitude").Get(12)
opened = []
paths = plugin.render_current_frame(api, outdir=sys.argv[2], opener=opened.append, width=96)
session = stage.GetSessionLayer()
before = session.ExportToString()
plugin.toggle_live(api)
api.frame = Usd.TimeCode(6)
plugin.live_tick(api, wait=False)
live = plugin._LIVE["bake"]
hull = stage.GetPrimAtPath("/World/Zeppelin/Hull")
live_state = {"frame": live.frame, "baked": live.baked,
              "first_sublayer_is_live": session.subLayerPaths[0] == live.current,
              "amplitude6": len(hull.GetAttribute("primvars:wrinkle:amplitude").Get(6) or [])}
plugin.toggle_live(api)
live_state["restored"] = session.ExportToString() == before
print(json.dumps({"baked": baked, "amplitude": len(amplitude or []), "paths": paths,
                  "opened": opened, "status": status, "live": live_state,
                  "numpy": "numpy" in sys.modules}))
"""


@pytest.mark.slow
def test_the_plugin_works_from_a_python_with_only_pxr(tmp_path):
    """Issue 27: from usdview's own Python (pxr and nothing else: no numpy, moderngl or
    OpenImageIO) with only the paths usdwrinkle info prints, both commands failed with
    ModuleNotFoundError. They now run usdwrinkle in USDWRINKLE_PYTHON (which info prints)
    on the stage as usdview holds it, and bring the bake back as a session sublayer (and
    Live, issue 56, runs there too)."""
    import os
    import subprocess
    import sys

    plain = tmp_path / "plain"
    subprocess.run([sys.executable, "-m", "venv", str(plain)], check=True, timeout=300)
    python = plain / "bin" / "python"
    install = subprocess.run([str(python), "-m", "pip", "install", "-q", "usd-core"],
                             capture_output=True, text=True, timeout=600)
    if install.returncode != 0:
        pytest.skip(f"cannot install usd-core into a fresh venv here: "
                    f"{install.stderr.strip().splitlines()[-1:]}")
    info = subprocess.run([sys.executable, "-m", "usdwrinkle", "info", "--no-gl"],
                          capture_output=True, text=True, timeout=120).stdout
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    for line in info.splitlines():
        if line.strip().startswith("export "):
            name, _, value = line.strip()[len("export "):].partition("=")
            env[name] = value
    assert set(env) >= {"PXR_PLUGINPATH_NAME", "PYTHONPATH", "USDWRINKLE_PYTHON"}
    (tmp_path / "out").mkdir()
    done = subprocess.run([str(python), "-c", PLAIN_SCRIPT, str(SAMPLES / "zeppelin.usda"),
                           str(tmp_path / "out")], capture_output=True, text=True,
                          timeout=600, env=env)
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert not result["numpy"]  # truly a Python without usdwrinkle's dependencies
    assert result["baked"] == ["/World/Zeppelin/Hull"] and result["amplitude"] == 506, result
    assert [Path(p).suffix for p in result["paths"]] == [".exr", ".png"], result
    assert result["opened"] == [result["paths"][1]]
    image = oiio.ImageBuf(result["paths"][1]).get_pixels(oiio.UINT8)
    assert image.shape[1] == 96 and image[..., 3].max() == 255
    # Wrinkles > Live, out of process too (issue 56): frames 12 and 6 baked by usdwrinkle
    # bake in USDWRINKLE_PYTHON, shown through the session layer, which Live off restores
    assert result["live"] == {"frame": 6.0, "baked": 2, "first_sublayer_is_live": True,
                              "amplitude6": 506, "restored": True}, result["live"]


def _baked_values(layer_path, frame):
    """{attribute path: value at ``frame``} of every time-sampled attribute a bake layer
    authors, asset paths resolved (a map's pixels in place of its file name)."""
    from pxr import Sdf

    layer = Sdf.Layer.FindOrOpen(str(layer_path))
    values = {}

    def visit(path):
        if not path.IsPropertyPath():
            return
        spec = layer.GetAttributeAtPath(path)
        if spec is None or not layer.ListTimeSamplesForPath(path):
            return
        value = layer.QueryTimeSample(path, frame)
        if isinstance(value, Sdf.AssetPath):
            file = layer.ComputeAbsolutePath(value.path)
            value = oiio.ImageBuf(file).get_pixels(oiio.FLOAT)
        values[str(path)] = np.asarray(value)

    layer.Traverse(Sdf.Path.absoluteRootPath, visit)
    return values


def _shown_values(stage, names, frame):
    """The same attributes as the stage composes them at ``frame``."""
    from pxr import Sdf

    values = {}
    for name in names:
        attribute = stage.GetAttributeAtPath(Sdf.Path(name))
        value = attribute.Get(frame)
        if isinstance(value, Sdf.AssetPath):
            value = oiio.ImageBuf(value.resolvedPath).get_pixels(oiio.FLOAT)
        values[name] = np.asarray(value)
    return values


def test_live_shows_each_frames_bake_and_leaves_the_session_as_it_was(gl_context, tmp_path):
    """Issue 56: Wrinkles > Live, scrubbing 1 -> 24 -> 12: at each frame the stage shows,
    through its session layer, the primvars and maps (normal and parallax, with the
    MaterialX network) of ``usdwrinkle bake --frames F --sparse --maps normal,parallax
    --map-size 1024``; back at 24 the kept bake is swapped in without baking; turning Live
    off leaves the session layer as it was and deletes Live's files."""
    import os

    from usdwrinkle.cli.main import main

    stage = Usd.Stage.Open(str(SAMPLES / "shirt.usda"))
    session = stage.GetSessionLayer()
    before = session.ExportToString()
    api, status = stand_in(stage, 1)
    assert usdview.toggle_live(api, ctx=gl_context) is True
    live = usdview._LIVE["bake"]
    try:
        for frame in (1, 24, 12):
            if frame != 1:
                api.frame = Usd.TimeCode(frame)
                usdview.live_tick(api)  # the frame has not held for one look yet
                assert live.frame != frame
                usdview.live_tick(api)
            assert live.frame == frame and session.subLayerPaths[0] == live.current
            reference = tmp_path / f"bake{frame}.usda"
            assert main(["bake", str(SAMPLES / "shirt.usda"), str(reference), "--quiet",
                         "--frames", str(frame), "--sparse", "--maps", "normal,parallax",
                         "--map-size", "1024"]) == 0
            expected = _baked_values(reference, frame)
            assert any("Parallax" in name for name in expected)
            assert any("wrinkle:amplitude" in name for name in expected)
            shown = _shown_values(stage, expected, frame)
            for name, value in expected.items():
                np.testing.assert_array_equal(shown[name], value, err_msg=name)
            assert f"Live at frame {frame} (baked" in status[-1]
        api.frame = Usd.TimeCode(24)
        usdview.live_tick(api, wait=False)
        assert live.baked == 3 and "Live at frame 24 (kept)" in status[-1]
    finally:
        folder = live.folder
        assert usdview.toggle_live(api) is False
    assert session.ExportToString() == before
    assert not os.path.exists(folder) and not usdview._LIVE


def test_live_bakes_again_after_an_edit(gl_context):
    """A kept bake shows the stage as it was when it was baked: an edit (here a width in
    the session layer, as the paint window writes strokes) forgets them all, so that the
    next frame shown is baked from the edited stage."""
    stage = Usd.Stage.Open(str(SAMPLES / "zeppelin.usda"))
    api, status = stand_in(stage, 12)
    usdview.toggle_live(api, ctx=gl_context)
    live = usdview._LIVE["bake"]
    try:
        api.frame = Usd.TimeCode(6)
        usdview.live_tick(api, wait=False)
        assert live.baked == 2 and len(live.cache) == 2
        hull = stage.GetPrimAtPath("/World/Zeppelin/Hull")
        amplitude = np.asarray(hull.GetAttribute("primvars:wrinkle:amplitude").Get(6))
        with Usd.EditContext(stage, stage.GetSessionLayer()):
            hull.GetAttribute("primvars:wrinkle:width").Set([0.6])
        assert live.cache == {}
        # the layer still shown is not part of the stage the next bake reads
        assert live.current in stage.GetSessionLayer().subLayerPaths
        assert live.current not in live.source_stage().GetSessionLayer().subLayerPaths
        api.frame = Usd.TimeCode(12)
        usdview.live_tick(api, wait=False)
        api.frame = Usd.TimeCode(6)
        usdview.live_tick(api, wait=False)
        assert live.baked == 4 and "(baked" in status[-1]
        edited = np.asarray(hull.GetAttribute("primvars:wrinkle:amplitude").Get(6))
        assert not np.array_equal(edited, amplitude)
    finally:
        usdview.toggle_live(api)


def test_live_out_of_process_asks_for_what_live_bakes_in_process():
    """Live's bake out of process (usdwrinkle bake with usdview.LIVE_FLAGS) is the one it
    runs in process (app/live.LIVE_OPTIONS): the command line reads the flags back into
    the same options."""
    from usdwrinkle.app.live import LIVE_OPTIONS
    from usdwrinkle.cli.main import build_parser

    args = build_parser().parse_args(["bake", "in.usda", "out.usda", *usdview.LIVE_FLAGS])
    assert args.sparse is True and LIVE_OPTIONS["sparse"] is True
    assert tuple(args.maps.split(",")) == LIVE_OPTIONS["maps"]
    assert args.map_size == LIVE_OPTIONS["map_size"]
