"""usdwrinkle paint STAGE [-o LAYER]: the paint window (paint/window.py)."""
from __future__ import annotations

import os

from ..process.errors import UsdWrinkleError


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "paint", help="paint wrinkle vectors q and the width W on the posed mesh, live",
        description="Open the paint window on the stage's wrinkled meshes: the left button "
                    "combs q along the stroke (rest space, whatever the pose), the folds "
                    "follow at once; W, amplitude, slack and the cloth preset are live "
                    "controls. Ctrl+S writes the strokes as overs through the WrinkleAPI. "
                    "In the window, H lists every key and mouse binding, View > Display "
                    "shows the painted amount and W. Needs PySide6 (pip install "
                    "'usdwrinkle[paint]') and a display.")
    p.add_argument("stage", help="the USD stage (.usda, .usdc, .usdz)")
    p.add_argument("-o", "--output", metavar="LAYER",
                   help="the layer the strokes are saved into: a new one sublayers the stage "
                        "(render it as the shot); an existing paint layer is painted further; "
                        "any other existing layer is written as an overrides layer (as apply "
                        "-o). Default: the stage's root layer, edited in place")
    p.add_argument("--prim", metavar="PATH", help="paint this wrinkled mesh only")
    p.add_argument("--frame", type=float, metavar="F",
                   help="the frame shown first (default: the stage's last)")
    p.add_argument("--camera", metavar="PRIM",
                   help="the stage camera the view can look through (View: stage camera), as "
                        "render --camera")
    p.add_argument("--all-meshes", action="store_true",
                   help="paint every Mesh, as if WrinkleAPI were applied (as render)")
    p.add_argument("--size", default="1200x700", metavar="WxH",
                   help="the window's size (default 1200x700)")
    p.set_defaults(run=run)


def _size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UsdWrinkleError(f"--size {text!r} is not WIDTHxHEIGHT (1200x700)") from None
    if not (200 <= width <= 16384 and 150 <= height <= 16384):
        raise UsdWrinkleError(f"--size {text} must be between 200x150 and 16384x16384")
    return width, height


#: Qt platforms that cannot show a QOpenGLWidget (Qt says "QOpenGLWidget is not
#: supported" and the window then waits for a GL context forever)
_NO_GL_PLATFORMS = ("offscreen", "minimal", "vnc", "linuxfb", "vkkhrdisplay")


def check_display() -> None:
    """Refuse, in one line, a session where the window cannot open: no display, a display
    that cannot be reached (Qt's xcb platform aborts the process: SIGABRT), or a Qt
    platform without OpenGL widgets (QT_QPA_PLATFORM=offscreen hangs)."""
    import os
    import sys

    platform = os.environ.get("QT_QPA_PLATFORM", "").split(":")[0].strip().lower()
    if platform in _NO_GL_PLATFORMS:
        raise UsdWrinkleError(f"the paint window cannot open on Qt's '{platform}' platform "
                              "(QT_QPA_PLATFORM): it has no OpenGL view; unset "
                              "QT_QPA_PLATFORM, or run under xvfb-run to script the window")
    if not sys.platform.startswith("linux") or platform not in ("", "xcb"):
        return
    display = os.environ.get("DISPLAY")
    if not display:
        if os.environ.get("WAYLAND_DISPLAY") and not platform:
            return
        raise UsdWrinkleError("the paint window needs a display (no DISPLAY is set): run it "
                              "in a desktop session, or under xvfb-run to script it")
    reason = x_display_error(display)
    if reason is not None:
        raise UsdWrinkleError(f"the paint window cannot reach the X display "
                              f"DISPLAY={display!r} ({reason}): start the X server, fix "
                              "DISPLAY, or run under xvfb-run")


#: connections tried before "no X server answers there" (a loaded Xvfb refused one now and
#: then: a CI run's paint test saw the window stop before it opened)
X_CONNECT_ATTEMPTS = 4


def x_display_error(display: str) -> str | None:
    """Why an X client cannot connect to ``display`` (None: it can), asked of libxcb, the
    library Qt's xcb platform connects through."""
    import ctypes
    import ctypes.util

    name = ctypes.util.find_library("xcb") or "libxcb.so.1"
    try:
        xcb = ctypes.CDLL(name)
    except OSError:
        return None  # no libxcb: Qt's xcb platform says what it lacks itself
    xcb.xcb_connect.restype = ctypes.c_void_p
    xcb.xcb_connect.argtypes = [ctypes.c_char_p, ctypes.c_void_p]
    xcb.xcb_connection_has_error.argtypes = [ctypes.c_void_p]
    xcb.xcb_disconnect.argtypes = [ctypes.c_void_p]
    import time

    for attempt in range(X_CONNECT_ATTEMPTS):
        connection = xcb.xcb_connect(display.encode(), None)
        try:
            code = xcb.xcb_connection_has_error(connection) if connection else 1
        finally:
            if connection:
                xcb.xcb_disconnect(connection)
        if code != 1 or attempt == X_CONNECT_ATTEMPTS - 1:
            break
        time.sleep(0.25)  # a busy X server refuses a connection now and then: ask again
    reasons = {1: "no X server answers there", 2: "an extension is missing",
               3: "out of memory", 4: "a request was too long", 5: "the display name is "
               "not valid", 6: "no screen of that number"}
    return None if code == 0 else reasons.get(code, f"xcb error {code}")


def run(args) -> int:
    from ..app.environment import require_schema
    from ..app.frames import check_time_code
    from ..app.paint_session import PaintSession, check_frame, check_paintable, open_paint_stage

    require_schema()
    size = _size(args.size)
    if args.frame is not None:
        check_time_code(args.frame, "`frame`")
    stage, layer, save = open_paint_stage(args.stage, args.output)
    # before a window opens
    check_paintable(stage, args.prim, args.all_meshes, args.camera)
    check_frame(args.frame, stage)
    check_display()
    from ..paint.window import run_window  # a one-line error without PySide6

    def make_session(ctx):
        return PaintSession(stage, layer, save, prim=args.prim, frame=args.frame,
                            camera=args.camera, all_meshes=args.all_meshes, ctx=ctx)

    return run_window(make_session, f"usdwrinkle paint {args.stage}", size,
                      debug=bool(getattr(args, "debug", False)),
                      stage_path=os.path.abspath(args.stage))
