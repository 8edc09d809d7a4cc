"""The paint window tried as an artist uses it (issue 43): a real window under Xvfb on
Qt's xcb platform, real mouse and key events, the window's own frames and screenshots.

Each test runs tests/paint_driver.py (or ``usdwrinkle paint`` itself, driven by xdotool)
in a process of its own, on an X server this module starts. The tier needs Xvfb,
libxcb-icccm4, libxcb-keysyms1 and xdotool (Debian; .ci/run installs them) and PySide6
(the test extra). Where they are missing it is skipped, saying so at the end of the run;
with USDWRINKLE_REQUIRE_PAINT=1 (CI) it fails instead. About 90 s in all here.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd

from usdwrinkle.authoring import WrinkleAPI

from helpers import (
    X_REFUSED,
    find_window,
    sheet_stage,
    start_window,
    wait_for_session,
    x_env,
    xdotool,
)

REPO = Path(__file__).resolve().parents[1]
DRIVER = REPO / "tests" / "paint_driver.py"
SHIRT = REPO / "sample_stages" / "shirt.usda"

pytestmark = pytest.mark.slow


def drive(display: str, scenario: str, out: Path, stage: Path | str = SHIRT) -> dict:
    for _ in range(3):  # again only when the X server refused the driver's connection
        proc = subprocess.run([sys.executable, str(DRIVER), scenario, str(out), str(stage)],
                              env=x_env(display), capture_output=True, text=True, timeout=300)
        if proc.returncode == 0 or not any(text in proc.stderr for text in X_REFUSED):
            break
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    result = json.loads((out / "result.json").read_text())
    result["stderr"] = proc.stderr
    return result


def screenshot_codes(path: Path) -> np.ndarray:
    import OpenImageIO as oiio

    return oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8)


def png_codes(path) -> np.ndarray:
    """A PNG's stored codes (straight alpha, as written; OpenImageIO would associate)."""
    import OpenImageIO as oiio

    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    image = oiio.ImageInput.open(str(path), config)
    try:
        return image.read_image(0, 0, 0, 4, oiio.UINT8)
    finally:
        image.close()


def test_a_comb_stroke_along_the_upper_arm(display, tmp_path):
    result = drive(display, "stroke", tmp_path)
    assert result["errors"] == []
    # every touched vertex combed along rest x, none on the far side, none beyond R
    assert result["touched"] >= 10
    assert result["alignment_min"] >= 0.95
    assert result["back_facing_touched"] == 0
    assert result["farthest_touched"] <= result["radius"] * (1 + 1e-9)
    assert result["q_max"] <= 1.0
    assert result["undo_exact"] and result["redo_exact"]
    # erase returns q to zero under the brush; smooth lowers the spread of q's direction
    assert result["erased"] >= 10 and result["erased_max"] == 0.0
    assert result["spread_after"] < 0.75 * result["spread_before"]
    # the preview keeps up while dragging (a bound far above the benchmark's figure, so
    # that a loaded machine does not fail it: the figure is in docs/benchmarks.md)
    assert np.median(result["preview_gaps"]) < 1.0
    # the screenshots show the stroke: the view changed where the upper arm is
    before = screenshot_codes(tmp_path / "before.png")
    after = screenshot_codes(tmp_path / "after.png")
    changed = np.abs(before[..., :3].astype(int) - after[..., :3]).max(-1) > 24
    assert changed.sum() > 2000


def test_a_mirrored_stroke_is_mirrored(display, tmp_path):
    stage = sheet_stage(tmp_path / "sheet.usda")
    result = drive(display, "mirror", tmp_path, stage)
    assert result["errors"] == []
    assert result["pairs"] == 41 * 41 and result["touched"] > 100
    assert result["mirror_error"] <= 1e-6


