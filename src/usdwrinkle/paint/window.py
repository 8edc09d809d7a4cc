"""The paint window (PySide6): the engine's own frame in a QOpenGLWidget, a brush on the
surface, live controls, a timeline. Every Qt override and slot runs through
:func:`guarded`, so a Python error becomes a message in the window, never a dead process
(PySide6 6.12 aborts on an exception that leaves an override).

Mouse (usdview and Maya): left button paints; Alt+left tumbles, middle (or Alt+middle)
tracks, right (or Alt+right) and the wheel dolly. Keys: Ctrl+S save, Ctrl+Shift+S save
as, Ctrl+Z undo, Ctrl+Shift+Z redo, F frames the meshes, [ and ] the radius, Esc drops
the stroke in progress, Space plays, H or ? shows these (BINDINGS, the Help menu).
"""
from __future__ import annotations

import functools
import os
import signal
import time
import traceback

import numpy as np

try:
    from PySide6 import QtCore, QtGui, QtWidgets
    from PySide6.QtOpenGLWidgets import QOpenGLWidget
except ImportError as exc:  # the optional extra
    from ..process.errors import UsdWrinkleError

    raise UsdWrinkleError("the paint window needs PySide6: pip install 'usdwrinkle[paint]' "
                          f"({exc})") from None

from ..app.paint_session import CLOTH_PRESETS, CONTROLS, FULL, PREVIEW, PaintSession
from ..brush.stamp import FALLOFFS, MIRROR_AXES, MODES
from ..brush.view import project
from ..process.timecode import format_frame

Qt = QtCore.Qt

#: the view's background (linear grey, under the frame's alpha), as usdview's
BACKGROUND = (0.18, 0.18, 0.2)

#: the W slider spans the current W divided and multiplied by this (log scale)
W_SPAN = 2.0

#: B + left drag resizes the brush (Maya's B): this many pixels to the right double it
RESIZE_PIXELS = 100.0

#: the keys and mouse bindings, as the Help menu and the H overlay list them
BINDINGS = (
    ("Left drag", "paint with the brush"),
    ("Shift+left drag", "smooth, whatever the brush's mode"),
    ("Ctrl+left drag", "erase, whatever the brush's mode"),
    ("Alt+left drag", "tumble the view"),
    ("Middle drag", "track the view (also Alt+middle)"),
    ("Right drag, wheel", "dolly the view (also Alt+right)"),
    ("[ and ]", "a smaller and a larger brush"),
    ("B + left drag", "resize the brush (100 px to the right doubles it)"),
    ("Esc", "drop the stroke in progress"),
    ("F", "frame the meshes"),
    ("Space", "play or stop the timeline"),
    ("Ctrl+Z", "undo"),
    ("Ctrl+Shift+Z", "redo"),
    ("Ctrl+O", "open another stage (File > Open Recent lists the last ones)"),
    ("Ctrl+S", "save"),
    ("Ctrl+Shift+S", "save as"),
    ("Ctrl+W", "close (asks about unsaved strokes)"),
    ("H or ?", "show or hide this list"),
    ("a value field", "type a value and press Enter (Esc puts it back)"),
)

#: each control's tooltip
TIPS = {
    "mode": "What a stroke paints: comb lays the wrinkle vector q along the stroke (folds "
            "across it), smooth averages q, erase removes it (Comb's lift), width paints W, "
            "attract turns q towards the stroke keeping its amount",
    "falloff": "How a stamp fades from its centre to the brush's edge: sphere acts on "
               "nearly the whole width, smooth on its middle, constant evenly",
    "mirror": "Paint the mirror image too, through the rest pose's plane at 0 on this axis",
    "radius": "The brush's radius in the mesh's rest units ([ and ] change it)",
    "strength": "How far one stamp moves the painted value towards its target (0 to 1)",
    "amount": "How strongly comb gathers the cloth: |q| from 0 (no fold) to 1 (folds that "
              "take up half the length); more amount gives deeper folds, not finer ones",
    "geodesic": "Measure the brush's reach along the surface (on), or straight through "
                "space (off: a stroke on one arm may reach the other)",
    "front_only": "Paint only what faces the camera",
    "flood": "Apply the brush's mode to every vertex of the active mesh (one undo step)",
    "show_q": "Draw the painted wrinkle vectors as short segments",
    "preset": "Brush presets: choose one to take its mode, falloff, size, strength, amount "
              "and the rest (kept in your config folder, for every window)",
    "save_preset": "Save the brush as it is now under a name (the same name replaces it)",
    "delete_preset": "Delete the preset shown in the list (the brush stays as it is)",
    "width": "W, the wrinkle width (rest wavelength) of the active mesh, in scene units; "
             "width mode paints this value",
    "amplitude": "wrinkle:amplitudeScale: scales every fold's height (1 is the fold law's)",
    "slack": "wrinkle:slack: the compression before the crests settle (folds are drawn "
             "from 0.6 of it on)",
    "irregularity": "wrinkle:irregularity: how unequal the folds are (0: regular waves; "
                    "about 0.3 in simulated cloth): their crests meander and the wider "
                    "ones stand taller",
    "cloth": "Set W from a cloth preset's fold width through the stage's metersPerUnit",
    "view": "Orbit with the mouse, or look through the stage's camera",
    "play": "Play the timeline (Space)",
    "timeline": "The frame shown and painted on",
}


class FaultPoints:
    """A debug handle for the tests (tests/paint_driver.py): ``arm(name)`` makes the next
    ``trip(name)`` raise, once, where the window calls it (paintGL "paint", a stroke's
    press "brush", save "save"), so that a test sees the window show the error and go on.
    Nothing arms it outside the tests."""

    #: point -> where it is, as the error says
    POINTS = {"paint": "paintGL", "brush": "the brush", "save": "save"}

    def __init__(self) -> None:
        self.armed: str | None = None

    def arm(self, name: str) -> None:
        if name not in self.POINTS:
            raise ValueError(f"no fault point {name!r} (one of {', '.join(self.POINTS)})")
        self.armed = name

    def trip(self, name: str) -> None:
        if self.armed == name:
            self.armed = None
            raise RuntimeError(f"injected fault in {self.POINTS[name]}")


