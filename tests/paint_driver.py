"""Drives the paint window as an artist does, in a process of its own under Xvfb (Qt's
xcb platform: QOpenGLWidget needs a real window): real QMouseEvents and key presses,
the window's own frames and screenshots. tests/test_paint_window.py runs it:

    python tests/paint_driver.py SCENARIO OUTDIR [STAGE]

and reads OUTDIR/result.json. Each scenario is one function below. The process never
shares GL with pytest's own context (Qt's GLX context and moderngl's EGL one in one
thread would take each other's place)."""
from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

os.environ.setdefault("QT_QPA_PLATFORM", "xcb")

from PySide6 import QtCore, QtGui, QtWidgets  # noqa: E402
from PySide6.QtTest import QTest  # noqa: E402

Qt = QtCore.Qt
REPO = Path(__file__).resolve().parents[1]
SHIRT = REPO / "sample_stages" / "shirt.usda"


def application() -> QtWidgets.QApplication:
    fmt = QtGui.QSurfaceFormat()
    fmt.setVersion(4, 3)
    fmt.setProfile(QtGui.QSurfaceFormat.CoreProfile)
    fmt.setDepthBufferSize(24)
    QtGui.QSurfaceFormat.setDefaultFormat(fmt)
    return QtWidgets.QApplication.instance() or QtWidgets.QApplication(["paint-driver"])


def open_window(stage: str, output: str, size=(1200, 700), **kwargs):
    from usdwrinkle.app.paint_session import PaintSession, open_paint_stage
    from usdwrinkle.paint.window import PaintWindow

    stage_, layer, save = open_paint_stage(stage, output)
    window = PaintWindow(lambda ctx: PaintSession(stage_, layer, save, ctx=ctx, **kwargs),
                         stage_path=os.path.abspath(stage))
    window.resize(*size)
    window.show()
    window.confirm_close = lambda: "discard"
    window.activateWindow()
    window.raise_()
    window.view.setFocus()
    wait_for(lambda: window.view.last_frame is not None, "the first frame")
    wait_for(window.isActiveWindow, "the window to take the keyboard")
    settle(window)
    return window


def wait_for(condition, what: str, timeout: float = 60.0) -> None:
    app = QtWidgets.QApplication.instance()
    deadline = time.monotonic() + timeout
    while not condition():
        app.processEvents(QtCore.QEventLoop.AllEvents, 50)
        if time.monotonic() > deadline:
            raise TimeoutError(f"waited {timeout} s for {what}")
        time.sleep(0.01)


def settle(window, quality: str = "full") -> None:
    """Let the view draw until its last frame is of ``quality`` and nothing is pending."""
    view = window.view
    view.update()
    count = len(view.frame_times)
    wait_for(lambda: len(view.frame_times) > count, "a frame")
    wait_for(lambda: view.last_frame is not None and
             view.last_frame.quality.preview == (quality == "preview"), f"a {quality} frame")


def mouse(widget, kind, x: float, y: float, button=Qt.LeftButton, buttons=None,
          modifiers=Qt.NoModifier) -> None:
    """A real QMouseEvent, through the application's event dispatch."""
    local = QtCore.QPointF(x, y)
    if buttons is None:
        buttons = Qt.NoButton if kind == QtCore.QEvent.MouseButtonRelease else button
    event = QtGui.QMouseEvent(kind, local, widget.mapToGlobal(local), button, buttons,
                              modifiers)
    QtWidgets.QApplication.sendEvent(widget, event)
    QtWidgets.QApplication.instance().processEvents()


def drag(window, points, button=Qt.LeftButton, modifiers=Qt.NoModifier) -> list[float]:
    """Press at the first point, move through the others (drawing between moves as
    the event loop does), release at the last; returns the seconds between frames."""
    view = window.view
    stamps = []
    mouse(view, QtCore.QEvent.MouseButtonPress, *points[0], button, modifiers=modifiers)
    for x, y in points[1:]:
        count = len(view.frame_times)
        mouse(view, QtCore.QEvent.MouseMove, x, y, Qt.NoButton, button, modifiers)
        wait_for(lambda c=count: len(view.frame_times) > c, "a preview frame")
        stamps.append(time.perf_counter())
    mouse(view, QtCore.QEvent.MouseButtonRelease, *points[-1], button, modifiers=modifiers)
    settle(window)
    return list(np.diff(stamps))


def line(a, b, steps: int = 30) -> list[tuple[float, float]]:
    return [tuple(np.asarray(a) + (np.asarray(b) - np.asarray(a)) * k / steps)
            for k in range(steps + 1)]


def view_pixels(window, path: str, mask: np.ndarray) -> np.ndarray:
    """The mean widget position of the posed vertices in ``mask`` (logical pixels)."""
    from usdwrinkle.brush.view import project

    session, frame = window.session, window.view.last_frame
    xy, _ = project(frame.camera, session.posed_points(path)[mask], frame.width, frame.height)
    xy[:, 0] *= window.view.width() / frame.width
    xy[:, 1] *= window.view.height() / frame.height
    return xy.mean(axis=0)


def key(window, key_code, modifiers=Qt.NoModifier) -> None:
    QTest.keyClick(window.view, key_code, modifiers)
    settle(window)


def screenshot(window, path: Path) -> str:
    """The window as the screen shows it (QWidget.grab re-renders a QOpenGLWidget
    without what QPainter draws over it: the brush outline and q)."""
    QtWidgets.QApplication.instance().processEvents()
    screen = QtWidgets.QApplication.instance().primaryScreen()
    screen.grabWindow(window.winId()).save(str(path))
    return str(path)


def upper_arm_stroke(window):
    """Pixels of a stroke along the rest x axis over the shirt's upper arm (rest x from
    0.3 to 1.0, on its front), and the facing flags at the start."""
    session = window.session
    path = session.active
    rest = session.mesh.rest_points
    facing = session.facing(path)
    a = view_pixels(window, path, facing & (np.abs(rest[:, 0] - 0.3) < 0.1))
    b = view_pixels(window, path, facing & (np.abs(rest[:, 0] - 1.0) < 0.1))
    return line(a, b), facing


def distance_to_segment(points, a, b) -> np.ndarray:
    ab = b - a
    t = np.clip(((points - a) @ ab) / max(ab @ ab, 1e-30), 0.0, 1.0)
    return np.linalg.norm(points - (a + t[:, None] * ab), axis=1)


# -- scenarios -------------------------------------------------------------------------
from helpers import sheet_stage  # noqa: E402,F401  (the tests' symmetric sheet)