def test_halving_w_doubles_the_crests(display, tmp_path):
    stage = sheet_stage(tmp_path / "sheet.usda")
    result = drive(display, "width", tmp_path, stage)
    assert result["errors"] == []
    full, half = result["counts"]
    assert result["widths"][1] == pytest.approx(result["widths"][0] / 2, rel=0.01)
    assert full >= 5
    assert 1.8 <= half / full <= 2.2, result


def test_errors_show_in_the_window_and_it_goes_on(display, tmp_path):
    result = drive(display, "faults", tmp_path)
    for fault in ("paint", "brush", "save"):
        assert result[f"banner_{fault}"], (fault, result)
    assert result["seen"] == [["RuntimeError: injected fault in paintGL"],
                              ["RuntimeError: injected fault in the brush"],
                              ["RuntimeError: injected fault in save"]]
    assert result["drew_after"] and result["closed"]
    # one line each on stderr, no traceback without --debug (issue 54, finding 17)
    assert "usdwrinkle: paint: error: RuntimeError: injected fault in paintGL" in \
        result["stderr"]
    assert "Traceback" not in result["stderr"]


def test_undo_refreshes_the_w_slider_and_esc_shows_the_layer(display, tmp_path):
    """Issue 54: after Ctrl+Z the W slider still said the undone value (finding 10), and a
    stroke dropped with Esc over painted q stayed on screen (finding 9)."""
    stage = sheet_stage(tmp_path / "sheet.usda", nx=21)
    result = drive(display, "undo_and_escape", tmp_path, stage)
    assert result["errors"] == []
    assert result["w_changed"] < 0.8 * result["w_before"]
    assert result["w_after_undo"] == pytest.approx(result["w_before"])
    assert result["slider_after_undo"] == pytest.approx(result["w_before"])
    assert float(result["label_after_undo"]) == pytest.approx(result["w_before"], rel=1e-3)
    assert result["stroke_shown"] and result["same_after_escape"]
    assert result["undo_steps"] == 1  # the first stroke; W was undone, Esc left no step
    assert "Traceback" not in result["stderr"]


def test_the_help_overlay_and_typed_values(display, tmp_path):
    """Issue 57: no help, no tooltips and no typed values. With real X events (xdotool):
    H shows the keys over the view and ? hides them, the list read from the widget; W =
    0.05 typed into its field is the engine's W (one undo step); a typed strength is the
    brush's; a word and a refused slack leave the values and say so in one line."""
    result = drive(display, "help_and_typed", tmp_path)
    assert not result["overlay_before"] and result["overlay_after_h"]
    assert not result["overlay_after_question"]
    keys = {keys for keys, _ in result["listed"]}
    for expected in ("Left drag", "Alt+left drag", "Ctrl+Z", "Ctrl+Shift+Z", "Ctrl+S",
                     "Esc", "F", "[ and ]", "Space", "H or ?"):
        assert expected in keys, result["listed"]
    assert "Keys and mouse" in result["help_menu"]
    assert result["w_before"] != pytest.approx(0.05)
    assert result["w_control"] == pytest.approx(0.05, rel=1e-6)
    assert result["w_engine"] == pytest.approx(0.05, rel=1e-6)
    assert result["w_field"] == "0.05"
    assert result["undo_steps_after_w"] == 1
    # the W slider is fine around the value: 0.05 / 2 to 0.05 * 2, the handle mid-way
    low, high, position = result["w_slider_after_typed"]
    assert (low, high, position) == (pytest.approx(0.025), pytest.approx(0.1), 500)
    # a 26 px drag of its handle changes W by at most 4 ** (26 / the groove's width)
    # (over 400x before: 9x), then the slider centres on the new W
    low, high, position, pixels = result["w_slider_after_drag"]
    factor = result["w_after_drag"] / 0.05
    assert 1.05 < factor <= 4 ** (26 / (pixels - 20)), (factor, pixels)
    assert (low, high, position) == (pytest.approx(result["w_after_drag"] / 2),
                                     pytest.approx(result["w_after_drag"] * 2), 500)
    assert result["undo_steps_after_drag"] == 2
    assert result["strength"] == pytest.approx(0.8)
    assert result["amplitude_after_word"] == pytest.approx(1.0)
    assert result["amplitude_field"] == "1"
    assert result["slack_after_refusal"] < 1.0 and result["slack_field"] != "2"
    # Esc while typing puts the field back (the window's own Esc took the key before)
    assert result["amplitude_field_typing"] == "3.5"
    assert result["amplitude_field_after_esc"] == "1"
    before, after = result["amplitude_after_esc"]
    assert before == after == pytest.approx(1.0) and not result["field_focus_after_esc"]
    assert len(result["errors"]) == 2, result["errors"]
    assert result["errors"][0] == "amplitude: 'lots' is not a number"
    assert "slack" in result["errors"][1]
    assert "Traceback" not in result["stderr"]
    for name, tip in result["tooltips"].items():
        assert len(tip) > 15, name


