"""usdview plugin: a "Wrinkles" menu with "Bake current frame", "Render current frame",
"Paint..." (the paint window on usdview's stage) and "Live" (the current frame's bake,
maps and texture deformation included, shown on every frame change: app/live.py).

usdview finds it when ``PXR_PLUGINPATH_NAME`` names this folder and ``PYTHONPATH``
can import ``usdwrinkle`` (``usdwrinkle info`` prints both). usd-core has no
Usdviewq, so it is imported lazily: this module imports everywhere, and the
commands are plain functions of a usdviewApi that tests drive with a stand-in.

usdview's own Python often has pxr and nothing else (no numpy, moderngl or OpenImageIO).
Importing this module needs only the standard library and pxr. Where usdwrinkle's
dependencies import, a command runs in usdview's process. Where they do not, it runs
``usdwrinkle`` in the Python that ``USDWRINKLE_PYTHON`` names (``usdwrinkle info`` prints
it: the Python usdwrinkle is installed in) on the stage as usdview holds it (its session
layer over its root layer), and brings the result back: the bake as a sublayer of the
session layer, the render as files.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile

try:  # only inside usdview
    from pxr.Usdviewq.plugin import PluginContainer as _PluginBase
except ImportError:  # usd-core, tests
    _PluginBase = object


def plugin_dir() -> str:
    """The folder holding this plugin's plugInfo.json."""
    return os.path.dirname(os.path.abspath(__file__))


def _frame(usdview_api) -> float | None:
    frame = usdview_api.frame
    return None if frame is None or frame.IsDefault() else float(frame.GetValue())


def _targets(usdview_api, wrinkled: list[str]) -> list[str]:
    """Wrinkled meshes under the selection, or all of them when none is selected."""
    selected = [str(p.GetPath()) for p in (usdview_api.selectedPrims or [])]
    if not selected:
        return list(wrinkled)
    picked = [path for path in wrinkled
              if any(path == s or path.startswith(s.rstrip("/") + "/") for s in selected)]
    return picked or list(wrinkled)


def _in_process() -> bool:
    """usdwrinkle's dependencies import in this Python (else: out of process)."""
    import importlib.util

    return all(importlib.util.find_spec(name) is not None
               for name in ("numpy", "moderngl", "OpenImageIO", "OpenEXR"))


def _usdwrinkle_python() -> str | None:
    python = os.environ.get("USDWRINKLE_PYTHON")
    return python if python and os.path.isfile(python) else None


def _held_stage(stage, folder: str) -> str:
    """A stage file that composes the session layer over the root layer, as usdview
    shows them (its edits and variant choices included)."""
    from pxr import Sdf

    session = os.path.join(folder, "session.usda")
    stage.GetSessionLayer().Export(session)
    root = stage.GetRootLayer()
    source = root.realPath or root.identifier
    if root.dirty and not source.lower().endswith(".usdz"):
        # usdview's unsaved edits of the root layer: a copy with its asset paths (sublayers,
        # references, textures) anchored where the layer is, so they resolve from here
        from pxr import UsdUtils

        copy = Sdf.Layer.CreateAnonymous(".usda")
        copy.TransferContent(root)
        UsdUtils.ModifyAssetPaths(copy, lambda path: root.ComputeAbsolutePath(path)
                                  if path else path)
        source = os.path.join(folder, "root.usda")
        copy.Export(source)
    shot = Sdf.Layer.CreateNew(os.path.join(folder, "shot.usda"))
    shot.subLayerPaths = [session, source]
    from ..layerinfo import copy_stage_info

    copy_stage_info(root, shot)  # read from the root layer only: the held stage keeps them
    shot.Save()
    return shot.realPath


