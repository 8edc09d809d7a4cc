"""usdwrinkle.api: render and bake from Python run the commands' code, with their checks
(issue 27)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle import api
from usdwrinkle.cli.main import main
from usdwrinkle.process.errors import UsdWrinkleError

SHIRT = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")


def pixels(path) -> np.ndarray:
    return oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8)


def test_render_equals_the_command_and_returns_its_frames(gl_context, tmp_path):
    written = api.render(SHIRT, tmp_path / "api" / "s.####.png", frames=[23, 24], width=96)
    assert [Path(p).name for p in written] == ["s.0023.png", "s.0024.png"]
    assert main(["render", SHIRT, str(tmp_path / "cli" / "s.####.png"), "--frames", "23:24",
                 "--width", "96", "--quiet"]) == 0
    for name in ("s.0023.png", "s.0024.png"):
        np.testing.assert_array_equal(pixels(tmp_path / "api" / name),
                                      pixels(tmp_path / "cli" / name))


def test_render_aovs_as_a_list_or_a_text(gl_context, tmp_path):
    a = api.render(SHIRT, tmp_path / "a.####.exr", frames=[24], width=64,
                   aovs=["normal", "color"])
    b = api.render(SHIRT, tmp_path / "b.####.exr", frames=[24], width=64, aovs="color,normal")
    for path in a + b:
        assert oiio.ImageInput.open(path).spec().channelnames == \
            ("R", "G", "B", "A", "N.X", "N.Y", "N.Z")
    np.testing.assert_array_equal(oiio.ImageBuf(a[0]).get_pixels(),
                                  oiio.ImageBuf(b[0]).get_pixels())


def test_bake_writes_the_layer_with_its_options(gl_context, tmp_path):
    from pxr import Sdf

    layer = api.bake(SHIRT, tmp_path / "shirt.usda", frames="24", maps=["normal"],
                     map_size=64, map_layout="asset", with_points=True)
    data = Sdf.Layer.FindOrOpen(layer).customLayerData["usdwrinkle"]
    assert data["withPoints"] and data["maps"]["size"] == 64
    assert data["maps"]["uv"] == "st" and data["maps"]["islands"] == ""
    assert (tmp_path / "shirt_maps" / "Sleeve.normal.0024.png").is_file()


def test_mistakes_are_the_commands_errors(tmp_path):
    with pytest.raises(TypeError, match="unexpected keyword argument 'widht'"):
        api.render(SHIRT, tmp_path / "s.png", widht=3)
    with pytest.raises(UsdWrinkleError, match="`width` and `height` must be positive"):
        api.render(SHIRT, tmp_path / "s.####.png", width=-3)
    with pytest.raises(UsdWrinkleError, match="does not exist"):
        api.bake(tmp_path / "missing.usda", tmp_path / "out.usda")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("call,options,message", [
    ("render", {"width": "wide"}, "`width`='wide' must be an integer"),
    ("render", {"width": 3.5}, "`width`=3.5 must be an integer"),
    ("render", {"exr_compression": "bogus"}, "`exr_compression`='bogus' is not one of zip"),
    ("render", {"frames": []}, "`frames` is empty"),
    ("render", {"aovs": ["color", "N"]}, "`aovs` takes a comma-separated list of color"),
    ("render", {"aovs": "normal"}, "`aovs` normal: a .png frame stores the colour alone"),
    ("bake", {"maps": "normal", "tangent_space": "MikkTSpace"},
     "`tangent_space`='MikkTSpace' is not one of triangle, mikktspace"),
    ("bake", {"display_color": "red"}, "`display_color`='red' is not one of amplitude"),
    ("bake", {"maps": "normal", "map_format": "jpg"}, "`map_format`='jpg' is not one of png"),
    ("bake", {"maps": "normal", "map_layout": "x"}, "`map_layout`='x' is not one of islands"),
])
def test_the_api_refuses_what_the_command_refuses(tmp_path, call, options, message):
    """Issue 42, finding 5: these gave per-triangle maps, the whole shot, a raw TypeError
    or a KeyError; each is now the command line's kind of one-line error, before any
    output exists."""
    output = tmp_path / ("x.####.png" if call == "render" else "x.usda")
    with pytest.raises(UsdWrinkleError, match=message.replace("(", r"\(")):
        getattr(api, call)(SHIRT, output, **options)
    assert not any(tmp_path.iterdir())


def test_the_api_warns_through_the_library_logger(gl_context, tmp_path, capfd):
    """Issue 44: with log.collect() around api.render, the messages stayed empty and the
    warning went to stderr (the API pushed the command line's reporter); and
    UsdWrinkleError could not be imported from usdwrinkle or usdwrinkle.api."""
    import usdwrinkle
    from usdwrinkle import api
    from usdwrinkle.process import log
    from usdwrinkle.process.errors import UsdWrinkleError

    assert api.UsdWrinkleError is UsdWrinkleError is usdwrinkle.UsdWrinkleError
    with log.collect() as messages:
        api.render(str(SHIRT), str(tmp_path / "f.####.png"), frames=[30], width=32)
    assert any("outside" in m for m in messages), messages
    assert "warning" not in capfd.readouterr().err
    # without a collector, the warning is usdwrinkle's one line on stderr
    api.render(str(SHIRT), str(tmp_path / "g.####.png"), frames=[30], width=32)
    assert "usdwrinkle: warning: " in capfd.readouterr().err


@pytest.mark.parametrize("options,message", [
    ({"frames": b"1:2"}, "`frames`=b'1:2' must be a FrameSpec text or a list of numbers"),
    ({"frames": [True]}, "`frames`=[True] must be a FrameSpec text or a list of numbers"),
    ({"frames": ["1"]}, "`frames`=['1'] must be a FrameSpec text or a list of numbers"),
    ({"workers": True}, "`workers`=True must be an integer"),
    ({"workers": "2"}, "`workers`='2' must be an integer"),
    ({"chunk": "5"}, "`chunk`='5' must be an integer"),
    ({"dask": 5}, "`dask`=5 must be 'local' or a scheduler's address"),
    ({"stage": b"shirt.usda"}, "`stage`=b'shirt.usda' must be a file path or a Usd.Stage"),
    ({"stage": 5}, "`stage`=5 must be a file path or a Usd.Stage"),
    ({"mask": 5}, "`mask`=5 must be a list"),
    ({"sublayer": 5}, "`sublayer`=5 must be a list"),
    ({"sublayer": [5]}, "`sublayer`=5 must be a string"),
    ({"width": True}, "`width`=True must be an integer"),
    ({"sublayer": "over.usda"}, "sublayer 'over.usda' does not exist"),
    ({"sublayer": Path("over.usda")}, "sublayer 'over.usda' does not exist"),
    ({"variant": "/World{look=red}"}, "/World has no variant set 'look'"),
])
def test_api_inputs_are_refused_naming_the_field(tmp_path, monkeypatch, options, message):
    """Issue 54, findings 7 and 18: bytes were iterated as frame numbers (b"1:2" rendered
    frames 49, 58 and 50), a bool was a frame or a worker count, and the others raised
    AttributeError or TypeError; a single text where a list is expected was split into
    characters. Each is a UsdWrinkleError naming the field, before any output exists."""
    monkeypatch.chdir(tmp_path)
    arguments = {"stage": SHIRT, "output": tmp_path / "x.####.png", "frames": "1",
                 "width": 16, **options}
    with pytest.raises(UsdWrinkleError, match=message.replace("(", r"\(").replace(
            "[", r"\[").replace("{", r"\{")):
        api.render(**arguments)
    assert not any(p.suffix == ".png" for p in tmp_path.iterdir())


def test_jobs_refuse_bytes_frames_when_made():
    from usdwrinkle.api import RenderJob, Shot

    with pytest.raises(UsdWrinkleError, match="`frames`=b'1' must be a FrameSpec"):
        RenderJob(Shot(SHIRT), "x.png", b"1")


def test_numpy_numbers_and_empty_lists_are_taken(gl_context, tmp_path):
    """width=np.int64(32) was refused as 'not an integer'; sublayer=None is no layer."""
    out = api.render(SHIRT, tmp_path / "x.png", frames=np.array([24.0]), width=np.int64(32),
                     sublayer=None, variant=None, mask=None, samples=np.int32(1))
    assert out == [str(tmp_path / "x.png")]
    assert oiio.ImageBuf(out[0]).spec().width == 32


def test_api_warnings_carry_the_prefix_in_a_fresh_process(tmp_path):
    """Issue 54, finding 19: without the CLI, the library logger had no handler, so Python's
    last-resort handler printed warnings bare. ``import usdwrinkle`` installs it; and
    use_default_handler(False) leaves the records to the host's logging."""
    import subprocess
    import sys

    script = (
        "import logging, sys\n"
        "from usdwrinkle import api, log\n"
        f"api.render({str(SHIRT)!r}, {str(tmp_path / 'a.png')!r}, frames=[30], width=16)\n"
        "log.use_default_handler(False)\n"
        "logging.basicConfig(format='HOST %(name)s %(message)s', stream=sys.stderr)\n"
        f"api.render({str(SHIRT)!r}, {str(tmp_path / 'b.png')!r}, frames=[30], width=16)\n")
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stderr.splitlines() if "outside" in line]
    assert len(lines) == 2, result.stderr
    assert lines[0].startswith("usdwrinkle: warning: 1 of the 1 frame(s) lie outside")
    assert lines[1].startswith("HOST usdwrinkle.app.render 1 of the 1 frame(s)")