def test_a_short_drag_with_a_huge_brush_paints_and_a_miss_says_so(display, tmp_path):
    """Issue 57: at radius 6.37 a short drag did nothing (stamps a quarter radius apart
    in rest space) and the outline vanished while painting. With real X events: an 80 px
    comb drag at radius 6 (typed) paints, as one undo step, its outline drawn while the
    button is down with an arrow along the drag (+x); a drag over the background changes
    nothing and the status bar says it missed."""
    result = drive(display, "big_brush", tmp_path)
    assert result["radius"] == pytest.approx(6.0) and result["mode"] == "comb"
    assert result["changed_points"] > 0 and result["undo_steps"] == 1
    assert result["stamps"] >= 2
    drawn = [seen for seen in result["outlines"].values() if seen is not None]
    assert len(drawn) == len(result["outlines"]) and all(seen["painting"] for seen in drawn)
    tip = drawn[-1]["tip"]
    assert tip is not None and tip[0] > result["cursor"][0] + 10  # the arrow points along +x
    assert abs(tip[1] - result["cursor"][1]) < 2
    assert "missed" in result["missed_message"]
    assert not result["missed_changed"] and result["undo_steps_after_miss"] == 1
    assert result["errors"] == []


def test_shift_smooths_and_ctrl_erases_while_held(display, tmp_path):
    """Issue 57: no modifier keys. With real X events over a combed upper arm: a drag
    with Shift held equals the same drag in the smooth mode, and with Ctrl held the same
    drag in the erase mode (each from the same state, Ctrl+Z between, which restores it
    exactly); erasing lowers the painted amount, and the brush's mode stays comb."""
    result = drive(display, "modifiers", tmp_path)
    assert result["combed"] > 0.5 and all(result["restored"]), result
    for mode in ("smooth", "erase"):
        assert result[mode]["changed"] > 1e-3, (mode, result[mode])
        assert result[mode]["held_vs_mode"] == 0.0, (mode, result[mode])
    assert result["erase"]["amount_after"] < 0.95
    assert result["mode_after"] == "comb" and result["errors"] == []


def test_b_and_a_drag_resize_the_brush(display, tmp_path):
    """Issue 57: no drag-to-resize. With real X events, B held and a 100 px drag to the
    right double the radius exactly (2 ** (dx / 100)); the outline grows on screen as it
    goes, nothing is painted, and a drag without B paints again."""
    result = drive(display, "resize", tmp_path)
    assert result["radius_after"] == pytest.approx(2 * result["radius_before"], rel=1e-6)
    assert float(result["field"]) == pytest.approx(result["radius_after"], rel=1e-2)
    sizes = [size for _, size in sorted(result["outline_px"].items(), key=lambda kv: int(kv[0]))]
    assert all(size is not None for size in sizes) and np.all(np.diff(sizes) > 0), sizes
    assert sizes[-1] / sizes[0] > 1.5
    assert result["q_untouched"] and result["undo_steps"] == 0
    assert result["painted_after"] and result["errors"] == []