def guarded(method):
    """Run a Qt override or slot; an exception is shown in the window (and logged),
    and the window goes on."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        try:
            return method(self, *args, **kwargs)
        except Exception as exc:  # noqa: BLE001 (a Qt override must never raise)
            owner = self if hasattr(self, "show_error") else getattr(self, "owner", None)
            text = exc.one_line() if hasattr(exc, "one_line") else f"{type(exc).__name__}: {exc}"
            detail = traceback.format_exc()
            # the traceback's frames hold the Qt objects of the override's call: let them go
            # now (kept, they outlive the GL context and crash the interpreter's exit)
            traceback.clear_frames(exc.__traceback__)
            exc.__traceback__ = None
            if owner is not None:
                owner.show_error(text, detail)
            return None

    return wrapper


_QUAD_VERTEX = """
#version 330
out vec2 uv;
void main() {
    vec2 corner = vec2(float(gl_VertexID & 1), float((gl_VertexID >> 1) & 1));
    uv = vec2(corner.x, 1.0 - corner.y);  // the frame's row 0 is its top
    gl_Position = vec4(corner * 2.0 - 1.0, 0.0, 1.0);
}
"""
_QUAD_FRAGMENT = """
#version 330
uniform sampler2D frame;
uniform vec3 background;
in vec2 uv;
out vec4 colour;
void main() {
    vec4 c = texture(frame, uv);  // sRGB codes, straight alpha, as the PNG holds them
    colour = vec4(mix(background, c.rgb, c.a), 1.0);
}
"""


class PaintView(QOpenGLWidget):
    """The engine draws into this widget's own GL context (moderngl attaches to it in
    initializeGL): the frame is resolved to the codes ``usdwrinkle render`` writes and
    shown, then the brush outline and q are drawn over it."""

    def __init__(self, owner: PaintWindow, make_session):
        super().__init__()
        self.owner = owner
        self._make_session = make_session
        self.session: PaintSession | None = None
        self.ctx = None
        self.setMouseTracking(True)
        self.setFocusPolicy(Qt.StrongFocus)
        self.setMinimumSize(320, 180)
        self.cursor_pos: QtCore.QPointF | None = None
        self.pressure = 1.0
        self.show_q = False
        self.interacting = False  # a stroke or a live slider: draw the preview
        self.last_frame = None
        self._drag = None
        #: the drag's direction on screen (unit, widget pixels), while painting
        self.drag_direction: np.ndarray | None = None
        #: a pen's event is being handled (tabletEvent), not the mouse's
        self._pen = False
        #: B is held: a left drag resizes the brush instead of painting
        self.resize_key = False
        #: the brush mode of the stroke in progress where a modifier overrides it
        self.stroke_mode: str | None = None
        #: the brush outline last drawn (_draw_outline), None where none was
        self.outline: dict | None = None
        self._texture = None
        self._program = None
        self._vao = None
        #: the tests' debug handle: a fault armed there raises at its point
        self.faults = FaultPoints()
        self.frame_times: list[float] = []

    # -- GL ---------------------------------------------------------------------------
    @guarded
    def initializeGL(self):  # noqa: N802 (Qt naming)
        import moderngl

        self.ctx = moderngl.create_context(require=430)
        self._program = self.ctx.program(vertex_shader=_QUAD_VERTEX,
                                         fragment_shader=_QUAD_FRAGMENT)
        self._vao = self.ctx.vertex_array(self._program, [])
        if self.session is None:
            self.session = self._make_session(self.ctx)
            self.owner.session_ready(self.session)

    def release(self) -> None:
        """Free the engine and the view's GL objects in their own context (before Qt
        destroys it: freed after, they crash the process)."""
        if self.ctx is None:
            return
        self.makeCurrent()
        try:
            if self.session is not None:
                self.session.release()
                self.session = None
            for item in (self._texture, self._vao, self._program):
                if item is not None:
                    item.release()
            self._texture = self._vao = self._program = None
        finally:
            self.doneCurrent()
            self.ctx = None

    def gl_size(self) -> tuple[int, int]:
        ratio = self.devicePixelRatioF()
        return max(1, int(self.width() * ratio)), max(1, int(self.height() * ratio))

    @guarded
    def paintGL(self):  # noqa: N802
        self.faults.trip("paint")
        if self.session is None or self.ctx is None:
            return
        started = time.perf_counter()
        width, height = self.gl_size()
        quality = PREVIEW if self.interacting else FULL
        frame = self.session.render(width, height, quality)
        self.last_frame = frame
        self._show(frame, width, height)
        self.frame_times.append(time.perf_counter() - started)
        self.owner.frame_drawn(frame)
        self._overlay()

    def _show(self, frame, width: int, height: int) -> None:
        import moderngl

        ctx = self.ctx
        if self._texture is None or self._texture.size != (frame.width, frame.height):
            if self._texture is not None:
                self._texture.release()
            self._texture = ctx.texture((frame.width, frame.height), 4, dtype="f1")
            self._texture.filter = (moderngl.LINEAR, moderngl.LINEAR)
        self._texture.write(np.ascontiguousarray(frame.pixels).tobytes())
        target = ctx.detect_framebuffer(self.defaultFramebufferObject())
        target.use()
        ctx.viewport = (0, 0, width, height)
        ctx.disable(moderngl.DEPTH_TEST | moderngl.BLEND | moderngl.CULL_FACE)
        ctx.scissor = None
        self._texture.use(0)
        self._program["frame"] = 0
        self._program["background"] = BACKGROUND
        self._vao.render(moderngl.TRIANGLE_STRIP, vertices=4)

    def _overlay(self) -> None:
        """The brush outline on the surface under the cursor, and q as segments."""
        session = self.session
        painter = QtGui.QPainter(self)
        try:
            painter.setRenderHint(QtGui.QPainter.Antialiasing)
            if self.show_q:
                self._draw_q(painter)
            kind = None if self._drag is None else self._drag[0]
            painting = kind == "paint"
            if self.cursor_pos is not None and kind in (None, "paint", "resize"):
                self._draw_outline(painter, session, painting)
        finally:
            painter.end()

    def _to_view(self, points, frame):
        """World points -> widget pixels (logical), and whether in front."""
        xy, front = project(frame.camera, points, frame.width, frame.height)
        xy[:, 0] *= self.width() / frame.width
        xy[:, 1] *= self.height() / frame.height
        return xy, front

    def _draw_outline(self, painter, session, painting: bool = False) -> None:
        """The brush's circle on the surface under the cursor; while painting, also an
        arrow from its centre along the drag (the direction comb combs along)."""
        self.outline = None
        frame = self.last_frame
        if frame is None:
            return
        hit = session.pick(self.cursor_pos.x(), self.cursor_pos.y(), self.width(), self.height())
        if hit is None:
            return
        posed = session.posed_points(hit.path)
        tri = session.engine.meshes[hit.path].topology.triangles[hit.triangle]
        corners = posed[tri]
        centre = hit.barycentric @ corners
        normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
        normal /= max(np.linalg.norm(normal), 1e-12)
        u = np.cross(normal, [0.0, 0.0, 1.0] if abs(normal[2]) < 0.9 else [1.0, 0.0, 0.0])
        u /= np.linalg.norm(u)
        v = np.cross(normal, u)
        angles = np.linspace(0, 2 * np.pi, 49)
        radius = session.brush.radius * _scale_of(session, hit.path)
        ring = centre + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)
        xy, front = self._to_view(ring, frame)
        if not front.all():
            return
        painter.setPen(QtGui.QPen(QtGui.QColor(255, 220, 80), 1.5))
        painter.drawPolyline(QtGui.QPolygonF([QtCore.QPointF(*p) for p in xy]))
        tip = None
        if painting and self.drag_direction is not None:
            centre_xy = np.array([self.cursor_pos.x(), self.cursor_pos.y()])
            reach = float(np.max(np.linalg.norm(xy - centre_xy, axis=1)))
            tip = centre_xy + self.drag_direction * min(max(reach, 12.0), 60.0)
            side = np.array([-self.drag_direction[1], self.drag_direction[0]]) * 5.0
            back = tip - self.drag_direction * 9.0
            painter.drawLine(QtCore.QPointF(*centre_xy), QtCore.QPointF(*tip))
            painter.drawPolyline(QtGui.QPolygonF([QtCore.QPointF(*(back + side)),
                                                  QtCore.QPointF(*tip),
                                                  QtCore.QPointF(*(back - side))]))
        #: what was drawn (widget pixels): the circle and the arrow's tip, for the tests
        self.outline = {"ring": xy, "tip": tip, "painting": painting}

    def _draw_q(self, painter) -> None:
        session, frame = self.session, self.last_frame
        if frame is None:
            return
        painter.setPen(QtGui.QPen(QtGui.QColor(80, 230, 255), 1.2))
        for path in session.paths:
            mesh = session.meshes[path]
            length = np.linalg.norm(mesh.q, axis=1)
            show = np.nonzero(length > 0.02)[0]
            if not len(show):
                continue
            posed = session.posed_points(path)
            facing = session.facing(path)
            show = show[facing[show]]
            directions = posed_directions(mesh, posed, mesh.q)
            half = 0.5 * mesh.mean_edge() * length[show, None] * directions[show]
            a, fa = self._to_view(posed[show] - half, frame)
            b, fb = self._to_view(posed[show] + half, frame)
            lines = [QtCore.QLineF(QtCore.QPointF(*p), QtCore.QPointF(*r))
                     for p, r, ok in zip(a, b, fa & fb, strict=True) if ok]
            painter.drawLines(lines)

    # -- input ------------------------------------------------------------------------
    @guarded
    def tabletEvent(self, event):  # noqa: N802
        """A pen: its press, moves and release drive the brush as the mouse's do, each
        stamp's strength times the pen's pressure (1 where the pen reports none).
        Accepted, so Qt sends no mouse events for it."""
        handler = {QtCore.QEvent.TabletPress: self.mousePressEvent,
                   QtCore.QEvent.TabletMove: self.mouseMoveEvent,
                   QtCore.QEvent.TabletRelease: self.mouseReleaseEvent}.get(event.type())
        if handler is None:
            event.ignore()
            return
        self.pressure = float(event.pressure()) if event.pressure() > 0 else 1.0
        self._pen = True
        try:
            handler(event)
        finally:
            self._pen = False
        event.accept()

    @guarded
    def mousePressEvent(self, event):  # noqa: N802
        if not self._pen:
            self.pressure = 1.0  # a mouse after a pen: full strength again
        pos = event.position()
        alt = bool(event.modifiers() & Qt.AltModifier)
        button = event.button()
        if button == Qt.LeftButton and not alt and self.resize_key:
            self._drag = ("resize", pos, self.session.brush.radius)
            self.cursor_pos = pos
            self.update()
            return
        if button == Qt.LeftButton and not alt:
            self.faults.trip("brush")
            # a stroke may start off the mesh: it begins where the drag first meets it.
            # Held at the press: Shift smooths, Ctrl erases (Maya's Artisan, Blender)
            modifiers = event.modifiers()
            self.stroke_mode = "smooth" if modifiers & Qt.ShiftModifier else \
                "erase" if modifiers & Qt.ControlModifier else None
            self._drag = ("paint", pos)
            self.interacting = True
            self.session.begin_stroke(pos.x(), pos.y(), self.width(), self.height(),
                                      self.pressure, self.stroke_mode)
            self.update()
            return
        kind = {Qt.LeftButton: "tumble", Qt.MiddleButton: "track",
                Qt.RightButton: "dolly"}.get(button)
        if kind is not None:
            self.session.stage_camera = False
            self.owner.sync_view_mode()
            self._drag = (kind, pos)
            self.interacting = True

    @guarded
    def mouseMoveEvent(self, event):  # noqa: N802
        pos = event.position()
        self.cursor_pos = pos
        if self._drag is None:
            self.update()  # the brush outline follows
            return
        if self._drag[0] == "resize":  # the outline stays where the drag began
            _, start, radius = self._drag
            self.cursor_pos = start
            self.owner.set_brush_radius(radius * 2.0 ** ((pos.x() - start.x()) / RESIZE_PIXELS))
            return
        kind, last = self._drag
        dx, dy = pos.x() - last.x(), pos.y() - last.y()
        if kind == "paint":
            if dx or dy:
                self.drag_direction = np.array([dx, dy]) / float(np.hypot(dx, dy))
            if not self.session.stroking:
                self.session.begin_stroke(pos.x(), pos.y(), self.width(), self.height(),
                                          self.pressure, self.stroke_mode)
            elif self.session.drag(pos.x(), pos.y(), self.width(), self.height(),
                                   self.pressure):
                self.owner.mark_dirty()
        elif kind == "tumble":
            self.session.orbit.tumble(dx, dy)
        elif kind == "track":
            self.session.orbit.track(dx, dy, self.height())
        elif kind == "dolly":
            self.session.orbit.dolly(-dy / 40.0)
        self._drag = (kind, pos)
        self.update()

    @guarded
    def mouseReleaseEvent(self, event):  # noqa: N802
        if self._drag is None:
            return
        kind = self._drag[0]
        self._drag = None
        self.interacting = False
        self.drag_direction = None
        if kind == "paint":
            began = self.session.stroking
            self.session.end_stroke()
            self.owner.after_edit()
            if not began:
                self.owner.statusBar().showMessage(
                    "the stroke missed the cloth: start or drag it over a wrinkled mesh "
                    f"({', '.join(self.session.paths)})", 6000)
            elif why := self.session.untouched():
                self.owner.statusBar().showMessage(why, 6000)
        self.update()  # refine: the full-quality frame

    @guarded
    def keyPressEvent(self, event):  # noqa: N802
        if event.key() == Qt.Key_B and not event.isAutoRepeat():
            self.resize_key = True
            return
        super().keyPressEvent(event)

    @guarded
    def keyReleaseEvent(self, event):  # noqa: N802
        if event.key() == Qt.Key_B and not event.isAutoRepeat():
            self.resize_key = False
            return
        super().keyReleaseEvent(event)

    @guarded
    def focusOutEvent(self, event):  # noqa: N802
        self.resize_key = False  # a B released elsewhere
        super().focusOutEvent(event)

    @guarded
    def wheelEvent(self, event):  # noqa: N802
        self.session.stage_camera = False
        self.owner.sync_view_mode()
        self.session.orbit.dolly(event.angleDelta().y() / 120.0)
        self.update()

    @guarded
    def leaveEvent(self, event):  # noqa: N802
        self.cursor_pos = None
        self.update()


def _scale_of(session, path: str) -> float:
    """How many world units one rest-space unit of ``path`` is (its local-to-world)."""
    engine = session.engine
    matrix = engine.local_to_world(path)[:3, :3] if engine.is_posed(path) else np.eye(3)
    return float(np.cbrt(abs(np.linalg.det(matrix)))) or 1.0


def posed_directions(mesh, posed: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Rest-space vectors carried to the posed mesh: per vertex, the least-squares map of
    its rest edges onto its posed edges (unit results; zero where undefined)."""
    tri = mesh.triangles
    edges = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    edges = np.concatenate([edges, edges[:, ::-1]])
    a = mesh.rest_points[edges[:, 1]] - mesh.rest_points[edges[:, 0]]
    b = posed[edges[:, 1]] - posed[edges[:, 0]]
    aa = np.zeros((mesh.count, 3, 3))
    ba = np.zeros((mesh.count, 3, 3))
    np.add.at(aa, edges[:, 0], a[:, :, None] * a[:, None, :])
    np.add.at(ba, edges[:, 0], b[:, :, None] * a[:, None, :])
    jac = ba @ np.linalg.pinv(aa, rcond=1e-6)
    out = np.einsum("nij,nj->ni", jac, np.asarray(vectors, np.float64))
    length = np.linalg.norm(out, axis=1, keepdims=True)
    return np.where(length > 1e-12, out / np.maximum(length, 1e-300), 0.0)