def _run_usdwrinkle(usdview_api, args: list[str]) -> bool:
    """Run ``usdwrinkle ARGS`` in USDWRINKLE_PYTHON; False (said in the status bar) when it
    cannot run or fails."""
    python = _usdwrinkle_python()
    if python is None:
        usdview_api.PrintStatus("Wrinkles: usdwrinkle's dependencies are not importable in "
                                "usdview's Python; set USDWRINKLE_PYTHON to the Python "
                                "usdwrinkle is installed in (usdwrinkle info prints it)")
        return False
    done = subprocess.run([python, "-m", "usdwrinkle", *args, "--quiet"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        lines = done.stderr.strip().splitlines()
        usdview_api.PrintStatus(f"Wrinkles: {lines[-1] if lines else 'usdwrinkle failed'}")
        return False
    return True


def _frame_args(frame: float | None) -> list[str]:
    return [] if frame is None else [f"--frames={frame!r}"]


def _bake_out_of_process(usdview_api) -> list[str]:
    from pxr import Sdf

    stage = usdview_api.stage
    frame = _frame(usdview_api)
    # the layer stays (the session layer sublayers it); the held stage goes
    folder = tempfile.mkdtemp(prefix="usdwrinkle-usdview-")
    layer = os.path.join(folder, "wrinkles.usda")
    with tempfile.TemporaryDirectory(prefix="usdwrinkle-usdview-") as held:
        ran = _run_usdwrinkle(usdview_api, ["bake", _held_stage(stage, held), layer,
                                            "--sparse", "--display-color", "amplitude",
                                            *_frame_args(frame)])
    baked = Sdf.Layer.FindOrOpen(layer) if ran and os.path.isfile(layer) else None
    if baked is None:
        if ran:
            usdview_api.PrintStatus("Wrinkles: usdwrinkle reported success but wrote no "
                                    "layer (is USDWRINKLE_PYTHON usdwrinkle's Python?)")
        import shutil

        shutil.rmtree(folder, ignore_errors=True)  # nothing of a failed bake is left
        return []
    targets = []
    baked.Traverse(Sdf.Path.absoluteRootPath, lambda path: targets.append(str(path.GetPrimPath()))
                   if path.IsPropertyPath() and path.name == "primvars:wrinkle:amplitude"
                   else None)
    stage.GetSessionLayer().subLayerPaths.insert(0, layer)
    when = "the default time" if frame is None else f"frame {frame:g}"
    usdview_api.PrintStatus(f"Wrinkles: baked {len(targets)} mesh(es) at {when} into the "
                            "session layer (displayColor shows the amplitude)")
    return sorted(targets)


def bake_current_frame(usdview_api, ctx=None) -> list[str]:
    """Bake the wrinkle primvars (and a displayColor ramp) of the current frame into the
    stage's session layer; returns the baked mesh paths."""
    if not _in_process():
        return _bake_out_of_process(usdview_api)
    from ..process.log import silenced

    with silenced():  # the status line reports the outcome (as the out-of-process bake)
        return _bake_in_process(usdview_api, ctx)


def _bake_in_process(usdview_api, ctx) -> list[str]:
    from ..app.bake import bake_frame_into
    from ..app.shot import Shot
    from ..process.errors import UsdWrinkleError

    stage = usdview_api.stage
    frame = _frame(usdview_api)
    try:
        targets = bake_frame_into(Shot(stage), stage.GetSessionLayer(), frame,
                                  pick=lambda wrinkled: _targets(usdview_api, wrinkled),
                                  ctx=ctx)
    except UsdWrinkleError as exc:
        usdview_api.PrintStatus(f"Wrinkles: {exc.one_line()}")
        return []
    if not targets:
        usdview_api.PrintStatus("Wrinkles: no mesh on this stage has WrinkleAPI applied")
        return []
    when = "the default time" if frame is None else f"frame {frame:g}"
    usdview_api.PrintStatus(f"Wrinkles: baked {len(targets)} mesh(es) at {when} into the "
                            "session layer (displayColor shows the amplitude)")
    return targets


def _open_file(path: str) -> None:
    try:
        from PySide6.QtCore import QUrl
        from PySide6.QtGui import QDesktopServices
    except ImportError:
        try:
            from PySide2.QtCore import QUrl
            from PySide2.QtGui import QDesktopServices
        except ImportError:
            QDesktopServices = None
    if QDesktopServices is not None:
        QDesktopServices.openUrl(QUrl.fromLocalFile(path))
        return
    opener = "open" if sys.platform == "darwin" else "xdg-open"
    subprocess.Popen([opener, path], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def render_current_frame(usdview_api, outdir: str | None = None, opener=_open_file,
                         width: int = 960, ctx=None) -> list[str]:
    """Render the current frame through the current camera to EXR and PNG, open the PNG."""
    from ..process.timecode import format_frame

    stage = usdview_api.stage
    frame = _frame(usdview_api)
    camera_prim = getattr(usdview_api, "cameraPrim", None)
    camera = str(camera_prim.GetPath()) if camera_prim else None
    outdir = outdir or tempfile.gettempdir()
    stem = os.path.splitext(os.path.basename(stage.GetRootLayer().identifier))[0] or "stage"
    tag = format_frame(frame)
    paths = [os.path.join(outdir, f"usdwrinkle_{stem}.{tag}{ext}") for ext in (".exr", ".png")]
    if not _in_process():
        with tempfile.TemporaryDirectory(prefix="usdwrinkle-usdview-") as folder:
            held = _held_stage(stage, folder)
            for path in paths:
                if not _run_usdwrinkle(usdview_api, [
                        "render", held, path, "--width", str(width),
                        *(["--camera", camera] if camera else []), *_frame_args(frame)]):
                    return []
        if not all(os.path.isfile(path) for path in paths):
            usdview_api.PrintStatus("Wrinkles: usdwrinkle reported success but wrote no "
                                    "frame (is USDWRINKLE_PYTHON usdwrinkle's Python?)")
            return []
        opener(paths[1])
        usdview_api.PrintStatus(f"Wrinkles: rendered {paths[0]} and {paths[1]}")
        return paths
    from ..app.options import RenderOptions
    from ..app.render import RenderJob
    from ..app.shot import Shot
    from ..process.errors import UsdWrinkleError
    from ..process.log import silenced

    shot = Shot(stage)
    options = RenderOptions(width=width, camera=camera)
    jobs = [RenderJob(shot, path, [frame], options) for path in paths]
    try:
        with silenced():  # the status line reports the outcome
            for job in jobs:
                job.check()  # both refusals before any GL work
            # one engine for both files: the phase history up to the frame is computed once
            engine = jobs[0].start_engine(ctx)
            try:
                for job in jobs:
                    job.run(ctx, engine)
            finally:
                engine.release()
    except UsdWrinkleError as exc:
        usdview_api.PrintStatus(f"Wrinkles: {exc.one_line()}")
        return []
    opener(paths[1])
    usdview_api.PrintStatus(f"Wrinkles: rendered {paths[0]} and {paths[1]}")
    return paths


#: paint windows opened in usdview's process (kept alive while open)
_PAINT_WINDOWS: list = []


def _has_pyside6() -> bool:
    """PySide6 imports, and usdview does not run on PySide2 (two Qt bindings cannot share
    one process: the window then runs out of process)."""
    import importlib.util

    return "PySide2" not in sys.modules and importlib.util.find_spec("PySide6") is not None


def _paint_prim(usdview_api) -> str | None:
    """The one selected mesh (the paint window's --prim), or None (every wrinkled mesh)."""
    selected = [p for p in (usdview_api.selectedPrims or []) if p.GetTypeName() == "Mesh"]
    return str(selected[0].GetPath()) if len(selected) == 1 else None


def paint_current_stage(usdview_api, launcher=subprocess.Popen):
    """Open the paint window on usdview's stage at its current frame (the selected mesh,
    or every wrinkled mesh).

    In usdview's process (usdwrinkle's dependencies and PySide6 import): the window
    paints usdview's stage itself, its strokes land in usdview's session layer (Save As
    writes them to a file). Otherwise ``usdwrinkle paint`` runs in USDWRINKLE_PYTHON on
    the stage as usdview holds it, its strokes saved into an overrides layer that the
    session layer sublayers; usdview reloads it whenever the window saves. Returns the
    window, or the process."""
    stage = usdview_api.stage
    frame = _frame(usdview_api)
    prim = _paint_prim(usdview_api)
    if _in_process() and _has_pyside6():
        from ..app.paint_session import PaintSession
        from ..paint.window import PaintWindow
        from ..process.errors import UsdWrinkleError

        def make_session(ctx):
            return PaintSession(stage, stage.GetSessionLayer(), None, prim=prim,
                                frame=frame, ctx=ctx,
                                in_memory=True)

        try:
            window = PaintWindow(make_session, "usdwrinkle paint (usdview)")
        except UsdWrinkleError as exc:
            usdview_api.PrintStatus(f"Wrinkles: {exc.one_line()}")
            return None
        from PySide6.QtCore import Qt

        window.setAttribute(Qt.WA_DeleteOnClose)
        window.destroyed.connect(lambda *_: _PAINT_WINDOWS.remove(window)
                                 if window in _PAINT_WINDOWS else None)
        _PAINT_WINDOWS.append(window)
        window.show()
        usdview_api.PrintStatus("Wrinkles: painting in a window of its own; strokes go to "
                                "the session layer")
        return window
    from pxr import Sdf

    python = _usdwrinkle_python()
    if python is None:
        usdview_api.PrintStatus("Wrinkles: usdwrinkle's dependencies are not importable in "
                                "usdview's Python; set USDWRINKLE_PYTHON to the Python "
                                "usdwrinkle is installed in (usdwrinkle info prints it)")
        return None
    folder = tempfile.mkdtemp(prefix="usdwrinkle-paint-")
    held = _held_stage(stage, folder)
    strokes = os.path.join(folder, "strokes.usda")
    Sdf.Layer.CreateNew(strokes).Save()
    args = [python, "-m", "usdwrinkle", "paint", held, "-o", strokes]
    if frame is not None:
        args.append(f"--frame={frame!r}")
    if prim is not None:
        args += ["--prim", prim]
    process = launcher(args)
    stage.GetSessionLayer().subLayerPaths.insert(0, strokes)
    _watch_layer(strokes, process)
    usdview_api.PrintStatus("Wrinkles: painting in usdwrinkle paint; each save shows here "
                            f"({strokes})")
    return process


def _running_qt():
    """usdview's QtCore (PySide6 or PySide2) where a Qt application runs, else None (a
    Python without Qt, or tests)."""
    try:
        from PySide6 import QtCore
    except ImportError:
        try:
            from PySide2 import QtCore
        except ImportError:
            return None
    return QtCore if QtCore.QCoreApplication.instance() is not None else None


def _watch_layer(path: str, process) -> None:
    """Reload ``path`` in usdview whenever the paint process saves it (a Qt timer, where
    usdview's Qt imports; a reload by hand otherwise)."""
    QtCore = _running_qt()
    if QtCore is None:
        return
    from pxr import Sdf

    seen = {"mtime": os.path.getmtime(path)}
    timer = QtCore.QTimer()

    def poll():
        try:
            mtime = os.path.getmtime(path)
        except OSError:
            mtime = seen["mtime"]
        if mtime != seen["mtime"]:
            seen["mtime"] = mtime
            layer = Sdf.Layer.Find(path)
            if layer is not None:
                layer.Reload()
        if process.poll() is not None:
            timer.stop()
            _PAINT_WINDOWS.remove(timer)

    timer.timeout.connect(poll)
    timer.start(1000)
    _PAINT_WINDOWS.append(timer)


#: Wrinkles > Live in this usdview: "bake" (app/live.LiveBake), "api", "timer", "seen"
_LIVE: dict = {}
#: app/live.LIVE_OPTIONS as ``usdwrinkle bake`` flags, for Live out of process
#: (tests/test_usdview_plugin.py checks that the command line reads them back the same)
LIVE_FLAGS = ("--sparse", "--maps", "normal,parallax", "--map-size", "1024")
#: how often Live looks at usdview's frame (ms); it bakes once a frame has held for one look,
#: so that dragging the time slider does not bake every frame it passes
LIVE_POLL_MS = 150


def _live_bake(usdview_api, ctx):
    """LiveBake's bake: a BakeJob here, or usdwrinkle bake in USDWRINKLE_PYTHON."""
    from ..app.live import bake_in_process

    if not _in_process():
        def bake(stage, frame, path):
            with tempfile.TemporaryDirectory(prefix="usdwrinkle-usdview-") as held:
                return _run_usdwrinkle(usdview_api, ["bake", _held_stage(stage, held), path,
                                                     *LIVE_FLAGS, *_frame_args(frame)])
        return bake
    run = bake_in_process(ctx)

    def bake(stage, frame, path):
        from ..process.errors import UsdWrinkleError
        from ..process.log import silenced

        try:
            with silenced():  # the status line reports the outcome
                return run(stage, frame, path)
        except UsdWrinkleError as exc:
            usdview_api.PrintStatus(f"Wrinkles: Live: {exc.one_line()}")
            return False
    return bake


def toggle_live(usdview_api, ctx=None) -> bool:
    """Wrinkles > Live. On: bake the current frame into the session layer and show it,
    and again whenever the frame changes (baked frames are kept and swapped back in while
    the stage is not edited). Off: take Live's layer out of the session layer, which is
    then as it was, and delete its files. Returns whether Live is on."""
    if _LIVE:
        return _stop_live(usdview_api)
    from ..app.live import LiveBake

    live = LiveBake(usdview_api.stage, _live_bake(usdview_api, ctx))
    _LIVE.update(bake=live, api=usdview_api, seen=_frame(usdview_api))
    _show_live(usdview_api, _frame(usdview_api))
    _start_live_timer(usdview_api)
    return True


def _stop_live(usdview_api) -> bool:
    timer = _LIVE.get("timer")
    if timer is not None:
        timer.stop()
    live = _LIVE["bake"]
    _LIVE.clear()
    live.stop()
    usdview_api.PrintStatus("Wrinkles: Live off (its layer is out of the session layer)")
    return False


def _show_live(usdview_api, frame) -> None:
    import time

    live = _LIVE["bake"]
    baked = live.baked
    started = time.perf_counter()
    path = live.show(frame)
    when = "the default time" if frame is None else f"frame {frame:g}"
    if path is None:
        usdview_api.PrintStatus(f"Wrinkles: Live could not bake {when}")
    elif live.baked > baked:
        usdview_api.PrintStatus(f"Wrinkles: Live at {when} (baked in "
                                f"{time.perf_counter() - started:.1f} s; "
                                f"{len(live.cache)} frame(s) kept)")
    else:
        usdview_api.PrintStatus(f"Wrinkles: Live at {when} (kept)")


def live_tick(usdview_api=None, wait: bool = True) -> None:
    """One look at usdview's frame (the Live timer calls it): a frame that differs from
    the one shown is baked and shown once it has held for one look (``wait=False``: at
    once)."""
    if not _LIVE:
        return
    usdview_api = usdview_api or _LIVE["api"]
    if usdview_api.stage is not _LIVE["bake"].stage:  # usdview opened another stage
        _stop_live(usdview_api)
        return
    frame = _frame(usdview_api)
    if frame == _LIVE["bake"].frame:
        _LIVE["seen"] = frame
        return
    if wait and frame != _LIVE["seen"]:
        _LIVE["seen"] = frame
        return
    _LIVE["seen"] = frame
    _show_live(usdview_api, frame)


def _start_live_timer(usdview_api) -> None:
    """Poll usdview's frame with a Qt timer, where usdview's Qt runs (tests tick by
    hand)."""
    QtCore = _running_qt()
    if QtCore is None:
        return
    timer = QtCore.QTimer()
    timer.timeout.connect(lambda: live_tick(usdview_api))
    timer.start(LIVE_POLL_MS)
    _LIVE["timer"] = timer


class WrinklePluginContainer(_PluginBase):
    """usdview's entry point: registers the commands and the "Wrinkles" menu."""

    def registerPlugins(self, plugRegistry, usdviewApi):  # noqa: N802, N803 (usdview API)
        self._bake = plugRegistry.registerCommandPlugin(
            "Wrinkles.BakeCurrentFrame", "Bake current frame", bake_current_frame)
        self._render = plugRegistry.registerCommandPlugin(
            "Wrinkles.RenderCurrentFrame", "Render current frame", render_current_frame)
        self._paint = plugRegistry.registerCommandPlugin(
            "Wrinkles.Paint", "Paint...", paint_current_stage)
        self._live = plugRegistry.registerCommandPlugin(
            "Wrinkles.Live", "Live (on/off)", toggle_live)

    def configureView(self, plugRegistry, plugUIBuilder):  # noqa: N802, N803 (usdview API)
        menu = plugUIBuilder.findOrCreateMenu("Wrinkles")
        menu.addItem(self._bake)
        menu.addItem(self._render)
        menu.addItem(self._paint)
        menu.addItem(self._live)


if _PluginBase is not object:  # register with usdview's plugin system
    from pxr import Tf

    Tf.Type.Define(WrinklePluginContainer)
