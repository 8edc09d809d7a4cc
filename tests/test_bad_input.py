"""Every malformed or degenerate stage of tests/data/bad/ through render and bake."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Usd

from usdwrinkle.cli.main import main

BAD = Path(__file__).resolve().parent / "data" / "bad"
CASES = json.loads((BAD / "cases.json").read_text())


def test_the_corpus_is_complete():
    assert len(CASES) >= 25
    for name in CASES:
        assert (BAD / name).is_file(), name


def one_line_error(capsys):
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    errors = [line for line in err if line.startswith("usdwrinkle: error: ")]
    assert len(errors) == 1, err
    assert not any("Traceback" in line for line in err), err
    return errors[0], err


@pytest.mark.parametrize("name", sorted(CASES))
def test_render(gl_context, tmp_path, capsys, name):
    expected = CASES[name]
    code = main(["render", str(BAD / name), str(tmp_path / "f.####.exr"), "--width", "48",
                 "--quiet"])
    if expected["outcome"] == "error":
        assert code == 2
        line, _ = one_line_error(capsys)
        assert expected["fragment"] in line, line
        # no temporary file; frames finished before a per-frame error stay, whole
        assert not list(tmp_path.glob(".*"))
        for frame in tmp_path.glob("f.*.exr"):
            assert oiio.ImageBuf(str(frame)).get_pixels(oiio.FLOAT) is not None
        if "at frame" not in expected["fragment"]:
            assert not list(tmp_path.iterdir())
        return
    assert code == 0, capsys.readouterr().err
    err = capsys.readouterr().err
    if expected["warning"]:
        assert "usdwrinkle: warning: " in err and expected["warning"] in err, err
    frames = sorted(tmp_path.glob("f.*.exr"))
    assert len(frames) == 3
    for frame in frames:
        buf = oiio.ImageBuf(str(frame))
        spec = buf.spec()
        pixels = buf.get_pixels(oiio.FLOAT).reshape(spec.height, spec.width, spec.nchannels)
        z = list(spec.channelnames).index("Z")
        finite = np.isfinite(pixels)
        finite[..., z] = True  # Z is inf where nothing was hit
        assert finite.all(), frame.name
        if expected["visible"]:  # drawn, not silently dropped
            alpha = pixels[..., list(spec.channelnames).index("A")]
            assert np.count_nonzero(alpha > 0) > 10, frame.name


@pytest.mark.parametrize("name", sorted(CASES))
def test_bake(gl_context, tmp_path, capsys, name):
    expected = CASES[name]
    if expected["bake"]:
        expected = {**expected, "outcome": expected["bake"][0],
                    "fragment": expected["bake"][1]}
    out = tmp_path / "baked.usda"
    code = main(["bake", str(BAD / name), str(out), "--quiet"])
    if expected["outcome"] == "error":
        assert code == 2
        line, _ = one_line_error(capsys)
        assert expected["fragment"] in line, line
        assert not list(tmp_path.iterdir())
        return
    assert code == 0, capsys.readouterr().err
    stage = Usd.Stage.Open(str(out))
    for prim in stage.Traverse():
        for attr in prim.GetAttributes():
            if not attr.GetName().startswith("primvars:wrinkle:"):
                continue
            for time in attr.GetTimeSamples():
                value = np.asarray(attr.Get(time), np.float64)
                assert np.all(np.isfinite(value)), (prim.GetPath(), attr.GetName(), time)
                if attr.GetName() == "primvars:wrinkle:compression":
                    assert np.all((value > 0) & (value <= 1))