class _Field(QtWidgets.QLineEdit):
    """A slider's typed value. Esc while typing puts the value back (the window's own Esc,
    drop the stroke, would take the key first: the field claims it through Qt's shortcut
    override while it has focus)."""

    escaped = QtCore.Signal()

    def event(self, event):  # noqa: D401 (Qt override)
        if event.type() == QtCore.QEvent.ShortcutOverride and event.key() == Qt.Key_Escape:
            event.accept()
            return True
        return super().event(event)

    def keyPressEvent(self, event):  # noqa: N802
        if event.key() == Qt.Key_Escape:
            self.escaped.emit()
            return
        super().keyPressEvent(event)


class _Slider(QtWidgets.QWidget):
    """A labelled float slider with a field that takes a typed value: the slider's own
    signals while dragged and on release; ``typed(value)`` when a value is typed and
    Enter pressed (any finite number, also beyond the slider's range: whoever takes it
    checks it), ``refused(text)`` when the text is not a number."""

    typed = QtCore.Signal(float)
    refused = QtCore.Signal(str)

    def __init__(self, label: str, low: float, high: float, value: float, decimals: int = 3,
                 log: bool = False):
        super().__init__()
        self.low, self.high, self.log, self.decimals = low, high, log, decimals
        layout = QtWidgets.QHBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        self.label = QtWidgets.QLabel(label)
        self.label.setMinimumWidth(70)
        self.slider = QtWidgets.QSlider(Qt.Horizontal)
        self.slider.setRange(0, 1000)
        #: the value, shown and typed (Enter takes it)
        self.field = _Field()
        self.field.setFixedWidth(64)
        self.field.setToolTip("Type a value and press Enter")
        layout.addWidget(self.label)
        layout.addWidget(self.slider, 1)
        layout.addWidget(self.field)
        self._exact: float | None = None
        self.set_value(value)
        self.slider.valueChanged.connect(self._moved)
        self.field.returnPressed.connect(self._typed)
        self.field.escaped.connect(self._escaped)

    def setToolTip(self, text: str) -> None:  # noqa: N802 (Qt naming)
        """The label and slider carry the control's tooltip; the field says it is typed."""
        super().setToolTip(text)
        self.label.setToolTip(text)
        self.slider.setToolTip(text)
        self.field.setToolTip(f"{text}. Type a value and press Enter")

    def _escaped(self) -> None:
        """Esc in the field: the value as it was, the keyboard back to the view."""
        self._show()
        self.field.clearFocus()

    def _typed(self) -> None:
        text = self.field.text().strip()
        try:
            value = float(text)
        except ValueError:
            value = float("nan")
        if not np.isfinite(value):
            self._show()
            self.refused.emit(f"{self.label.text()}: {text!r} is not a number")
            return
        self.set_value(value)
        self.field.clearFocus()
        self.typed.emit(value)

    def _to_value(self, position: int) -> float:
        t = position / 1000.0
        if self.log:
            return float(self.low * (self.high / self.low) ** t)
        return float(self.low + t * (self.high - self.low))

    def _to_position(self, value: float) -> int:
        value = min(max(value, self.low), self.high)
        if self.log:
            t = np.log(value / self.low) / np.log(self.high / self.low)
        else:
            t = (value - self.low) / (self.high - self.low) if self.high > self.low else 0.0
        return int(round(1000 * t))

    def value(self) -> float:
        """The value set (exactly), or the slider's position once it moved."""
        return self._exact if self._exact is not None else self._to_value(self.slider.value())

    def set_value(self, value: float) -> None:
        blocked = self.slider.blockSignals(True)
        self.slider.setValue(self._to_position(value))
        self.slider.blockSignals(blocked)
        self._exact = float(value)  # the label shows 0.06, not the nearest step's 0.0603
        self._show()

    def _moved(self, *_):
        self._exact = None
        self._show()

    def _show(self, *_):
        self.field.setText(f"{self.value():.{self.decimals}g}")
        self.field.setCursorPosition(0)