def _fine_points(layer: str) -> np.ndarray:
    from pxr import Usd, UsdGeom

    stage = Usd.Stage.Open(layer)
    fine = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Arm/Sleeve_wrinkled"))
    return np.asarray(fine.GetPointsAttr().Get(24), np.float64)


def test_another_context_made_current_changes_nothing(gl_context, tmp_path):
    """GL calls go to the thread's current context. A script that made a second context
    current (its own moderngl work, an engine on a context of its own) got a geometry bake
    whose every fine point was (0, 0, 0), silently. Every door and engine call now makes
    usdwrinkle's context current for its work (render/context.current) and gives the
    thread its context back after: the frames, the fields and the baked points are the
    same, and the script's context still draws into its own framebuffer."""
    import ctypes

    import moderngl

    from usdwrinkle.engine import WrinkleEngine

    egl = ctypes.CDLL("libEGL.so.1")
    egl.eglGetCurrentContext.restype = ctypes.c_void_p

    def everything(tag):
        frame = api.render(SHIRT, tmp_path / tag / "s.####.png", frames=[24], width=96)[0]
        layer = api.bake(SHIRT, tmp_path / tag / "geo.usdc", frames=[24], geometry=True,
                         levels=2)
        engine = WrinkleEngine(SHIRT)
        try:
            engine.compute_frame(24)
            amplitude = engine.read_fields("/World/Arm/Sleeve").amplitude.copy()
        finally:
            engine.release()
        return pixels(frame), _fine_points(layer), amplitude

    ours = egl.eglGetCurrentContext()
    before = everything("before")
    assert np.ptp(before[1], axis=0).min() > 0.1 and before[2].max() > 0
    host = moderngl.create_standalone_context(backend="egl", require=430)
    try:
        mine = egl.eglGetCurrentContext()
        assert mine and mine != ours
        fbo = host.simple_framebuffer((4, 4))
        after = everything("after")
        assert egl.eglGetCurrentContext() == mine  # the script's context is current again
        fbo.use()
        host.clear(0.25, 0.5, 0.75, 1.0)
        np.testing.assert_array_equal(np.frombuffer(fbo.read(components=4), np.uint8)[:4],
                                      [64, 128, 191, 255])
    finally:
        host.release()
        from usdwrinkle.render.context import current

        with current(gl_context):  # none current now: ours is made current and stays
            pass
    assert egl.eglGetCurrentContext() == ours
    np.testing.assert_array_equal(after[0], before[0])
    np.testing.assert_array_equal(after[1], before[1])
    np.testing.assert_array_equal(after[2], before[2])
