"""Brush presets (usdwrinkle/app/presets.py, issue 57): a JSON file in the config folder,
every preset checked as a brush is."""
from __future__ import annotations

import json

import pytest

from usdwrinkle.app.presets import (
    config_dir,
    delete_preset,
    load_presets,
    presets_path,
    save_preset,
)
from usdwrinkle.brush.stamp import BrushSettings
from usdwrinkle.process.errors import UsdWrinkleError


def test_the_config_folder_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.delenv("USDWRINKLE_CONFIG_DIR", raising=False)
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "xdg"))
    assert config_dir() == tmp_path / "xdg" / "usdwrinkle"
    monkeypatch.setenv("USDWRINKLE_CONFIG_DIR", str(tmp_path / "own"))
    assert presets_path() == tmp_path / "own" / "brushes.json"


def test_presets_round_trip_and_keep_each_other(tmp_path):
    path = tmp_path / "cfg" / "brushes.json"
    assert load_presets(path) == ({}, [])  # no file: no presets
    fine = BrushSettings(mode="smooth", radius=0.05, strength=0.9, mirror="x")
    save_preset("fine", fine, path)
    save_preset(" wide ", BrushSettings(radius=2.0), path)
    brushes, refused = load_presets(path)
    assert refused == [] and sorted(brushes) == ["fine", "wide"]
    assert brushes["fine"] == fine
    save_preset("fine", BrushSettings(radius=0.07), path)  # the same name replaces it
    assert load_presets(path)[0]["fine"].radius == 0.07
    delete_preset("wide", path)
    assert sorted(load_presets(path)[0]) == ["fine"]
    with pytest.raises(UsdWrinkleError, match="no brush preset 'wide'"):
        delete_preset("wide", path)
    assert json.loads(path.read_text())["version"] == 1
    assert [p.name for p in path.parent.iterdir()] == ["brushes.json"]  # no temporaries


def test_a_bad_preset_is_refused_in_one_line_and_the_others_load(tmp_path):
    path = tmp_path / "brushes.json"
    path.write_text(json.dumps({"version": 1, "presets": {
        "good": {"radius": 0.3}, "negative": {"radius": -1}, "odd": {"colour": "red"},
        "list": [1, 2]}}))
    brushes, refused = load_presets(path)
    assert sorted(brushes) == ["good"] and brushes["good"].radius == 0.3
    assert len(refused) == 3
    assert any("'negative'" in line and "radius" in line for line in refused)
    assert any("'odd'" in line and "colour" in line for line in refused)
    path.write_text("{not json")
    with pytest.raises(UsdWrinkleError, match="cannot be read"):
        load_presets(path)
    with pytest.raises(UsdWrinkleError, match="needs a name"):
        save_preset("  ", BrushSettings(), tmp_path / "other.json")


def test_recent_stages_keep_the_newest_first_and_only_existing_files(tmp_path):
    from usdwrinkle.app.recent import KEEP, recent_stages, remember_stage

    path = tmp_path / "cfg" / "recent.json"
    assert recent_stages(path) == []
    files = []
    for k in range(KEEP + 2):
        stage = tmp_path / f"s{k}.usda"
        stage.write_text("#usda 1.0\n")
        files.append(str(stage))
        remember_stage(str(stage), path)
    assert recent_stages(path) == files[::-1][:KEEP]
    remember_stage(files[5], path)  # again: moved to the front, not doubled
    assert recent_stages(path)[:2] == [files[5], files[-1]]
    assert len(recent_stages(path)) == KEEP
    (tmp_path / "s11.usda").unlink()  # a stage that is gone is not listed
    assert files[-1] not in recent_stages(path)
    path.write_text("{broken")
    assert recent_stages(path) == []  # a convenience: an unreadable list is empty