class HelpOverlay(QtWidgets.QLabel):
    """The keys and mouse bindings (BINDINGS) over the top left of the view, H or ? to
    show or hide; :meth:`listed` reads them back from the text shown."""

    def __init__(self, parent: QtWidgets.QWidget):
        import html

        super().__init__(parent)
        rows = "".join(f"<tr><td><b>{html.escape(keys)}</b></td>"
                       f"<td>&nbsp;&nbsp;{html.escape(what)}</td></tr>"
                       for keys, what in BINDINGS)
        self.setText(f"<table>{rows}</table>")
        self.setTextFormat(Qt.RichText)
        self.setStyleSheet("background: rgba(20, 20, 24, 215); color: #f0f0f0; "
                           "padding: 10px; border-radius: 6px;")
        self.setAttribute(Qt.WA_TransparentForMouseEvents)
        self.adjustSize()
        self.move(12, 12)

    def listed(self) -> list[tuple[str, str]]:
        """The (keys, what) rows the overlay shows, read back from its text."""
        import html
        import re

        rows = re.findall(r"<tr><td><b>(.*?)</b></td><td>(?:&nbsp;)*(.*?)</td></tr>",
                          self.text())
        return [(html.unescape(keys), html.unescape(what)) for keys, what in rows]


class PaintWindow(QtWidgets.QMainWindow):
    """``usdwrinkle paint``: the view, the brush and control panel, the timeline."""

    def __init__(self, make_session, title: str = "usdwrinkle paint", debug: bool = False,
                 stage_path: str | None = None):
        super().__init__()
        #: the stage file painted (File > Open Recent remembers it); None: the stage's
        #: root layer where it is a file
        self.stage_path = stage_path
        #: print each error's traceback too (``usdwrinkle --debug paint``)
        self.debug = debug
        self.setWindowTitle(title)
        self._title = title
        self.session: PaintSession | None = None
        self.errors: list[str] = []
        #: asked when closing with unsaved strokes: returns "save", "discard" or "cancel"
        #: (a dialog by default; tests answer it)
        self.confirm_close = self._ask_close
        #: the name a brush preset is saved under (a dialog by default; tests answer it)
        self.ask_preset_name = self._ask_preset_name
        #: the stage File > Open paints, and the file Save As writes, given where the
        #: dialog starts (dialogs by default; tests answer them)
        self.ask_open_path = self._ask_open_path
        self.ask_save_path = self._ask_save_path
        self._closing_what = "closing"
        self.view = PaintView(self, make_session)
        self.setCentralWidget(self.view)
        self.error_banner = QtWidgets.QLabel()
        self.error_banner.setStyleSheet("background:#7a1f1f;color:white;padding:4px")
        self.error_banner.setWordWrap(True)
        self.error_banner.hide()
        self.statusBar().addPermanentWidget(self.error_banner, 1)
        #: the last frame's numbers, on the status bar's right; its left side keeps the
        #: messages (saved, a stroke that missed) for their seconds
        self.frame_info = QtWidgets.QLabel()
        self.statusBar().addPermanentWidget(self.frame_info)
        self._build_controls()
        self._build_timeline()
        self._build_actions()
        self._play = QtCore.QTimer(self)
        self._play.timeout.connect(self._step_play)
        self.resize(1200, 700)

    # -- building -------------------------------------------------------------------
    def _build_controls(self) -> None:
        dock = QtWidgets.QDockWidget("Brush and wrinkles", self)
        dock.setFeatures(QtWidgets.QDockWidget.NoDockWidgetFeatures)
        panel = QtWidgets.QWidget()
        form = QtWidgets.QVBoxLayout(panel)
        self.mode = QtWidgets.QComboBox()
        self.mode.addItems(MODES)
        self.falloff = QtWidgets.QComboBox()
        self.falloff.addItems(FALLOFFS)
        self.mirror = QtWidgets.QComboBox()
        self.mirror.addItems(["none" if axis is None else axis for axis in MIRROR_AXES])
        self.geodesic = QtWidgets.QCheckBox("distance along the surface")
        self.geodesic.setChecked(True)
        self.front_only = QtWidgets.QCheckBox("front-facing only")
        self.front_only.setChecked(True)
        self.show_q = QtWidgets.QCheckBox("show q")
        self.radius = _Slider("radius", 1e-3, 10.0, 0.1, log=True)
        self.strength = _Slider("strength", 0.0, 1.0, 0.5)
        self.amount = _Slider("amount", 0.0, 1.0, 1.0)
        self.flood_button = QtWidgets.QPushButton("Flood")
        self.width_slider = _Slider("W", 1e-3, 10.0, 0.1, log=True)
        self.amplitude = _Slider("amplitude", 0.0, 4.0, 1.0)
        self.slack = _Slider("slack", 0.0, 0.9, 0.06)
        self.irregularity = _Slider("irregularity", 0.0, CONTROLS["irregularity"][2], 0.0)
        self.cloth = QtWidgets.QComboBox()
        self.cloth.addItems(["(as authored)", *CLOTH_PRESETS])
        self.view_mode = QtWidgets.QComboBox()
        self.view_mode.addItems(["orbit", "stage camera"])
        self.preset = QtWidgets.QComboBox()
        self.save_preset_button = QtWidgets.QPushButton("Save...")
        self.delete_preset_button = QtWidgets.QPushButton("Delete")
        preset_row = QtWidgets.QHBoxLayout()
        preset_row.addWidget(QtWidgets.QLabel("preset"))
        preset_row.addWidget(self.preset, 1)
        form.addLayout(preset_row)
        preset_buttons = QtWidgets.QHBoxLayout()
        preset_buttons.addWidget(self.save_preset_button)
        preset_buttons.addWidget(self.delete_preset_button)
        form.addLayout(preset_buttons)
        for label, widget in (("mode", self.mode), ("falloff", self.falloff),
                              ("mirror", self.mirror)):
            row = QtWidgets.QHBoxLayout()
            row.addWidget(QtWidgets.QLabel(label))
            row.addWidget(widget, 1)
            form.addLayout(row)
        for widget in (self.radius, self.strength, self.amount, self.geodesic,
                       self.front_only, self.flood_button, self.show_q):
            form.addWidget(widget)
        form.addWidget(QtWidgets.QLabel("<b>Wrinkles</b>"))
        for widget in (self.width_slider, self.amplitude, self.slack, self.irregularity):
            form.addWidget(widget)
        for label, widget in (("cloth", self.cloth), ("view", self.view_mode)):
            row = QtWidgets.QHBoxLayout()
            row.addWidget(QtWidgets.QLabel(label))
            row.addWidget(widget, 1)
            form.addLayout(row)
        form.addStretch(1)
        dock.setWidget(panel)
        self.addDockWidget(Qt.RightDockWidgetArea, dock)
        for combo in (self.mode, self.falloff, self.mirror):
            combo.currentTextChanged.connect(self._brush_changed)
        for box in (self.geodesic, self.front_only):
            box.toggled.connect(self._brush_changed)
        for slider in (self.radius, self.strength, self.amount):
            slider.slider.valueChanged.connect(self._brush_changed)
        self.show_q.toggled.connect(self._show_q)
        self.flood_button.clicked.connect(self._flood)
        for name, slider in self._controls().items():
            slider.slider.valueChanged.connect(functools.partial(self._control_moved, name))
            slider.slider.sliderReleased.connect(functools.partial(self._control_released,
                                                                   name))
        self.cloth.currentTextChanged.connect(self._cloth_changed)
        self._fill_presets()
        self.preset.activated.connect(self._preset_chosen)
        self.save_preset_button.clicked.connect(self._save_preset)
        self.delete_preset_button.clicked.connect(self._delete_preset)
        self.view_mode.currentTextChanged.connect(self._view_mode_changed)
        for slider in (self.radius, self.strength, self.amount):
            slider.typed.connect(functools.partial(self._brush_typed, slider))
        for name, slider in self._controls().items():
            slider.typed.connect(functools.partial(self._control_typed, name))
        for slider in (*self._controls().values(), self.radius, self.strength, self.amount):
            slider.refused.connect(self._field_refused)
        for name, widget in self._tipped().items():
            widget.setToolTip(TIPS[name])

    def _tipped(self) -> dict:
        """The controls, by their TIPS names."""
        return {"mode": self.mode, "falloff": self.falloff, "mirror": self.mirror,
                "radius": self.radius, "strength": self.strength, "amount": self.amount,
                "geodesic": self.geodesic, "front_only": self.front_only,
                "flood": self.flood_button, "show_q": self.show_q,
                "width": self.width_slider, "amplitude": self.amplitude,
                "slack": self.slack, "irregularity": self.irregularity,
                "cloth": self.cloth, "view": self.view_mode,
                "preset": self.preset, "save_preset": self.save_preset_button,
                "delete_preset": self.delete_preset_button}

    def _controls(self) -> dict:
        return {"width": self.width_slider, "amplitude_scale": self.amplitude,
                "slack": self.slack, "irregularity": self.irregularity}

    def _build_timeline(self) -> None:
        bar = QtWidgets.QToolBar("Timeline", self)
        bar.setMovable(False)
        self.play_button = QtWidgets.QPushButton("Play")
        self.play_button.setCheckable(True)
        self.timeline = QtWidgets.QSlider(Qt.Horizontal)
        self.frame_label = QtWidgets.QLabel()
        self.frame_label.setMinimumWidth(80)
        bar.addWidget(self.play_button)
        bar.addWidget(self.timeline)
        bar.addWidget(self.frame_label)
        self.addToolBar(Qt.BottomToolBarArea, bar)
        self.timeline.valueChanged.connect(self._scrub)
        self.play_button.toggled.connect(self._toggle_play)
        self.play_button.setToolTip(TIPS["play"])
        self.timeline.setToolTip(TIPS["timeline"])

    def _build_actions(self) -> None:
        menu = self.menuBar().addMenu("&File")
        edit = self.menuBar().addMenu("&Edit")
        view = self.menuBar().addMenu("&View")
        help_menu = self.menuBar().addMenu("&Help")
        specs = (
            (menu, "&Open...", QtGui.QKeySequence.Open, self.open_dialog),
            (menu, "&Save", QtGui.QKeySequence.Save, self.save),
            (menu, "Save &As...", QtGui.QKeySequence("Ctrl+Shift+S"), self.save_as),
            (menu, "&Close", QtGui.QKeySequence.Close, self.close),
            (edit, "&Undo", QtGui.QKeySequence("Ctrl+Z"), self.undo),
            (edit, "&Redo", QtGui.QKeySequence("Ctrl+Shift+Z"), self.redo),
            (edit, "Drop stroke", QtGui.QKeySequence(Qt.Key_Escape), self._cancel_stroke),
            (edit, "Smaller brush", QtGui.QKeySequence(Qt.Key_BracketLeft),
             functools.partial(self._resize_brush, 1 / 1.15)),
            (edit, "Larger brush", QtGui.QKeySequence(Qt.Key_BracketRight),
             functools.partial(self._resize_brush, 1.15)),
            (view, "&Frame meshes", QtGui.QKeySequence(Qt.Key_F), self.frame_meshes),
            (view, "Play", QtGui.QKeySequence(Qt.Key_Space),
             lambda: self.play_button.toggle()),
            (help_menu, "&Keys and mouse", QtGui.QKeySequence(Qt.Key_H), self.toggle_help),
            (help_menu, "&About", QtGui.QKeySequence(), self._about),
        )
        self.actions_by_name = {}
        for owner, text, keys, slot in specs:
            action = QtGui.QAction(text, self)
            action.setShortcut(keys)
            action.setShortcutContext(Qt.WindowShortcut)
            action.triggered.connect(self._guard_slot(slot))
            owner.addAction(action)
            self.actions_by_name[text.replace("&", "")] = action
        display = view.addMenu("&Display")
        group = QtGui.QActionGroup(self)
        group.setExclusive(True)
        self.display_actions = {}
        for name, text, tip in (
                ("shaded", "&Shaded wrinkles", "The material and the wrinkles, as render"),
                ("amount", "Painted &amount |q|", "The painted amount |q| from blue (0) to "
                 "red (1); grey where nothing is painted"),
                ("width", "Painted &W", "The painted W against the W control's value: "
                 "green equal, blue a quarter, red four times")):
            action = QtGui.QAction(text, self)
            action.setCheckable(True)
            action.setToolTip(tip)
            action.setChecked(name == "shaded")
            action.triggered.connect(functools.partial(self._display, name))
            group.addAction(action)
            display.addAction(action)
            self.display_actions[name] = action
        self.recent_menu = QtWidgets.QMenu("Open &Recent", self)
        menu.insertMenu(self.actions_by_name["Save"], self.recent_menu)
        self.recent_menu.aboutToShow.connect(self._fill_recent)
        relief = QtGui.QAction("&Relief", self)
        relief.setCheckable(True)
        relief.setToolTip("Draw the folds where the view ray meets them, as the displaced "
                          "geometry stands: the flanks that face away hide behind the "
                          "crests. Slower on a CPU renderer")
        relief.toggled.connect(self._relief)
        view.addAction(relief)
        self.actions_by_name["Relief"] = relief
        follow = QtGui.QAction("Follow the &mesh", self)
        follow.setCheckable(True)
        follow.setToolTip("While the timeline plays or scrubs, the view moves with the "
                          "meshes (their box's centre)")
        follow.toggled.connect(self._follow)
        view.addAction(follow)
        self.actions_by_name["Follow the mesh"] = follow
        keys = self.actions_by_name["Keys and mouse"]
        keys.setShortcuts([QtGui.QKeySequence(Qt.Key_H), QtGui.QKeySequence("?")])
        keys.setCheckable(True)
        self.help_overlay = HelpOverlay(self.view)
        self.help_overlay.hide()

    def toggle_help(self) -> None:
        """Show or hide the keys and mouse bindings over the view (H or ?)."""
        show = not self.help_overlay.isVisible()
        self.help_overlay.setVisible(show)
        if show:
            self.help_overlay.raise_()
        self.actions_by_name["Keys and mouse"].setChecked(show)

    def _about(self) -> None:
        from .. import __version__

        QtWidgets.QMessageBox.about(
            self, "About usdwrinkle paint",
            f"usdwrinkle {__version__}: paint rest-pose wrinkle vectors q and W on "
            "WrinkleAPI meshes; the saved layer renders as this window draws it. "
            "The README's paint section has the whole story; H lists the keys.")

    @guarded
    def _brush_typed(self, slider, value: float) -> None:
        """A typed brush value: taken when the brush accepts it, else the field goes
        back to the brush's value and the window says why."""
        if self.session is None:
            return
        name = {self.radius: "radius", self.strength: "strength",
                self.amount: "amount"}[slider]
        try:
            self._brush_changed()
        finally:
            if getattr(self.session.brush, name) != slider.value():
                slider.set_value(getattr(self.session.brush, name))

    @guarded
    def _control_typed(self, name: str, value: float) -> None:
        """A typed W, amplitude or slack: authored as one undo step, or refused in one
        line with the field back at the session's value."""
        if self.session is None:
            return
        try:
            self.session.set_control(name, value, live=False)
        finally:
            self._controls()[name].set_value(self.session.control(name))
            if name == "width":
                self._centre_width_slider()
        self.after_edit()
        self.view.update()

    def _field_refused(self, text: str) -> None:
        self.show_error(text)  # one line in the banner, as the session's refusals

    def _guard_slot(self, slot):
        def run(*_):
            try:
                slot()
            except Exception as exc:  # noqa: BLE001 (a slot must never raise into Qt)
                text = exc.one_line() if hasattr(exc, "one_line") else \
                    f"{type(exc).__name__}: {exc}"
                self.show_error(text, traceback.format_exc())
        return run

    # -- the session ------------------------------------------------------------------
    def session_ready(self, session: PaintSession) -> None:
        """The view made its session (initializeGL): fill the controls from it."""
        self.session = session
        brush = session.brush
        self.radius.low, self.radius.high = brush.radius / 100, brush.radius * 20
        self._show_brush(brush)
        self._fill_controls()
        frames = session.frames
        if len(frames) > 1 and frames[0] is not None:
            blocked = self.timeline.blockSignals(True)
            self.timeline.setRange(int(frames[0]), int(frames[-1]))
            self.timeline.setValue(int(round(session.frame)))
            self.timeline.blockSignals(blocked)
        else:
            self.timeline.setEnabled(False)
            self.play_button.setEnabled(False)
        session.set_relief(self.actions_by_name["Relief"].isChecked())
        self.sync_view_mode()
        self._update_title()
        self._update_frame_label()
        stage_path = self.stage_path or session.stage.GetRootLayer().realPath
        if stage_path and os.path.isfile(stage_path):
            from ..app.recent import remember_stage

            remember_stage(stage_path)  # File > Open Recent

    # -- brush presets (app/presets.py) ---------------------------------------------
    def _fill_presets(self) -> None:
        """The preset list from the file; a preset the file holds badly is one line."""
        from ..app.presets import load_presets

        try:
            self.presets, refused = load_presets()
        except Exception as exc:  # noqa: BLE001 (an unreadable file: said, not fatal)
            self.presets, refused = {}, [exc.one_line() if hasattr(exc, "one_line")
                                         else str(exc)]
        for line in refused:
            self.show_error(line)
        self.preset.blockSignals(True)
        self.preset.clear()
        self.preset.addItem("(choose)")
        self.preset.addItems(sorted(self.presets))
        self.preset.blockSignals(False)

    @guarded
    def _preset_chosen(self, index: int) -> None:
        name = self.preset.itemText(index)
        if name not in self.presets:
            return
        self.apply_brush(self.presets[name])
        self.statusBar().showMessage(f"brush preset {name!r}", 4000)

    def apply_brush(self, brush) -> None:
        """Set every brush control from ``brush`` (a preset), then the brush from them;
        the width mode's W stays the W control's."""
        from ..app.paint_session import with_brush

        self._show_brush(brush)
        self._brush_changed()
        with_brush(self.session, spacing=brush.spacing)

    def _show_brush(self, brush) -> None:
        """Every brush control shows ``brush``, its signals held (nothing is applied)."""
        toggles = (self.mode, self.falloff, self.mirror, self.geodesic, self.front_only)
        for widget in toggles:
            widget.blockSignals(True)
        try:
            self.mode.setCurrentText(brush.mode)
            self.falloff.setCurrentText(brush.falloff)
            self.mirror.setCurrentText(brush.mirror or "none")
            self.geodesic.setChecked(bool(brush.geodesic))
            self.front_only.setChecked(bool(brush.front_facing_only))
            for slider, value in ((self.radius, brush.radius), (self.strength, brush.strength),
                                  (self.amount, brush.amount)):
                slider.set_value(value)
        finally:
            for widget in toggles:
                widget.blockSignals(False)

    @guarded
    def _save_preset(self, *_) -> None:
        from ..app.presets import save_preset

        name = self.ask_preset_name()
        if not name:
            return
        where = save_preset(name, self.session.brush)
        self._fill_presets()
        self.preset.setCurrentText(name.strip())
        self.statusBar().showMessage(f"saved brush preset {name.strip()!r} to {where}", 6000)

    @guarded
    def _delete_preset(self, *_) -> None:
        from ..app.presets import delete_preset

        name = self.preset.currentText()
        if name not in self.presets:
            self.statusBar().showMessage("choose a preset in the list to delete it", 4000)
            return
        delete_preset(name)
        self._fill_presets()
        self.statusBar().showMessage(f"deleted brush preset {name!r}", 4000)

    def _ask_preset_name(self) -> str | None:
        name, ok = QtWidgets.QInputDialog.getText(self, "Save the brush preset",
                                                  "Preset name:")
        return name if ok else None

    def _fill_controls(self) -> None:
        for name, slider in self._controls().items():
            slider.set_value(self.session.control(name))
        self._centre_width_slider()

    def _centre_width_slider(self) -> None:
        """The W slider spans W_SPAN around the current W, its handle in the middle
        (issue 57: over 400x, a 26 px drag was a 9x change); re-centred after each
        release, typed value, undo or preset, so that the next drag refines from there."""
        width = self.session.control("width")
        self.width_slider.low, self.width_slider.high = width / W_SPAN, width * W_SPAN
        self.width_slider.set_value(width)

    @guarded
    def _brush_changed(self, *_):
        if self.session is None:
            return
        from ..app.paint_session import with_brush

        with_brush(self.session, mode=self.mode.currentText(),
                   falloff=self.falloff.currentText(),
                   mirror=None if self.mirror.currentText() == "none" else
                   self.mirror.currentText(),
                   geodesic=self.geodesic.isChecked(),
                   front_facing_only=self.front_only.isChecked(),
                   radius=self.radius.value(), strength=self.strength.value(),
                   amount=self.amount.value(), width=self.width_slider.value())
        self.view.update()

    def set_brush_radius(self, radius: float) -> None:
        """The brush radius exactly (B + drag): the field shows it, the brush takes it
        (within the slider's range)."""
        self.radius.set_value(min(max(radius, self.radius.low), self.radius.high))
        self._brush_changed()

    def _resize_brush(self, factor: float) -> None:
        self.radius.slider.setValue(self.radius._to_position(self.radius.value() * factor))

    @guarded
    def _show_q(self, on: bool):
        self.view.show_q = bool(on)
        self.view.update()

    @guarded
    def _control_moved(self, name: str, *_):
        if self.session is None:
            return
        slider = self._controls()[name]
        live = slider.slider.isSliderDown()
        self.view.interacting = live
        self.session.set_control(name, slider.value(), live=live)
        if not live:
            self.after_edit()
        self.view.update()

    @guarded
    def _control_released(self, name: str):
        if self.session is None:
            return
        self.view.interacting = False
        self.session.set_control(name, self._controls()[name].value(), live=False)
        if name == "width":
            self._centre_width_slider()
        self.after_edit()
        self.view.update()

    @guarded
    def _cloth_changed(self, text: str):
        if self.session is None or text.startswith("("):
            return
        self.session.set_cloth(text)
        self._fill_controls()
        self.after_edit()
        self.view.update()

    @guarded
    def _view_mode_changed(self, text: str):
        if self.session is None:
            return
        self.session.stage_camera = text == "stage camera"
        self.view.update()

    def sync_view_mode(self) -> None:
        blocked = self.view_mode.blockSignals(True)
        self.view_mode.setCurrentText("stage camera" if self.session.stage_camera else "orbit")
        self.view_mode.blockSignals(blocked)

    @guarded
    def _flood(self, *_):
        self.session.flood()
        self.after_edit()
        self.view.update()

    def _cancel_stroke(self) -> None:
        if self.session is not None and self.session.stroking:
            self.session.cancel_stroke()
            self.view._drag = None
            self.view.interacting = False
            self.view.update()

    @guarded
    def _display(self, name: str, *_) -> None:
        """View > Display: what the meshes are drawn in (app.paint_session.DISPLAYS)."""
        self.session.set_display(name)
        self.display_actions[name].setChecked(True)
        self.view.update()

    @guarded
    def _relief(self, on: bool) -> None:
        if self.session is not None:
            self.session.set_relief(on)
            self.view.update()

    def _follow(self, on: bool) -> None:
        self.session.set_follow(on)
        self.sync_view_mode()
        self.view.update()

    def frame_meshes(self) -> None:
        self.session.stage_camera = False
        self.sync_view_mode()
        self.session.frame_view(self.view.width() / max(self.view.height(), 1))
        self.view.update()

    # -- timeline -------------------------------------------------------------------
    @guarded
    def _scrub(self, value: int):
        if self.session is None:
            return
        self.session.frame = float(value)
        self._update_frame_label()
        self.view.update()

    def _update_frame_label(self) -> None:
        if self.session is not None:
            self.frame_label.setText(f"frame {format_frame(self.session.frame)}")

    @guarded
    def _toggle_play(self, on: bool):
        self.play_button.setText("Pause" if on else "Play")
        if on:
            self._play.start(0)
        else:
            self._play.stop()

    @guarded
    def _step_play(self):
        value = self.timeline.value() + 1
        if value > self.timeline.maximum():
            value = self.timeline.minimum()
        self.timeline.setValue(value)

    # -- undo, save, close ----------------------------------------------------------
    def undo(self) -> None:
        if self.session.undo() is not None:
            self.after_edit()
            self._fill_controls()
            self.view.update()

    def redo(self) -> None:
        if self.session.redo() is not None:
            self.after_edit()
            self._fill_controls()
            self.view.update()

    def save(self) -> bool:
        self.view.faults.trip("save")
        if self.session.save_path is None and not self.session.in_memory:
            return self.save_as()
        where = self.session.save()
        self.statusBar().showMessage(f"saved {where}" if where else "saved (in memory)",
                                     5000)
        self._update_title()
        return True

    def save_as(self) -> bool:
        path = self.ask_save_path(self._save_as_start())
        if not path:
            return False
        where = self.session.save(path)
        self.statusBar().showMessage(f"saved {where}", 5000)
        self._update_title()
        return True

    def _save_as_start(self) -> str:
        """Where Save As starts: the layer's own folder and name, else the stage's folder
        (issue 57: it started in the current folder)."""
        session = self.session
        if session.save_path:
            return session.save_path
        stage = self.stage_path or session.stage.GetRootLayer().realPath
        folder = os.path.dirname(stage) if stage else os.getcwd()
        return os.path.join(folder, "painted.usda")

    def _ask_save_path(self, start: str) -> str | None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            self, "Save the painted layer", start, "USD layers (*.usda *.usdc *.usd)")
        return path or None

    # -- opening another stage --------------------------------------------------------
    def open_dialog(self) -> bool:
        """File > Open: a stage to paint in this window instead (asking about unsaved
        strokes first)."""
        return self.open_stage(self.ask_open_path(self._open_start()))

    def _open_start(self) -> str:
        """Where File > Open starts: the painted stage's folder."""
        stage = self.stage_path or (self.session.stage.GetRootLayer().realPath
                                    if self.session else "")
        return os.path.dirname(stage) if stage else os.getcwd()

    def _ask_open_path(self, start: str) -> str | None:
        path, _ = QtWidgets.QFileDialog.getOpenFileName(
            self, "Open a stage to paint", start,
            "USD stages (*.usda *.usdc *.usd *.usdz);;All files (*)")
        return path or None

    def _fill_recent(self) -> None:
        from ..app.recent import recent_stages

        self.recent_menu.clear()
        stages = recent_stages()
        for stage in stages:
            action = self.recent_menu.addAction(stage)
            action.triggered.connect(functools.partial(self._open_recent, stage))
        if not stages:
            self.recent_menu.addAction("(none yet)").setEnabled(False)

    @guarded
    def _open_recent(self, stage: str, *_) -> None:
        self.open_stage(stage)

    def open_stage(self, path: str | None) -> bool:
        """Paint ``path`` in this window, as ``usdwrinkle paint PATH`` does (its root
        layer edited in place; a .usdz needs Save As). Unsaved strokes are asked about
        first; a stage that cannot be painted is one line in the banner and the window
        keeps the one it had."""
        if not path:
            return False
        if self.session is not None and self.session.dirty:
            self._closing_what = "opening another stage"
            try:
                answer = self.confirm_close()
            finally:
                self._closing_what = "closing"
            if answer == "cancel" or (answer == "save" and not self.save()):
                return False
        from ..app.paint_session import PaintSession, check_paintable, open_paint_stage

        try:
            stage, layer, save = open_paint_stage(path, None)
            check_paintable(stage, None, False)
            view = self.view
            view.makeCurrent()
            try:
                session = PaintSession(stage, layer, save, ctx=view.ctx)
                old, view.session = view.session, session
                if old is not None:
                    old.release()
            finally:
                view.doneCurrent()
        except Exception as exc:  # noqa: BLE001 (one line; the window keeps its stage)
            text = exc.one_line() if hasattr(exc, "one_line") else f"{type(exc).__name__}: {exc}"
            self.show_error(text, traceback.format_exc())
            return False
        self._title = f"usdwrinkle paint {path}"
        self.stage_path = path
        self.display_actions["shaded"].setChecked(True)
        follow = self.actions_by_name["Follow the mesh"]
        blocked = follow.blockSignals(True)
        follow.setChecked(False)
        follow.blockSignals(blocked)
        self.session_ready(session)
        self.statusBar().showMessage(f"opened {path}", 5000)
        self.view.update()
        return True

    def mark_dirty(self) -> None:
        self._update_title()

    def after_edit(self) -> None:
        self.error_banner.hide()
        self._update_title()

    def _update_title(self) -> None:
        if self.session is None:
            return
        where = self.session.save_path or "(unsaved layer)"
        self.setWindowTitle(f"{self._title} - {where}[*]")
        self.setWindowModified(self.session.dirty)

    def frame_drawn(self, frame) -> None:
        kind = "preview" if frame.quality.preview else "full"
        self.frame_info.setText(
            f"frame {format_frame(frame.frame)}, {frame.width}x{frame.height} {kind} in "
            f"{1e3 * frame.seconds:.0f} ms; radius {self.session.brush.radius:.3g}; "
            f"mesh {self.session.active}")

    def show_error(self, text: str, detail: str = "") -> None:
        """A Python error inside a Qt override or slot: shown in the window, logged, and
        the window goes on."""
        self.errors.append(text)
        from ..process.errors import print_stderr

        print_stderr(f"usdwrinkle: paint: error: {text}"
                     + (f"\n{detail}" if detail and self.debug else ""))
        # shown from the event loop, not here: inside paintGL a new banner re-lays the
        # window out and resizes the GL widget while it paints, which can crash the
        # process (docs/decisions.md, "The paint window's error banner")
        QtCore.QTimer.singleShot(0, functools.partial(self._show_banner, text))

    def _show_banner(self, text: str) -> None:
        self.error_banner.setText(f"error: {text}")
        self.error_banner.show()

    # -- stop signals (SIGINT, SIGTERM, SIGHUP) ---------------------------------------
    #: the exit code a stop signal asked for (130 SIGINT, 143 SIGTERM and SIGHUP), while
    #: the window closes (None: no stop asked)
    stop_code: int | None = None

    def stop_requested(self, signum: int) -> None:
        """A stop signal: close as Ctrl+W does (asking first when strokes are unsaved), then
        end with the shell's code. A second one while the question is open does not wait
        for an answer: the unsaved strokes go to a recovery file beside the layer, and
        the process ends at once."""
        from ..process.errors import print_stderr

        code = 130 if signum == signal.SIGINT else 143
        said = "interrupted" if code == 130 else "terminated"
        if self.stop_code is not None or self.session is None:
            note = ""
            if self.session is not None and self.session.dirty:
                try:
                    note = f"; unsaved strokes written to {self.session.write_recovery()}"
                except Exception as exc:  # noqa: BLE001 (the stop goes on regardless)
                    note = f"; unsaved strokes lost ({exc})"
            print_stderr(f"usdwrinkle: {said}{note}")
            os._exit(code)
        self.stop_code = code
        QtCore.QTimer.singleShot(0, functools.partial(self._close_for_stop, said))

    def _close_for_stop(self, said: str) -> None:
        from ..process.errors import print_stderr

        code = self.stop_code
        if self.close():
            print_stderr(f"usdwrinkle: {said}")
            self.stop_code = code
            QtWidgets.QApplication.exit(code)
        else:  # the artist answered Cancel: painting goes on
            self.stop_code = None
            self.statusBar().showMessage(f"{said}: cancelled, the window stays open", 5000)

    def _ask_close(self) -> str:
        box = QtWidgets.QMessageBox(self)
        box.setWindowTitle("Unsaved strokes")
        box.setText("The painted layer has unsaved strokes. Save them before "
                    f"{self._closing_what}?")
        box.setStandardButtons(QtWidgets.QMessageBox.Save | QtWidgets.QMessageBox.Discard |
                               QtWidgets.QMessageBox.Cancel)
        answer = box.exec()
        return {QtWidgets.QMessageBox.Save: "save",
                QtWidgets.QMessageBox.Discard: "discard"}.get(answer, "cancel")

    @guarded
    def closeEvent(self, event):  # noqa: N802
        if self.session is not None and self.session.dirty:
            answer = self.confirm_close()
            if answer == "cancel" or (answer == "save" and not self.save()):
                event.ignore()
                return
        self._play.stop()
        self.view.release()
        self.session = None
        event.accept()


