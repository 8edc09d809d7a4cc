"""usdwrinkle paint STAGE [-o LAYER]: the paint window (paint/window.py)."""
from __future__ import annotations

from ..errors import UsdWrinkleError


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "paint", help="paint wrinkle vectors q and the width W on the posed mesh, live",
        description="Open the paint window on the stage's wrinkled meshes: the left button "
                    "combs q along the stroke (rest space, whatever the pose), the folds "
                    "follow at once; W, amplitude, slack and the cloth preset are live "
                    "controls. Ctrl+S writes the strokes as overs through the WrinkleAPI. "
                    "Needs PySide6 (pip install 'usdwrinkle[paint]') and a display.")
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


def check_display() -> None:
    """Refuse, in one line, a Linux session with no display: Qt's xcb platform would
    abort the process instead."""
    import os
    import sys

    if sys.platform.startswith("linux") and not os.environ.get("QT_QPA_PLATFORM") and \
            not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        raise UsdWrinkleError("the paint window needs a display (no DISPLAY is set): run it "
                              "in a desktop session, or under xvfb-run to script it")


def run(args) -> int:
    from ..app.environment import require_schema
    from ..app.frames import check_time_code
    from ..app.paint import PaintSession, check_paintable, open_paint_stage

    require_schema()
    size = _size(args.size)
    if args.frame is not None:
        check_time_code(args.frame, "`frame`")
    stage, layer, save = open_paint_stage(args.stage, args.output)
    check_paintable(stage, args.prim, args.all_meshes)  # before a window opens
    check_display()
    from ..paint.window import run_window  # a one-line error without PySide6

    def make_session(ctx):
        return PaintSession(stage, layer, save, prim=args.prim, frame=args.frame,
                            camera=args.camera, all_meshes=args.all_meshes, ctx=ctx)

    return run_window(make_session, f"usdwrinkle paint {args.stage}", size)