def test_the_view_follows_the_animated_mesh(display, tmp_path):
    """Issue 57: the view stayed framed on the opening frame while the timeline played, so
    earlier frames ran off-screen. A sheet 2 units across travels 8 units along x over 17
    frames; played with Space, the view framed on the last frame loses it on the first
    frames, and with View > Follow the mesh keeps all of it in view on every frame."""
    from usdwrinkle.authoring.builders import grid_sheet, point_cache_stage

    rest, counts, indices = grid_sheet(9, 9, 2.0)
    posed = {f: rest * np.float32([0.8, 1.0, 1.0]) + np.float32([0.5 * (f - 17), 0.0, 0.0])
             for f in range(1, 18)}
    stage = point_cache_stage(rest, posed, counts, indices, width=0.3)
    path = tmp_path / "travel.usda"
    stage.GetRootLayer().Export(str(path))
    result = drive(display, "follow", tmp_path, stage=str(path))
    assert result["follow_checked"] and result["errors"] == []
    assert len(result["off"]) == len(result["on"]) == 17
    assert min(result["off"].values()) < 0.5, result["off"]  # the test can fail
    assert min(result["on"].values()) == 1.0, result["on"]


def test_pen_pressure_scales_the_strength(display, tmp_path):
    """Issue 57: pen pressure untested. Synthesized QTabletEvents (a stylus) over a combed
    arm in the erase mode: a tap at pressure 0.2 takes exactly 0.2 of what a tap at 1.0
    takes from q (erase moves q by strength x pressure x falloff), the pen's events are
    accepted (no mouse events doubled), and a mouse tap after the pen takes the full
    amount again."""
    result = drive(display, "tablet", tmp_path)
    assert all(result["accepted"]) and result["restored"] and result["errors"] == []
    low, full = np.array(result["taken"]["0.2"]), np.array(result["taken"]["1.0"])
    touched = np.abs(full) > 1e-4
    assert touched.sum() > 10
    np.testing.assert_allclose(low[touched] / full[touched], 0.2, rtol=2e-3)
    np.testing.assert_allclose(np.array(result["mouse_taken"])[touched], full[touched],
                               rtol=1e-4, atol=1e-6)


def test_display_modes_show_what_is_painted(display, tmp_path):
    """Issue 57: nothing showed what is painted. After a comb stroke, View > Display >
    Painted amount draws the painted points in the ramp's colours (saturated, warm at
    |q| > 0.5) and the unpainted ones grey, where the shaded view showed the plaid;
    Painted W draws the uniform W green (the W control's value); Shaded gives back the
    very same frame."""
    result = drive(display, "display", tmp_path)
    assert result["errors"] == [] and result["amount_checked"] and result["width_checked"]
    shaded, amount, width = result["shaded"], result["amount"], result["width"]
    assert amount["painted"]["count"] > 20 and amount["unpainted"]["count"] > 20
    assert shaded["unpainted"]["saturation"] > 0.3  # the plaid
    assert amount["unpainted"]["saturation"] < 0.1  # grey: nothing painted
    assert amount["painted"]["saturation"] > 0.5
    red, green, blue = amount["painted"]["rgb"]
    assert red > blue and green > blue  # warm: the ramp's upper half
    for where in ("painted", "unpainted"):
        red, green, blue = width[where]["rgb"]
        assert green > 1.5 * red and green > 1.5 * blue, width[where]
    assert result["shaded_again"] == shaded


