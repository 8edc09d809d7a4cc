"""usdwrinkle.api: render and bake from Python run the commands' code, with their checks
(issue 27)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from usdwrinkle import api
from usdwrinkle.cli.main import main
from usdwrinkle.errors import UsdWrinkleError

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
    from usdwrinkle import api, log
    from usdwrinkle.errors import UsdWrinkleError

    assert api.UsdWrinkleError is UsdWrinkleError is usdwrinkle.UsdWrinkleError
    with log.collect() as messages:
        api.render(str(SHIRT), str(tmp_path / "f.####.png"), frames=[30], width=32)
    assert any("outside" in m for m in messages), messages
    assert "warning" not in capfd.readouterr().err
    # without a collector, the warning is usdwrinkle's one line on stderr
    api.render(str(SHIRT), str(tmp_path / "g.####.png"), frames=[30], width=32)
    assert "usdwrinkle: warning: " in capfd.readouterr().err