class StopSignals(QtCore.QObject):
    """SIGINT, SIGTERM and SIGHUP while the window runs, delivered to it in Qt's event
    loop: Python's handlers run only when Python code runs, and Qt sits in C++ between
    events, so the signal's number is written to a pipe (``signal.set_wakeup_fd``) that a
    QSocketNotifier watches. The window then closes as Ctrl+W does (stop_requested). Before,
    the CLI's handler raised KeyboardInterrupt inside Qt's dispatch, which swallowed it,
    and left the three signals ignored: only SIGKILL ended the window."""

    SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP")
                    if hasattr(signal, name))

    def __init__(self, window: PaintWindow):
        super().__init__(window)
        self.window = window
        self._read, self._write = os.pipe()
        os.set_blocking(self._read, False)
        os.set_blocking(self._write, False)
        self._previous_fd = signal.set_wakeup_fd(self._write)
        self._previous = {sig: signal.signal(sig, self._caught) for sig in self.SIGNALS}
        signal.pthread_sigmask(signal.SIG_UNBLOCK, self.SIGNALS)
        self._notifier = QtCore.QSocketNotifier(self._read, QtCore.QSocketNotifier.Read, self)
        self._notifier.activated.connect(self._woken)

    def _caught(self, signum, frame) -> None:
        """Python's handler: the pipe already holds the number (its C handler wrote it)."""

    def _woken(self, *_) -> None:
        try:
            numbers = os.read(self._read, 64)
        except BlockingIOError:
            return
        for number in numbers:
            if number in self.SIGNALS:
                try:
                    self.window.stop_requested(number)
                except Exception as exc:  # noqa: BLE001 (never into Qt's dispatch)
                    self.window.show_error(f"{type(exc).__name__}: {exc}")

    def restore(self) -> None:
        self._notifier.setEnabled(False)
        signal.set_wakeup_fd(self._previous_fd)
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        os.close(self._read)
        os.close(self._write)


def run_window(make_session, title: str = "usdwrinkle paint", size=(1200, 700),
               debug: bool = False, stage_path: str | None = None) -> int:
    """Open the paint window on a session made in its GL context; returns Qt's exit code."""
    from PySide6.QtGui import QSurfaceFormat

    fmt = QSurfaceFormat()
    fmt.setVersion(4, 3)
    fmt.setProfile(QSurfaceFormat.CoreProfile)
    fmt.setDepthBufferSize(24)
    QSurfaceFormat.setDefaultFormat(fmt)
    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["usdwrinkle paint"])
    window = PaintWindow(make_session, title, debug=debug, stage_path=stage_path)
    window.resize(*size)
    stops = StopSignals(window)
    window.show()
    try:
        code = app.exec()
    finally:
        stops.restore()
    window.view.release()
    return window.stop_code if window.stop_code is not None else code
