"""metersPerUnit that no width can be converted through (issue 42, findings 7, 12, 21):
render, bake and check refuse it in one line (it was a ZeroDivisionError, NaN widths,
negative widths, or a clean check), and check --json stays strict JSON."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from pxr import Usd

from usdwrinkle.cli.main import main

CURTAIN = Path(__file__).resolve().parents[1] / "sample_stages" / "curtain.usda"


def shot(tmp_path, meters: float) -> str:
    """The curtain (a cloth preset's width, no authored W) under a root layer with
    ``meters``."""
    path = tmp_path / "shot.usda"
    stage = Usd.Stage.CreateNew(str(path))
    stage.GetRootLayer().subLayerPaths.append(str(CURTAIN))
    stage.GetRootLayer().pseudoRoot.SetInfo("metersPerUnit", float(meters))
    stage.Save()
    return str(path)


@pytest.mark.parametrize("meters", [float("nan"), float("inf"), -1.0, 0.0, 1e-30, 1e12])
def test_unusable_units_are_refused_everywhere(tmp_path, capsys, meters):
    """1e-30 gave W = 8.5e28 scene units, beyond the documented 1e15 of any width."""
    stage = shot(tmp_path, meters)
    expected = f"metersPerUnit {meters:g} must be finite and within 1e-09..1e+09"
    assert main(["render", stage, str(tmp_path / "x.png"), "--frames", "3", "--width",
                 "32"]) == 2
    assert expected in capsys.readouterr().err
    assert main(["bake", stage, str(tmp_path / "b.usda"), "--frames", "3"]) == 2
    assert expected in capsys.readouterr().err
    assert not list(tmp_path.glob("x*")) and not list(tmp_path.glob("b*"))
    assert main(["check", stage, "--wrinkles-only", "--json"]) == 1
    report = json.loads(capsys.readouterr().out,
                        parse_constant=lambda name: pytest.fail(f"{name} is not JSON"))
    assert not report["clean"]
    assert any(f["attribute"] == "metersPerUnit" and expected in f["message"]
               for f in report["findings"])


def test_frames_outside_the_shot_are_said(tmp_path, capsys):
    """Issue 42, finding 19: --frames 100:102 on a 1..24 shot rendered after a 99-frame
    preroll without a word."""
    shirt = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")
    assert main(["render", shirt, str(tmp_path / "x.####.png"), "--frames", "100:101",
                 "--width", "32", "--samples", "1", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "2 of the 2 frame(s) lie outside the stage's time range 1..24 (first: 100)" in err
    assert main(["render", shirt, str(tmp_path / "y.####.png"), "--frames", "23:24",
                 "--width", "32", "--samples", "1", "--quiet"]) == 0
    assert "outside" not in capsys.readouterr().err


def test_unauthored_and_mismatched_units_are_said(tmp_path, capsys, corpus):
    """Issue 42, finding 2: the README's CesiumMan recipe (a shot without metersPerUnit
    over a .usdz in metres) rendered W 100x too wide, and a sublayer's other units changed
    the amplitude, with no word from render, bake or check."""
    shot = tmp_path / "shot.usda"
    stage = Usd.Stage.CreateNew(str(shot))
    stage.GetRootLayer().subLayerPaths.append(str(corpus / "usd-wg" / "CesiumMan.usdz"))
    stage.Save()
    assert main(["render", str(shot), str(tmp_path / "x.png"), "--frames", "1", "--width",
                 "32", "--all-meshes", "--quiet"]) == 0
    err = capsys.readouterr().err
    assert "the stage's root layer authors no metersPerUnit, so the cloth preset's width" in err
    assert "CesiumMan.usdz' authors metersPerUnit 1 but the stage uses its root layer's " \
        "0.01" in err
    assert main(["check", str(shot), "--wrinkles-only", "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert any(f["attribute"] == "metersPerUnit" and f["type"] == "warning" and
               "authors metersPerUnit 1" in f["message"] for f in report["findings"])
    # the curtain, whose own layer authors metres, under a root layer that agrees: silent
    agreeing = shot.parent / "agree.usda"
    stage = Usd.Stage.CreateNew(str(agreeing))
    stage.GetRootLayer().subLayerPaths.append(str(CURTAIN))
    stage.GetRootLayer().pseudoRoot.SetInfo("metersPerUnit", 1.0)
    stage.Save()
    assert main(["render", str(agreeing), str(tmp_path / "y.png"), "--frames", "3",
                 "--width", "32", "--quiet"]) == 0
    assert "metersPerUnit" not in capsys.readouterr().err