def scenario_stroke(out: Path, stage: str) -> dict:
    """Comb along rest x over the upper arm, undo, redo, erase, smooth; screenshots."""
    window = open_window(stage, str(out / "painted.usda"))
    session = window.session
    screenshot(window, out / "before.png")
    path = session.active
    q0 = session.mesh.q.copy()
    points, facing = upper_arm_stroke(window)
    gaps = drag(window, points)
    q1 = session.mesh.q.copy()
    changed = np.nonzero(np.any(q1 != q0, axis=1))[0]
    length = np.linalg.norm(q1[changed], axis=1)
    rest = session.mesh.rest_points
    result = {
        "touched": int(len(changed)),
        "alignment_min": float((np.abs(q1[changed, 0]) / length).min()) if len(changed) else 0,
        "back_facing_touched": int((~facing[changed]).sum()),
        "q_max": float(np.linalg.norm(q1, axis=1).max()),
        "radius": session.brush.radius,
        "errors": list(window.errors),
        "preview_gaps": gaps,
    }
    centres = np.array(session.stamp_centres)
    far = [float(np.min(np.linalg.norm(centres - rest[i], axis=1))) for i in changed]
    result["farthest_touched"] = max(far) if far else 0.0
    window.show_q.setChecked(True)
    settle(window)
    screenshot(window, out / "after.png")
    window.show_q.setChecked(False)
    key(window, Qt.Key_Z, Qt.ControlModifier)
    session.engine.pull_changes()
    result["undo_exact"] = bool(np.array_equal(session.mesh.q, q0)) and bool(
        np.array_equal(session.engine.meshes[path].params.q, q0))
    key(window, Qt.Key_Z, Qt.ControlModifier | Qt.ShiftModifier)
    session.engine.pull_changes()
    result["redo_exact"] = bool(np.array_equal(session.mesh.q, q1)) and bool(
        np.array_equal(session.engine.meshes[path].params.q, q1))
    # erase: full strength, a constant profile, the same stroke
    window.mode.setCurrentText("erase")
    window.falloff.setCurrentText("constant")
    window.strength.set_value(1.0)
    window._brush_changed()
    drag(window, points)
    q2 = session.mesh.q
    erased = session.last_touched
    result["erased"] = int(len(erased))
    result["erased_max"] = float(np.abs(q2[erased]).max()) if len(erased) else 1.0
    # smooth: over a region of scattered directions
    key(window, Qt.Key_Z, Qt.ControlModifier)
    from usdwrinkle.brush.stamp import spread

    rng = np.random.default_rng(7)
    noisy = session.mesh.q.copy()
    region = np.nonzero(distance_to_segment(rest, np.array([0.3, 0, 0]),
                                            np.array([1.0, 0, 0])) < 0.6)[0]
    # along x, scattered: each vertex's direction off by a random tangent part
    scattered = np.array([1.0, 0.0, 0.0]) + 0.7 * rng.normal(size=(len(region), 3))
    noisy[region] = 0.8 * scattered / np.linalg.norm(scattered, axis=1)[:, None]
    from usdwrinkle.app.paint_session import Edit

    session._record(Edit(path, "paint", (session.mesh.q.copy(), session.mesh.width.copy()),
                         (noisy.astype(np.float32), session.mesh.width.copy())))
    window.mode.setCurrentText("smooth")
    window.falloff.setCurrentText("smooth")
    window.strength.set_value(1.0)
    window._brush_changed()
    before_smooth = session.mesh.q.copy()
    for _ in range(3):
        drag(window, points)
    touched = session.last_touched
    result["spread_before"] = spread(before_smooth, touched)
    result["spread_after"] = spread(session.mesh.q, touched)
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_mirror(out: Path, stage: str) -> dict:
    """A stroke on one half of a symmetric sheet with the mirror through x = 0."""
    window = open_window(stage, str(out / "mirror.usda"))
    session = window.session
    window.mirror.setCurrentText("x")
    window._brush_changed()
    rest = session.mesh.rest_points
    path = session.active
    facing = session.facing(path)
    a = view_pixels(window, path, facing & (np.abs(rest[:, 0] - 0.3) < 0.06) &
                    (np.abs(rest[:, 1] + 0.4) < 0.06))
    b = view_pixels(window, path, facing & (np.abs(rest[:, 0] - 0.6) < 0.06) &
                    (np.abs(rest[:, 1] - 0.3) < 0.06))
    drag(window, line(a, b))
    q = session.mesh.q.astype(np.float64)
    partner = session.mesh.mirror_map("x")
    paired = partner >= 0
    mirrored = q[partner[paired]] * np.array([-1.0, 1.0, 1.0])
    result = {"pairs": int(paired.sum()), "touched": int(np.any(q != 0, axis=1).sum()),
              "mirror_error": float(np.abs(q[paired] - mirrored).max()),
              "errors": list(window.errors)}
    screenshot(window, out / "mirror.png")
    window.close()
    return result


def crest_count(pixels: np.ndarray, row: int, lo: int, hi: int, band: int = 40) -> float:
    """Crests along a line of the frame (row ``row``, columns lo..hi): the number of
    wavelengths of the strongest periodic part of the luminance across it (a Hann-windowed
    spectrum, 16x zero-padded; the rows within ``band`` of it summed). A count of peaks
    would be fooled by the flat tops of the height profile and the light's falloff."""
    rows = slice(max(row - band, 0), row + band)
    luminance = pixels[rows, lo:hi, :3].astype(np.float64) @ [0.2126, 0.7152, 0.0722]
    luminance -= luminance.mean(axis=1, keepdims=True)
    n = luminance.shape[1]
    spectrum = np.abs(np.fft.rfft(luminance * np.hanning(n), n=16 * n, axis=1)).sum(axis=0)
    frequency = np.fft.rfftfreq(16 * n)
    spectrum[frequency < 2.0 / n] = 0.0  # the mean and the shading's slow change
    return float(frequency[np.argmax(spectrum)] * n)