def test_brush_presets_are_saved_and_chosen(display, tmp_path):
    """Issue 57: no brush presets. With real X events: a brush saved as a preset (Save...,
    the name answered) is written to the config folder's brushes.json; after changing the
    brush, choosing the preset from its list gives back every setting, the controls
    showing them; a file with a bad preset still lists the good one and says the bad one
    in one line, naming it."""
    result = drive(display, "presets", tmp_path)
    saved = result["saved"]
    assert saved["mode"] == "smooth" and saved["falloff"] == "linear"
    assert saved["radius"] == pytest.approx(0.2) and saved["strength"] == pytest.approx(0.8)
    assert result["file"]["presets"]["soft smooth"] == saved
    assert result["listed_after_save"] == ["(choose)", "soft smooth"]
    assert result["changed"]["mode"] == "comb" and result["changed"]["radius"] == 0.5
    chosen = dict(result["chosen"])
    assert chosen.pop("width") == result["changed"]["width"]  # W stays the W control's
    assert chosen == {k: v for k, v in saved.items() if k != "width"}
    assert result["controls"] == {"mode": "smooth", "falloff": "linear", "radius": "0.2",
                                  "strength": "0.8"}
    assert result["errors"] == []
    assert result["listed_with_second"] == ["(choose)", "soft smooth", "to go"]
    assert result["listed_after_delete"] == ["(choose)", "soft smooth"]
    assert result["file_after_delete"] == ["soft smooth"]
    assert result["listed_with_broken"] == ["(choose)", "soft smooth"]
    assert len(result["errors_with_broken"]) == 1
    assert "'broken'" in result["errors_with_broken"][0]
    assert "radius" in result["errors_with_broken"][0]


def test_file_open_recent_files_and_save_as_in_the_layers_folder(display, tmp_path):
    """Issue 57: no File > Open, no recent files, Save As in the current folder. With the
    shirt painted and unsaved, Ctrl+O (a real key, the dialog answered, starting in the
    shirt's folder) asks first: cancel keeps the shirt and its strokes, discard opens the
    second stage in the same window (its mesh, timeline and title), which then paints;
    File > Open Recent lists both stages, newest first, and opens the shirt again; Save
    As starts at the layer itself, in its folder."""
    from usdwrinkle.authoring.builders import grid_sheet, point_cache_stage

    rest, counts, indices = grid_sheet(9, 9, 2.0)
    posed = {f: rest * np.float32([1.0 - 0.02 * f, 1.0, 1.0]) for f in range(1, 11)}
    second = tmp_path / "second" / "sheet.usda"
    second.parent.mkdir()
    stage = point_cache_stage(rest, posed, counts, indices, width=0.3)
    stage.GetRootLayer().Export(str(second))
    result = drive(display, "open", tmp_path / "out", stage=str(second))
    assert result["open_started_in"] == str(SHIRT.parent)
    assert result["after_cancel"] == str(SHIRT) and result["dirty_after_cancel"]
    assert result["after_open"] == result["root_after_open"] == str(second)
    assert result["paths"] == ["/Sheet"]
    assert str(second) in result["title"] and not result["dirty_after_open"]
    assert result["timeline"] == [1, 10]
    assert result["painted_new"]
    assert result["recent"][:2] == [str(second), str(SHIRT)]
    assert result["save_as_started_at"] == str(second)  # edited in place: the stage itself
    assert result["after_recent"] == str(SHIRT)
    assert result["paths_after_recent"] == ["/World/Arm/Sleeve"]
    assert result["errors"] == []
    # refused: not a stage, and nothing to paint; one line each, the shirt kept
    assert result["refused"] == [False, False]
    assert len(result["errors_after_refused"]) == 2, result["errors_after_refused"]
    assert "WrinkleAPI" in result["errors_after_refused"][1]
    assert result["after_refused"] == str(SHIRT)
    assert result["paths_after_refused"] == ["/World/Arm/Sleeve"]


def test_closing_with_unsaved_strokes_asks_first(display, tmp_path):
    result = drive(display, "close", tmp_path)
    assert result["asked"] == ["cancel", "save"] and result["errors"] == []
    assert result["open_after_cancel"] and result["dirty_after_cancel"]
    assert not result["saved_after_cancel"] and result["title_modified"]
    assert result["saved"] and not result["open_after_save"]


def test_the_saved_layer_renders_as_the_window_drew_it(display, tmp_path):
    from usdwrinkle.cli.main import main

    result = drive(display, "render_equal", tmp_path)
    assert result["errors"] == [] and result["saved"] and not result["dirty"]
    assert result["reopened_same_q"]
    for frame, (width, height) in result["sizes"].items():
        out = tmp_path / f"render.{int(frame):04d}.png"
        assert main(["render", str(tmp_path / "equal.usda"), str(out), "--frames", frame,
                     "--width", str(width), "--height", str(height), "--quiet"]) == 0
        widget = np.load(tmp_path / f"widget.{frame}.npy")
        assert np.array_equal(widget, png_codes(out)), frame
    # View > Relief draws as render --relief
    assert result["relief"]["checked"]
    width, height = result["relief"]["size"]
    out = tmp_path / "render.relief.0024.png"
    assert main(["render", str(tmp_path / "equal.usda"), str(out), "--frames", "24",
                 "--width", str(width), "--height", str(height), "--relief", "--quiet"]) == 0
    widget = np.load(tmp_path / "widget.relief.24.npy")
    assert np.array_equal(widget, png_codes(out))
    assert not np.array_equal(widget, np.load(tmp_path / "widget.24.npy"))


def test_an_artist_paints_and_saves(display, tmp_path):
    """usdwrinkle paint shirt.usda -o out.usda; a left-button drag across the window's
    middle (X events from xdotool); Ctrl+S; Ctrl+W. The layer holds the stroke's q, and
    render of it differs from the plain shirt."""
    from usdwrinkle.cli.main import main

    out = tmp_path / "out.usda"
    # the main window (Qt also makes hidden helper windows of that name)
    proc, log, window = start_window(display, [sys.executable, "-m", "usdwrinkle", "paint",
                                               str(SHIRT), "-o", str(out), "--size",
                                               "1000x650"], tmp_path / "paint.log")
    try:
        xdotool(display, "windowfocus", "--sync", window)
        wait_for_session(display, window)
        geometry = dict(line.split("=") for line in
                        xdotool(display, "getwindowgeometry", "--shell", window).split())
        width, height = int(geometry["WIDTH"]), int(geometry["HEIGHT"])
        y = height // 2
        xdotool(display, "mousemove", "--window", window, str(width // 6), str(y))
        xdotool(display, "mousedown", "1")
        for step in range(1, 25):
            x = width // 6 + step * (width // 2) // 24
            xdotool(display, "mousemove", "--window", window, str(x), str(y))
            time.sleep(0.05)
        xdotool(display, "mouseup", "1")
        if shutil.which("import"):  # ImageMagick's, where installed: a screenshot to look at
            time.sleep(2)  # the full-quality frame after release
            subprocess.run(["import", "-window", "root", str(tmp_path / "artist.png")],
                           env=x_env(display), timeout=60, check=False)
        xdotool(display, "key", "--window", window, "ctrl+s")
        deadline = time.monotonic() + 30
        while not out.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        assert out.exists(), (tmp_path / "paint.log").read_text()
        # the window closes (nothing unsaved); xdotool may then miss its window
        xdotool(display, "key", "--window", window, "ctrl+w", check=False)
        assert proc.wait(30) == 0, (tmp_path / "paint.log").read_text()
    finally:
        if proc.poll() is None:
            proc.kill()
        log.close()
    painted = Usd.Stage.Open(str(out))
    plain = Usd.Stage.Open(str(SHIRT))
    path = "/World/Arm/Sleeve"
    q = WrinkleAPI(painted.GetPrimAtPath(path)).get_q()
    q0 = WrinkleAPI(plain.GetPrimAtPath(path)).get_q()
    changed = np.any(q != q0, axis=1)
    assert changed.sum() >= 10
    assert np.linalg.norm(q[changed], axis=1).min() > 0.0
    assert np.linalg.norm(q, axis=1).max() <= 1.0
    # the layer stands on its own: it sublayers the shirt by a relative path
    assert not os.path.isabs(painted.GetRootLayer().subLayerPaths[0])
    for stage, name in ((out, "painted"), (SHIRT, "plain")):
        assert main(["render", str(stage), str(tmp_path / f"{name}.png"), "--frames", "24",
                     "--width", "320", "--quiet"]) == 0
    a, b = png_codes(tmp_path / "painted.png"), png_codes(tmp_path / "plain.png")
    assert (np.abs(a.astype(int) - b).max(-1) > 8).sum() > 200


def test_usdview_paints_in_its_own_process(display, tmp_path):
    result = drive(display, "usdview", tmp_path)
    assert result["errors"] == [] and result["in_session_layer"], result
    assert not result["root_dirty"] and not result["dirty"] and result["frame"] == 24.0
    assert "strokes go to the session layer" in result["status"][-1]


def test_usdview_paints_through_usdwrinkle_python(display, tmp_path, monkeypatch):
    """From a usdview whose Python cannot import usdwrinkle's dependencies: the window is
    usdwrinkle paint in USDWRINKLE_PYTHON, and its saved strokes reach usdview's stage
    through an overrides layer that the session layer sublayers."""
    from types import SimpleNamespace

    from pxr import Sdf

    from usdwrinkle import usdview

    monkeypatch.setattr(usdview, "_in_process", lambda: False)
    monkeypatch.setenv("USDWRINKLE_PYTHON", sys.executable)
    stage = Usd.Stage.Open(str(SHIRT))
    sleeve = stage.GetPrimAtPath("/World/Arm/Sleeve")
    status: list[str] = []
    api = SimpleNamespace(stage=stage, frame=Usd.TimeCode(24), selectedPrims=[sleeve],
                          PrintStatus=status.append)
    launched = []

    def launcher(args):
        launched.append(args)
        return subprocess.Popen(args, env=x_env(display), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)

    process = usdview.paint_current_stage(api, launcher=launcher)
    args = launched[0]
    assert args[:4] == [sys.executable, "-m", "usdwrinkle", "paint"]
    assert args[args.index("--prim") + 1] == "/World/Arm/Sleeve" and "--frame=24.0" in args
    strokes = args[args.index("-o") + 1]
    assert stage.GetSessionLayer().subLayerPaths[0] == strokes
    q0 = WrinkleAPI(sleeve).get_q()
    try:
        window = find_window(display, "usdwrinkle paint", process.pid)
        xdotool(display, "windowfocus", "--sync", window)
        wait_for_session(display, window)
        geometry = dict(line.split("=") for line in
                        xdotool(display, "getwindowgeometry", "--shell", window).split())
        width, height = int(geometry["WIDTH"]), int(geometry["HEIGHT"])
        xdotool(display, "mousemove", "--window", window, str(width // 6), str(height // 2))
        xdotool(display, "mousedown", "1")
        for step in range(1, 25):
            xdotool(display, "mousemove", "--window", window,
                    str(width // 6 + step * (width // 2) // 24), str(height // 2))
            time.sleep(0.05)
        xdotool(display, "mouseup", "1")
        before = os.path.getmtime(strokes)
        xdotool(display, "key", "--window", window, "ctrl+s")
        deadline = time.monotonic() + 30
        while os.path.getmtime(strokes) == before and time.monotonic() < deadline:
            time.sleep(0.2)
        xdotool(display, "key", "--window", window, "ctrl+w", check=False)
        assert process.wait(30) == 0
    finally:
        if process.poll() is None:
            process.kill()
    Sdf.Layer.Find(strokes).Reload()  # what the plugin's timer does inside usdview
    q = WrinkleAPI(sleeve).get_q()
    assert np.any(q != q0, axis=1).sum() >= 10
    assert not stage.GetRootLayer().dirty