def scenario_width(out: Path, stage: str) -> dict:
    """Flood q over a flat sheet, then halve W with its slider: the crests along a line
    across the painted area, counted in the widget's own frame."""
    window = open_window(stage, str(out / "width.usda"), size=(1000, 700))
    session = window.session
    session.orbit.yaw, session.orbit.pitch = 0.0, 89.0  # straight down onto the sheet
    session.frame_view(window.view.width() / window.view.height())
    window.strength.set_value(0.6)
    window.amount.set_value(0.6)
    window._brush_changed()
    session._last_stroke_direction = np.array([1.0, 0.0, 0.0])
    window.flood_button.click()
    settle(window)
    frame = window.view.last_frame
    covered = np.nonzero(frame.pixels[frame.height // 2, :, 3] == 255)[0]
    row, lo, hi = frame.height // 2, int(covered.min()) + 4, int(covered.max()) - 4
    counts = [crest_count(frame.pixels, row, lo, hi)]
    np.save(out / "width_full.npy", frame.pixels)
    screenshot(window, out / "width_full.png")
    slider = window.width_slider
    width = slider.value()
    slider.slider.setSliderDown(True)
    slider.slider.setValue(slider._to_position(width / 2))
    settle(window, "preview")
    slider.slider.setSliderDown(False)
    slider.slider.sliderReleased.emit()
    settle(window)
    frame = window.view.last_frame
    counts.append(crest_count(frame.pixels, row, lo, hi))
    np.save(out / "width_half.npy", frame.pixels)
    screenshot(window, out / "width_half.png")
    result = {"counts": counts, "widths": [width, session.control("width")],
              "errors": list(window.errors)}
    window.close()
    return result


def scenario_faults(out: Path, stage: str) -> dict:
    """An exception inside paintGL, the brush and save: shown, and the window goes on."""
    window = open_window(stage, str(out / "faults.usda"))
    result = {"seen": []}
    for fault in ("paint", "brush", "save"):
        before = len(window.errors)
        window.view.faults.arm(fault)
        if fault == "paint":
            window.view.update()
            wait_for(lambda b=before: len(window.errors) > b, "the paint error")
        elif fault == "brush":
            mouse(window.view, QtCore.QEvent.MouseButtonPress, 400, 300)
            mouse(window.view, QtCore.QEvent.MouseButtonRelease, 400, 300)
        else:
            QTest.keyClick(window.view, Qt.Key_S, Qt.ControlModifier)
            QtWidgets.QApplication.instance().processEvents()
        result["seen"].append(window.errors[before:])
        # the window shows its banner from the event loop (a zero-time timer, so that no
        # layout change happens inside paintGL): wait for it, as an artist would see it
        # a moment later, instead of reading the banner in the same instant
        shown = window.errors[before:][-1:] if len(window.errors) > before else []
        try:
            wait_for(lambda t=shown: bool(t) and window.error_banner.isVisible() and
                     window.error_banner.text() == f"error: {t[0]}", f"the {fault} banner",
                     timeout=30.0)
        except TimeoutError:
            pass  # the test reports the banner as not shown
        result[f"banner_{fault}"] = window.error_banner.isVisible() and \
            "injected" in window.error_banner.text()
    # and it still draws and paints
    count = len(window.view.frame_times)
    settle(window)
    result["drew_after"] = len(window.view.frame_times) > count
    screenshot(window, out / "faults.png")
    window.close()
    result["closed"] = True
    return result


def scenario_undo_and_escape(out: Path, stage: str) -> dict:
    """Issue 54, findings 9 and 10: the W slider after Ctrl+Z, and Esc during a stroke over
    painted q (the window must show what the layer holds), with real events."""
    window = open_window(stage, str(out / "undo.usda"), size=(1000, 640))
    session = window.session
    result = {"w_before": session.control("width")}
    slider = window.width_slider
    # drag W's slider a quarter of its travel, as an artist does, and let go
    handle = slider.slider
    rect = handle.rect()
    x0 = rect.left() + rect.width() * handle.value() / 1000.0
    y = rect.center().y()
    mouse(handle, QtCore.QEvent.MouseButtonPress, x0, y)
    for step in range(1, 11):
        mouse(handle, QtCore.QEvent.MouseMove, x0 - step * rect.width() / 40.0, y,
              Qt.NoButton, Qt.LeftButton)
    mouse(handle, QtCore.QEvent.MouseButtonRelease, x0 - rect.width() / 4.0, y)
    settle(window)
    result["w_changed"] = session.control("width")
    key(window, Qt.Key_Z, Qt.ControlModifier)
    result["w_after_undo"] = session.control("width")
    result["slider_after_undo"] = slider.value()
    result["label_after_undo"] = slider.field.text()
    # a stroke, then a second one dropped with Esc halfway
    w, h = window.view.width(), window.view.height()
    drag(window, line((0.3 * w, 0.5 * h), (0.7 * w, 0.5 * h)))
    settle(window)
    first = window.view.last_frame.pixels.copy()
    view = window.view
    points = line((0.5 * w, 0.25 * h), (0.5 * w, 0.75 * h))
    mouse(view, QtCore.QEvent.MouseButtonPress, *points[0])
    for x, y in points[1:]:
        count = len(view.frame_times)
        mouse(view, QtCore.QEvent.MouseMove, x, y, Qt.NoButton, Qt.LeftButton)
        wait_for(lambda c=count: len(view.frame_times) > c, "a preview frame")
    result["stroke_shown"] = bool(session.stroking)
    QTest.keyClick(window.view, Qt.Key_Escape)
    mouse(view, QtCore.QEvent.MouseButtonRelease, *points[-1])
    settle(window)
    after = window.view.last_frame.pixels
    result["same_after_escape"] = bool(after.shape == first.shape and
                                       np.array_equal(after, first))
    result["undo_steps"] = len(session.undo_stack)
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_render_equal(out: Path, stage: str) -> dict:
    """Paint, save with Ctrl+S, and keep the widget's full-quality frames through the
    stage's camera at two frames, and at frame 24 with View > Relief (the test renders
    the saved layer and compares)."""
    layer = out / "equal.usda"
    window = open_window(stage, str(layer), size=(1000, 640))
    points, _ = upper_arm_stroke(window)
    drag(window, points)
    key(window, Qt.Key_S, Qt.ControlModifier)
    window.view_mode.setCurrentText("stage camera")
    frames = {}
    for frame in (24, 12):
        window.timeline.setValue(frame)
        settle(window)
        pixels = window.view.last_frame
        np.save(out / f"widget.{frame}.npy", pixels.pixels)
        frames[frame] = [pixels.width, pixels.height]
    window.timeline.setValue(24)
    window.actions_by_name["Relief"].trigger()
    settle(window)
    np.save(out / "widget.relief.24.npy", window.view.last_frame.pixels)
    screenshot(window, out / "relief.png")
    relief = {"checked": window.actions_by_name["Relief"].isChecked(),
              "size": [window.view.last_frame.width, window.view.last_frame.height]}
    q = window.session.mesh.q.copy()
    np.save(out / "q.npy", q)
    result = {"sizes": frames, "saved": layer.exists(), "dirty": window.session.dirty,
              "relief": relief, "errors": list(window.errors)}
    window.close()
    # reopen the saved layer, as the artist does the next day
    window = open_window(stage, str(layer), size=(600, 400))
    result["reopened_same_q"] = bool(np.array_equal(window.session.mesh.q, q))
    window.close()
    return result


def scenario_usdview(out: Path, stage: str) -> dict:
    """Wrinkles > Paint... in usdview's own process (a stand-in usdviewApi on an open
    stage): a stroke, Ctrl+S; the strokes are in usdview's session layer."""
    from types import SimpleNamespace

    from pxr import Usd

    from usdwrinkle import usdview

    held = Usd.Stage.Open(stage)
    status: list[str] = []
    api = SimpleNamespace(stage=held, frame=Usd.TimeCode(24), selectedPrims=[],
                          PrintStatus=status.append)
    window = usdview.paint_current_stage(api)
    window.confirm_close = lambda: "discard"
    window.resize(1200, 700)
    window.activateWindow()
    wait_for(lambda: window.view.last_frame is not None, "the first frame")
    wait_for(window.isActiveWindow, "the window to take the keyboard")
    settle(window)
    points, _ = upper_arm_stroke(window)
    drag(window, points)
    key(window, Qt.Key_S, Qt.ControlModifier)
    path = window.session.active
    spec = held.GetSessionLayer().GetPropertyAtPath(f"{path}.primvars:wrinkle:q")
    result = {"status": status, "in_session_layer": spec is not None,
              "root_dirty": held.GetRootLayer().dirty, "dirty": window.session.dirty,
              "frame": window.session.frame, "errors": list(window.errors)}
    window.close()
    return result


def scenario_close(out: Path, stage: str) -> dict:
    """Closing with an unsaved stroke asks first: Cancel keeps the window and the stroke,
    Save writes the layer and closes."""
    layer = out / "close.usda"
    window = open_window(stage, str(layer))
    points, _ = upper_arm_stroke(window)
    drag(window, points)
    asked = []
    window.confirm_close = lambda: asked.append("cancel") or "cancel"
    window.close()
    QtWidgets.QApplication.instance().processEvents()
    result = {"asked": list(asked), "open_after_cancel": window.isVisible(),
              "dirty_after_cancel": window.session.dirty, "saved_after_cancel": layer.exists(),
              "title_modified": window.isWindowModified()}
    window.confirm_close = lambda: asked.append("save") or "save"
    window.close()
    QtWidgets.QApplication.instance().processEvents()
    result.update({"asked": asked, "open_after_save": window.isVisible(),
                   "saved": layer.exists(), "errors": list(window.errors)})
    return result


def scenario_bench(out: Path, stage: str) -> dict:
    """The window's own latencies with a 960x540 view (benchmarks/paint.py runs it):
    frame intervals while dragging across the view's middle, release to the full-quality
    frame, and a move of the W slider to the frame that shows it."""
    all_meshes = os.environ.get("PAINT_BENCH_ALL_MESHES") == "1"
    window = open_window(stage, str(out / "bench.usda"), all_meshes=all_meshes)
    window.view.setFixedSize(960, 540)
    settle(window)
    view = window.view
    y = view.height() / 2
    points = line((view.width() * 0.1, y), (view.width() * 0.9, y), 40)
    mouse(view, QtCore.QEvent.MouseButtonPress, *points[0])
    gaps, last = [], time.perf_counter()
    for x, yy in points[1:]:
        count = len(view.frame_times)
        mouse(view, QtCore.QEvent.MouseMove, x, yy, Qt.NoButton, Qt.LeftButton)
        wait_for(lambda c=count: len(view.frame_times) > c, "a preview frame")
        now = time.perf_counter()
        gaps.append(now - last)
        last = now
    started = time.perf_counter()
    mouse(view, QtCore.QEvent.MouseButtonRelease, *points[-1])
    settle(window)
    release = time.perf_counter() - started
    slider = window.width_slider
    width = slider.value()
    moves = []
    for factor in (0.8, 0.64, 0.8, 1.0):
        count = len(view.frame_times)
        started = time.perf_counter()
        slider.slider.setSliderDown(True)
        slider.slider.setValue(slider._to_position(width * factor))
        wait_for(lambda c=count: len(view.frame_times) > c, "the W frame")
        moves.append(time.perf_counter() - started)
    slider.slider.setSliderDown(False)
    slider.slider.sliderReleased.emit()
    settle(window)
    frame = view.last_frame
    result = {"view": [frame.width, frame.height], "stroked": window.session.dirty,
              "drag_gaps": gaps[1:], "release": release, "width_moves": moves,
              "vertices": int(sum(m.count for m in window.session.meshes.values())),
              "errors": list(window.errors)}
    window.close()
    return result


def x_events(window, *args: str) -> None:
    """xdotool on this process's own window (real X events through the X server, as an
    artist's keyboard and mouse send them), then waited for until Qt has handled the
    events it sent (InputLog; ``expected_input``), and what they posted."""
    log = InputLog()
    try:
        x_events_only(*args)
        for kind, modifiers, count in expected_input(args):
            wait_for(lambda kind=kind, modifiers=modifiers, count=count:
                     log.count(kind, modifiers) >= count,
                     f"{count} {kind} event(s) from xdotool {' '.join(args)}", timeout=60.0)
        if args[0] == "windowfocus":
            wait_for(window.isActiveWindow, "the window to take the keyboard")
    finally:
        log.close()
    app = QtWidgets.QApplication.instance()
    for _ in range(3):  # what the handlers posted (zero timers, updates)
        app.processEvents(QtCore.QEventLoop.AllEvents, 50)
        time.sleep(0.01)


def expected_input(args) -> list[tuple]:
    """The input events an xdotool command line sends Qt: (kind, whether a modifier
    key's events count, how many). A key or a typed character is one release of a key
    that is not a modifier (Ctrl+Z's Z); keydown and keyup one press or release of that
    key, modifiers too; a button's down and up its press and release; a move alone a
    move (our calls always move the pointer somewhere it is not)."""
    ev = QtCore.QEvent
    command, operands = args[0], [a for a in args[1:] if not a.startswith("--")]
    if command == "key":
        return [(ev.KeyRelease, False, 1)]
    if command == "type":
        return [(ev.KeyRelease, False, len(operands[-1]))]
    if command == "keydown":
        return [(ev.KeyPress, True, 1)]
    if command == "keyup":
        return [(ev.KeyRelease, True, 1)]
    if command == "mouseup":
        return [(ev.MouseButtonRelease, True, 1)]
    if command == "mousedown":
        return [(ev.MouseButtonPress, True, 1)]
    if command == "mousemove":
        after = {"click": ev.MouseButtonRelease, "mousedown": ev.MouseButtonPress}
        follow = [after[a] for a in args if a in after]
        return [(follow[-1] if follow else ev.MouseMove, True, 1)]
    return []


def x_click(window, widget) -> None:
    """A real left click in the middle of ``widget``; on a combo box, waited for until
    its list has opened (the keys that follow go to the list)."""
    centre = widget.mapTo(window, QtCore.QPoint(widget.width() // 2, widget.height() // 2))
    x_events(window, "mousemove", "--window", str(int(window.winId())), str(centre.x()),
             str(centre.y()), "click", "1")
    if isinstance(widget, QtWidgets.QComboBox):
        wait_for(widget.view().isVisible, "the combo box's list to open")


def x_type(window, field, text: str) -> None:
    """Click into ``field``, select all, type ``text`` and press Enter (real X events)."""
    x_click(window, field)
    x_events(window, "key", "ctrl+a")
    x_events(window, "type", text)
    x_events(window, "key", "Return")


def scenario_help_and_typed(out: Path, stage: str) -> dict:
    """Issue 57: the help overlay (H, then ?, with real key events), its key list read
    from the widget; W = 0.05 and a strength typed into their fields; a word typed into
    a field; every control's tooltip."""
    window = open_window(stage, str(out / "typed.usda"), size=(1100, 640))
    session = window.session
    wid = str(int(window.winId()))
    x_events(window, "windowfocus", "--sync", wid)
    result = {"overlay_before": window.help_overlay.isVisible()}
    x_events(window, "key", "h")
    result["overlay_after_h"] = window.help_overlay.isVisible()
    result["listed"] = window.help_overlay.listed()
    screenshot(window, out / "help.png")
    x_events(window, "key", "question")
    result["overlay_after_question"] = window.help_overlay.isVisible()
    result["help_menu"] = [a.text().replace("&", "") for a in
                           window.menuBar().actions()[-1].menu().actions()]
    # W typed into its field: click, select all, type, Enter
    result["w_before"] = session.control("width")
    x_type(window, window.width_slider.field, "0.05")
    settle(window)
    result["w_control"] = session.control("width")
    result["w_engine"] = float(np.median(session.engine.meshes[session.active].params.width))
    result["w_field"] = window.width_slider.field.text()
    result["undo_steps_after_w"] = len(session.undo_stack)
    slider = window.width_slider
    result["w_slider_after_typed"] = [slider.low, slider.high, slider.slider.value()]
    # a 26 px drag of the W slider's handle (real X events): how much W changes
    handle = slider.slider.mapTo(window, QtCore.QPoint(slider.slider.width() // 2,
                                                       slider.slider.height() // 2))
    wid = str(int(window.winId()))
    x_events(window, "mousemove", "--window", wid, str(handle.x()), str(handle.y()),
             "mousedown", "1")
    x_events(window, "mousemove", "--window", wid, str(handle.x() + 26), str(handle.y()))
    x_events(window, "mouseup", "1")
    settle(window)
    result["w_after_drag"] = session.control("width")
    result["w_slider_after_drag"] = [slider.low, slider.high, slider.slider.value(),
                                     slider.slider.width()]
    result["undo_steps_after_drag"] = len(session.undo_stack)
    # a brush value, then a word
    x_type(window, window.strength.field, "0.8")
    result["strength"] = session.brush.strength
    x_type(window, window.amplitude.field, "lots")
    settle(window)
    result["amplitude_after_word"] = session.control("amplitude_scale")
    result["amplitude_field"] = window.amplitude.field.text()
    # a slack the session refuses (must be below 1): one line, the field back
    x_type(window, window.slack.field, "2")
    settle(window)
    result["slack_after_refusal"] = session.control("slack")
    result["slack_field"] = window.slack.field.text()
    # Esc while typing: the field goes back, nothing is taken, the focus leaves it
    amplitude_before = session.control("amplitude_scale")
    x_click(window, window.amplitude.field)
    x_events(window, "key", "ctrl+a")
    x_events(window, "type", "3.5")
    result["amplitude_field_typing"] = window.amplitude.field.text()
    x_events(window, "key", "Escape")
    settle(window)
    result["amplitude_field_after_esc"] = window.amplitude.field.text()
    result["amplitude_after_esc"] = [amplitude_before, session.control("amplitude_scale")]
    result["field_focus_after_esc"] = window.amplitude.field.hasFocus()
    result["errors"] = list(window.errors)
    result["tooltips"] = {name: widget.toolTip() for name, widget in window._tipped().items()}
    result["tooltips"]["play"] = window.play_button.toolTip()
    result["tooltips"]["timeline"] = window.timeline.toolTip()
    window.close()
    return result


class InputLog(QtCore.QObject):
    """The input events Qt has handled since it was made (an application-wide event
    filter): what the x_ helpers wait for after each xdotool call, instead of a fixed
    half second. Qt offers one event to every widget up the parent chain, and a window's
    event again to the widget under it, so each is kept once, by its kind, X timestamp
    and key or button. ``view``: keep only the mouse events that reach it, with their
    view pixel (x_drag)."""

    KEYS = (QtCore.QEvent.KeyPress, QtCore.QEvent.KeyRelease)
    MOUSE = (QtCore.QEvent.MouseMove, QtCore.QEvent.MouseButtonPress,
             QtCore.QEvent.MouseButtonRelease)
    MODIFIERS = (Qt.Key_Shift, Qt.Key_Control, Qt.Key_Alt, Qt.Key_Meta, Qt.Key_AltGr)

    def __init__(self, view=None):
        super().__init__()
        self.view, self.events, self.seen = view, [], set()
        QtWidgets.QApplication.instance().installEventFilter(self)

    def eventFilter(self, obj, event):  # noqa: N802
        kind = event.type()
        if self.view is not None:
            if obj is self.view and kind in self.MOUSE:
                position = event.position()
                self.events.append((kind, round(position.x()), round(position.y())))
        elif kind in self.MOUSE or kind in self.KEYS:
            detail = event.key() if kind in self.KEYS else event.button()
            identity = (kind, event.timestamp(), detail)
            if identity not in self.seen:
                self.seen.add(identity)
                self.events.append((kind, detail))
        return False

    def count(self, kind, modifiers: bool = True) -> int:
        """How many ``kind`` events came; ``modifiers`` False: not counting the key
        events of Shift, Ctrl, Alt and Meta."""
        return sum(1 for e in self.events
                   if e[0] == kind and (modifiers or e[1] not in self.MODIFIERS))

    def close(self) -> None:
        QtWidgets.QApplication.instance().removeEventFilter(self)


def x_drag(window, points, hold=None) -> dict:
    """A left-button drag through widget pixels ``points`` with real X events (xdotool:
    press, moves, release), each waited for until the view has handled it; ``hold(k)``
    runs after the k-th move, the button still down. Returns what ``hold`` returned, by
    move."""
    wid = str(int(window.winId()))
    origin = window.view.mapTo(window, QtCore.QPoint(0, 0))
    seen = {}
    log = InputLog(window.view)

    def pixel(x, y):
        """The view pixel the pointer lands on for widget point (x, y)."""
        return int(round(x)), int(round(y))

    def at(x, y):
        """xdotool's window coordinates of that pixel."""
        px, py = pixel(x, y)
        return str(origin.x() + px), str(origin.y() + py)

    def sent(kind, x=None, y=None) -> None:
        """Wait until the view has handled a ``kind`` event (at view pixel x, y)."""
        def arrived():
            return any(e[0] == kind and (x is None or (e[1], e[2]) == (x, y))
                       for e in log.events)
        wait_for(arrived, f"the view to get {kind} at {x}, {y}", timeout=60.0)
        log.events.clear()

    try:
        # a pixel beside the first point, then onto it: a move that surely moves
        x0, y0 = points[0]
        x_events_only("mousemove", "--window", wid, *at(x0 + 1, y0))
        x_events_only("mousemove", "--window", wid, *at(x0, y0))
        first = pixel(x0, y0)
        sent(QtCore.QEvent.MouseMove, *first)
        x_events_only("mousedown", "1")
        sent(QtCore.QEvent.MouseButtonPress)
        last = first
        for k, (x, y) in enumerate(points[1:], 1):
            x_events_only("mousemove", "--window", wid, *at(x, y))
            target = pixel(x, y)
            if target != last:  # a move to where the pointer is sends nothing
                sent(QtCore.QEvent.MouseMove, *target)
            last = target
            if hold is not None:
                seen[k] = hold(k)
        x_events_only("mouseup", "1")
        sent(QtCore.QEvent.MouseButtonRelease)
    finally:
        log.close()
    settle(window)
    return seen


def x_events_only(*args: str) -> None:
    """xdotool, without waiting for Qt to handle what it sent (the caller waits)."""
    import subprocess

    subprocess.run(["xdotool", *args], check=True, timeout=60, capture_output=True)


def scenario_big_brush(out: Path, stage: str) -> dict:
    """Issue 57: with a huge brush (radius 6, typed) a short drag did nothing and showed
    no outline. With real X events: an 80 px comb drag over the shirt at radius 6 paints
    (one undo step), the outline stays drawn while the button is down with an arrow
    along the drag; a drag over the empty background paints nothing and says so in the
    status bar."""
    window = open_window(stage, str(out / "big.usda"), size=(1100, 640))
    session, view = window.session, window.view
    x_events(window, "windowfocus", "--sync", str(int(window.winId())))
    x_type(window, window.radius.field, "6")
    settle(window)
    result = {"radius": session.brush.radius, "mode": session.brush.mode}
    points, _ = upper_arm_stroke(window)
    start = np.asarray(points[len(points) // 2])
    drag_points = [tuple(start + [k * 10.0, 0.0]) for k in range(9)]  # 80 px
    before = session.mesh.q.copy()

    def outline(k):
        view.repaint()  # the overlay as the next paint draws it
        if k == 4:
            screenshot(window, out / "big_brush_drag.png")
        drawn = view.outline
        if drawn is None:
            return None
        return {"painting": drawn["painting"],
                "tip": None if drawn["tip"] is None else [float(v) for v in drawn["tip"]],
                "ring_px": float(np.ptp(drawn["ring"][:, 0]))}

    seen = x_drag(window, drag_points, hold=outline)
    amount = np.linalg.norm(session.mesh.q - before, axis=1)
    result.update({"outlines": seen, "cursor": [float(v) for v in drag_points[-1]],
                   "changed_points": int(np.sum(amount > 1e-6)),
                   "undo_steps": len(session.undo_stack),
                   "stamps": len(session.stamp_centres)})
    screenshot(window, out / "big_brush.png")
    # the background: the window's top-left corner, far from the shirt
    q_before = session.mesh.q.copy()
    x_drag(window, [(12.0 + k * 10.0, 12.0) for k in range(9)])
    result["missed_message"] = window.statusBar().currentMessage()
    result["missed_changed"] = bool(not np.array_equal(q_before, session.mesh.q))
    result["undo_steps_after_miss"] = len(session.undo_stack)
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_modifiers(out: Path, stage: str) -> dict:
    """Issue 57: Shift smooths and Ctrl erases while held. With real X events: a comb
    stroke along the upper arm, then a short drag across it with Shift held, and the same
    drag in the smooth mode (each from the same state: Ctrl+Z between); the same with
    Ctrl and the erase mode. Returns the q arrays' differences."""
    window = open_window(stage, str(out / "modifiers.usda"), size=(1100, 640))
    session = window.session
    wid = str(int(window.winId()))
    x_events(window, "windowfocus", "--sync", wid)
    points, _ = upper_arm_stroke(window)
    x_drag(window, points[::3])
    combed = session.mesh.q.copy()
    middle = np.asarray(points[len(points) // 2])
    across = [tuple(middle + [0.0, dy]) for dy in range(-40, 41, 8)]
    result = {"combed": float(np.linalg.norm(combed, axis=1).max())}

    def stroke(modifier=None, mode=None) -> np.ndarray:
        if mode is not None:
            window.mode.setCurrentText(mode)
        if modifier is not None:
            x_events(window, "keydown", modifier)
        x_drag(window, across)
        if modifier is not None:
            x_events(window, "keyup", modifier)
        q = session.mesh.q.copy()
        x_events(window, "key", "ctrl+z")
        settle(window)
        result.setdefault("restored", []).append(bool(np.array_equal(session.mesh.q, combed)))
        window.mode.setCurrentText("comb")
        return q

    for modifier, mode in (("shift", "smooth"), ("ctrl", "erase")):
        held, chosen = stroke(modifier=modifier), stroke(mode=mode)
        result[mode] = {"held_vs_mode": float(np.abs(held - chosen).max()),
                        "changed": float(np.abs(held - combed).max()),
                        "amount_after": float(np.linalg.norm(held, axis=1).sum()
                                              / max(np.linalg.norm(combed, axis=1).sum(),
                                                    1e-12))}
    result["mode_after"] = session.brush.mode
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_resize(out: Path, stage: str) -> dict:
    """Issue 57: B + left drag resizes the brush (real X events: B held, a 100 px drag to
    the right over the shirt); the outline drawn at the drag's start grows with it. Then
    a plain drag still paints, and q is untouched by the resize."""
    window = open_window(stage, str(out / "resize.usda"), size=(1100, 640))
    session, view = window.session, window.view
    x_events(window, "windowfocus", "--sync", str(int(window.winId())))
    points, _ = upper_arm_stroke(window)
    start = np.asarray(points[len(points) // 2])
    before_q = session.mesh.q.copy()
    result = {"radius_before": session.brush.radius}

    def outline(k):
        # an outline painted since the radius changed: repaint() need not paint at once
        # under Xvfb, and the last outline then stood for this move (two equal sizes)
        view.outline = None
        view.repaint()
        try:
            wait_for(lambda: view.outline is not None, "the outline painted", timeout=10.0)
        except TimeoutError:
            return None
        return float(np.ptp(view.outline["ring"][:, 0]))

    x_events(window, "keydown", "b")
    seen = x_drag(window, [tuple(start + [dx, 0.0]) for dx in range(0, 101, 20)],
                  hold=outline)
    x_events(window, "keyup", "b")
    result.update({"radius_after": session.brush.radius, "outline_px": seen,
                   "field": window.radius.field.text(),
                   "q_untouched": bool(np.array_equal(before_q, session.mesh.q)),
                   "undo_steps": len(session.undo_stack)})
    x_drag(window, [tuple(start + [dx, 0.0]) for dx in range(0, 41, 8)])
    result["painted_after"] = bool(not np.array_equal(before_q, session.mesh.q))
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_follow(out: Path, stage: str) -> dict:
    """Issue 57: the view stayed framed on the opening frame while the timeline played.
    ``stage``: a sheet that travels across the frames (the test writes it). The timeline
    played with Space (real X key events) over every frame, with View > Follow the mesh
    off and then on: per drawn frame, the share of the mesh's points inside the view."""
    from usdwrinkle.brush.view import project

    window = open_window(stage, str(out / "follow.usda"), size=(1000, 600))
    session, view = window.session, window.view
    x_events(window, "windowfocus", "--sync", str(int(window.winId())))
    frames = range(window.timeline.minimum(), window.timeline.maximum() + 1)

    def inside() -> dict:
        shares = {}

        def record():
            frame = view.last_frame
            if frame is None or frame.frame in shares:
                return False
            points = session.engine.posed_points(session.active)
            xy, front = project(frame.camera, points, frame.width, frame.height)
            shares[frame.frame] = float(np.mean(front & (xy[:, 0] >= 0) & (xy[:, 1] >= 0) &
                                                (xy[:, 0] <= frame.width) &
                                                (xy[:, 1] <= frame.height)))
            return len(shares) == len(frames)

        window.timeline.setValue(window.timeline.maximum())
        settle(window)
        x_events(window, "key", "space")  # play
        wait_for(record, "every frame drawn while playing", timeout=240)
        x_events(window, "key", "space")  # stop
        settle(window)
        return shares

    result = {"off": inside()}
    window.actions_by_name["Follow the mesh"].trigger()
    result["follow_checked"] = window.actions_by_name["Follow the mesh"].isChecked()
    result["on"] = inside()
    result["errors"] = list(window.errors)
    window.close()
    return result


def tablet(widget, kind, x: float, y: float, pressure: float, buttons) -> bool:
    """A QTabletEvent from a pen (synthesized: Xvfb has no tablet), through the
    application's event dispatch; whether the widget accepted it."""
    pen = tablet.device = getattr(tablet, "device", None) or QtGui.QPointingDevice(
        "test pen", 4242, QtGui.QInputDevice.DeviceType.Stylus,
        QtGui.QPointingDevice.PointerType.Pen,
        QtGui.QInputDevice.Capability.Position | QtGui.QInputDevice.Capability.Pressure,
        1, 3)
    local = QtCore.QPointF(x, y)
    button = Qt.NoButton if kind == QtCore.QEvent.TabletMove else Qt.LeftButton
    event = QtGui.QTabletEvent(kind, pen, local, widget.mapToGlobal(local), pressure, 0.0,
                               0.0, 0.0, 0.0, 0.0, Qt.NoModifier, button, buttons)
    QtWidgets.QApplication.sendEvent(widget, event)
    QtWidgets.QApplication.instance().processEvents()
    return event.isAccepted()


def scenario_tablet(out: Path, stage: str) -> dict:
    """Issue 57: pen pressure was in the code but untested. A comb stroke along the upper
    arm (mouse), then a pen tap (press, release) in the erase mode at pressure 0.2 and,
    from the same state (Ctrl+Z between), at 1.0: what each tap took from q. A mouse tap
    after the pen paints at full strength again."""
    window = open_window(stage, str(out / "tablet.usda"), size=(1100, 640))
    session, view = window.session, window.view
    points, _ = upper_arm_stroke(window)
    drag(window, points[::3])
    combed = session.mesh.q.astype(np.float64)
    window.mode.setCurrentText("erase")
    x, y = points[len(points) // 2]
    taken, accepted = {}, []
    for pressure in (0.2, 1.0):
        accepted.append(tablet(view, QtCore.QEvent.TabletPress, x, y, pressure,
                               Qt.LeftButton))
        accepted.append(tablet(view, QtCore.QEvent.TabletRelease, x, y, pressure,
                               Qt.NoButton))
        settle(window)
        taken[str(pressure)] = (combed - session.mesh.q).tolist()
        key(window, Qt.Key_Z, Qt.ControlModifier)
    result = {"accepted": accepted, "taken": taken, "strength": session.brush.strength,
              "restored": bool(np.array_equal(session.mesh.q, combed.astype(np.float32)))}
    # a mouse tap after the pen: the pressure is the mouse's (1) again
    mouse(view, QtCore.QEvent.MouseButtonPress, x, y)
    mouse(view, QtCore.QEvent.MouseButtonRelease, x, y)
    settle(window)
    result["mouse_taken"] = (combed - session.mesh.q).tolist()
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_display(out: Path, stage: str) -> dict:
    """Issue 57: nothing showed what is painted. A comb stroke along the upper arm, then
    View > Display > Painted amount and Painted W: the drawn frame's colour (saturation
    and hue) at the front-facing points painted at |q| > 0.5 and at those left unpainted,
    in each display; screenshots."""
    from usdwrinkle.brush.view import project

    window = open_window(stage, str(out / "display.usda"), size=(1100, 640))
    session, view = window.session, window.view
    points, _ = upper_arm_stroke(window)
    drag(window, points[::3])
    path = session.active
    amount = np.linalg.norm(session.mesh.q, axis=1)

    def colours() -> dict:
        frame = view.last_frame
        rgb = frame.pixels[..., :3].astype(np.float64) / 255.0
        xy, front = project(frame.camera, session.posed_points(path), frame.width,
                            frame.height)
        facing = session.facing(path) & front
        col = np.clip(np.round(xy[:, 0]).astype(int), 0, frame.width - 1)
        row = np.clip(np.round(xy[:, 1]).astype(int), 0, frame.height - 1)
        seen = {}
        for name, chosen in (("painted", facing & (amount > 0.5)),
                             ("unpainted", facing & (amount == 0.0))):
            samples = rgb[row[chosen], col[chosen]]
            saturation = (samples.max(axis=1) - samples.min(axis=1)) / \
                np.maximum(samples.max(axis=1), 1e-6)
            seen[name] = {"count": int(chosen.sum()),
                          "saturation": float(np.median(saturation)),
                          "rgb": np.median(samples, axis=0).tolist()}
        return seen

    result = {"shaded": colours()}
    for name in ("amount", "width"):
        window.display_actions[name].trigger()
        settle(window)
        result[name] = colours()
        result[name + "_checked"] = window.display_actions[name].isChecked()
        screenshot(window, out / f"display_{name}.png")
    window.display_actions["shaded"].trigger()
    settle(window)
    result["shaded_again"] = colours()
    result["errors"] = list(window.errors)
    window.close()
    return result


def scenario_presets(out: Path, stage: str) -> dict:
    """Issue 57: brush presets. With real X events: the brush set (smooth, linear,
    radius 0.2 and strength 0.8 typed), Save... clicked (the name answered), the brush
    changed, then the preset chosen from its list (click, Down, Enter): the brush's
    values before and after. Then a preset file with one bad entry: a window opened on it
    lists the good one and says the bad one in one line."""
    import json as json_module

    window = open_window(stage, str(out / "presets.usda"), size=(1100, 640))
    session = window.session
    x_events(window, "windowfocus", "--sync", str(int(window.winId())))
    window.mode.setCurrentText("smooth")
    window.falloff.setCurrentText("linear")
    x_type(window, window.radius.field, "0.2")
    x_type(window, window.strength.field, "0.8")
    saved = dataclasses_dict(session.brush)
    window.ask_preset_name = lambda: "soft smooth"
    x_click(window, window.save_preset_button)
    result = {"saved": saved, "file": json_module.loads(
        (out / "config" / "brushes.json").read_text()),
        "listed_after_save": [window.preset.itemText(i) for i in range(window.preset.count())]}
    window.mode.setCurrentText("comb")
    x_type(window, window.radius.field, "0.5")
    x_type(window, window.strength.field, "0.3")
    result["changed"] = dataclasses_dict(session.brush)
    window.preset.setCurrentIndex(0)
    x_click(window, window.preset)
    x_events(window, "key", "Down")
    x_events(window, "key", "Return")
    result["chosen"] = dataclasses_dict(session.brush)
    result["controls"] = {"mode": window.mode.currentText(),
                          "falloff": window.falloff.currentText(),
                          "radius": window.radius.field.text(),
                          "strength": window.strength.field.text()}
    result["errors"] = list(window.errors)
    # a second preset, then deleted again (Delete clicked with it shown)
    window.ask_preset_name = lambda: "to go"
    x_click(window, window.save_preset_button)
    result["listed_with_second"] = [window.preset.itemText(i)
                                    for i in range(window.preset.count())]
    x_click(window, window.delete_preset_button)
    result["listed_after_delete"] = [window.preset.itemText(i)
                                     for i in range(window.preset.count())]
    result["file_after_delete"] = sorted(json_module.loads(
        (out / "config" / "brushes.json").read_text())["presets"])
    window.close()
    # a file with a bad preset beside the good one
    data = json_module.loads((out / "config" / "brushes.json").read_text())
    data["presets"]["broken"] = {**data["presets"]["soft smooth"], "radius": -1.0}
    (out / "config" / "brushes.json").write_text(json_module.dumps(data))
    window = open_window(stage, str(out / "presets2.usda"), size=(1100, 640))
    result["listed_with_broken"] = [window.preset.itemText(i)
                                    for i in range(window.preset.count())]
    result["errors_with_broken"] = list(window.errors)
    window.close()
    return result


def scenario_open(out: Path, stage: str) -> dict:
    """Issue 57: no File > Open, no recent files, Save As in the current folder. ``stage``:
    a second stage to open (the test writes it). With the shirt painted (unsaved):
    Ctrl+O (a real key) answered with the second stage, the unsaved question cancelled,
    then discarded; a stroke on the second stage; File > Open Recent's entries; the shirt
    again from it; where Save As starts."""
    shirt = str(SHIRT)
    window = open_window(shirt, str(out / "first.usda"), size=(1000, 600))
    x_events(window, "windowfocus", "--sync", str(int(window.winId())))
    points, _ = upper_arm_stroke(window)
    drag(window, points[::3])
    asked = []
    window.ask_open_path = lambda start: asked.append(start) or stage
    window.confirm_close = lambda: "cancel"
    x_events(window, "key", "ctrl+o")
    result = {"open_started_in": asked[-1],
              "after_cancel": window.stage_path,
              "dirty_after_cancel": window.session.dirty}
    window.confirm_close = lambda: "discard"
    x_events(window, "key", "ctrl+o")
    settle(window)
    session = window.session
    result.update({"after_open": window.stage_path,
                   "root_after_open": session.stage.GetRootLayer().realPath,
                   "paths": list(session.paths), "title": window.windowTitle(),
                   "dirty_after_open": session.dirty,
                   "timeline": [window.timeline.minimum(), window.timeline.maximum()]})
    # a stroke on the new stage: across the view's middle
    w, h = window.view.width(), window.view.height()
    before = session.mesh.q.copy()
    drag(window, line((0.35 * w, 0.5 * h), (0.65 * w, 0.5 * h), 12))
    result["painted_new"] = bool(not np.array_equal(before, session.mesh.q))
    window._fill_recent()
    result["recent"] = [a.text() for a in window.recent_menu.actions()]
    starts = []
    window.ask_save_path = lambda start: starts.append(start) or None
    window.save_as()
    result["save_as_started_at"] = starts[-1]
    shirt_entry = next(a for a in window.recent_menu.actions() if a.text() == shirt)
    shirt_entry.trigger()
    settle(window)
    result["after_recent"] = window.stage_path
    result["paths_after_recent"] = list(window.session.paths)
    result["errors"] = list(window.errors)
    # a file that is not a stage, and a stage with nothing to paint: one line each, and
    # the window keeps the shirt
    not_usd = out / "notes.usda"
    not_usd.write_text("these are not USD")
    plain = out / "plain.usda"
    plain.write_text('#usda 1.0\n\ndef Mesh "M"\n{\n    point3f[] points = [(0, 0, 0)]\n}\n')
    result["refused"] = [window.open_stage(str(not_usd)), window.open_stage(str(plain))]
    result["errors_after_refused"] = list(window.errors)
    result["after_refused"] = window.stage_path
    result["paths_after_refused"] = list(window.session.paths)
    window.close()
    return result


def dataclasses_dict(brush) -> dict:
    import dataclasses

    return dataclasses.asdict(brush)


def scenario_figures(out: Path, stage: str) -> dict:
    """The README's screenshots (python tests/paint_driver.py figures docs/images, under
    xvfb-run): the window before and after a comb stroke along the shirt's upper arm,
    q shown as segments; the painted amount display; the keys overlay (H)."""
    window = open_window(stage, str(out / "paint_figures.usda"), size=(1100, 620))
    screenshot(window, out / "paint_before.png")
    points, _ = upper_arm_stroke(window)
    drag(window, points)
    window.show_q.setChecked(True)
    window.view.cursor_pos = QtCore.QPointF(*points[len(points) // 2])
    settle(window)
    screenshot(window, out / "paint_after.png")
    window.show_q.setChecked(False)
    window.display_actions["amount"].trigger()
    settle(window)
    screenshot(window, out / "paint_amount.png")
    # W painted at twice the mesh's over the forearm's front, shown on its ramp
    from dataclasses import replace

    window.mode.setCurrentText("width")
    session = window.session
    session.brush = replace(session.brush, width=2.0 * session.control("width"))
    rest = session.mesh.rest_points
    fore = view_pixels(window, session.active, session.facing(session.active) &
                       (rest[:, 0] > 1.4) & (rest[:, 0] < 1.8))
    drag(window, line(fore - [0, 60], fore + [0, 60], 12))
    window.display_actions["width"].trigger()
    settle(window)
    screenshot(window, out / "paint_width.png")
    window.mode.setCurrentText("comb")
    window.display_actions["shaded"].trigger()
    window.view.cursor_pos = None
    window.toggle_help()
    settle(window)
    screenshot(window, out / "paint_help.png")
    while window.session.dirty and window.session.undo() is not None:
        pass
    window.close()
    (out / "paint_figures.usda").unlink(missing_ok=True)
    return {"written": ["paint_before.png", "paint_after.png", "paint_amount.png",
                        "paint_width.png", "paint_help.png"]}


def main(argv: list[str]) -> int:
    scenario, out = argv[0], Path(argv[1])
    stage = argv[2] if len(argv) > 2 else str(SHIRT)
    out.mkdir(parents=True, exist_ok=True)
    # brush presets from a folder of the test's own, never the user's config; the
    # figures' folder holds the README's images only
    os.environ["USDWRINKLE_CONFIG_DIR"] = (tempfile.mkdtemp(prefix="usdwrinkle-config-")
                                           if scenario == "figures" else str(out / "config"))
    app = application()
    result = globals()[f"scenario_{scenario}"](out, stage)
    if scenario != "figures":  # the figures' folder holds the README's images only
        (out / "result.json").write_text(json.dumps(result, indent=1, default=float))
    app.processEvents()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
