"""usdview plugin: a "Wrinkles" menu with "Bake current frame" and "Render current frame".

usdview finds it when ``PXR_PLUGINPATH_NAME`` names this folder and ``PYTHONPATH``
can import ``usdwrinkle`` (``usdwrinkle info`` prints both). usd-core has no
Usdviewq, so it is imported lazily: this module imports everywhere, and the
commands are plain functions of a usdviewApi that tests drive with a stand-in.
"""
from __future__ import annotations

import math
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


def _frame(usdview_api) -> float:
    frame = usdview_api.frame
    return math.nan if frame is None or frame.IsDefault() else float(frame.GetValue())


def _targets(usdview_api, wrinkled: list[str]) -> list[str]:
    """Wrinkled meshes under the selection, or all of them when none is selected."""
    selected = [str(p.GetPath()) for p in (usdview_api.selectedPrims or [])]
    if not selected:
        return list(wrinkled)
    picked = [path for path in wrinkled
              if any(path == s or path.startswith(s.rstrip("/") + "/") for s in selected)]
    return picked or list(wrinkled)


def bake_current_frame(usdview_api, ctx=None) -> list[str]:
    """Bake the wrinkle primvars (and a displayColor ramp) of the current frame into the
    stage's session layer; returns the baked mesh paths."""
    from ..engine import WrinkleEngine
    from ..errors import UsdWrinkleError
    from ..outputs.layers import LayerBaker

    stage = usdview_api.stage
    frame = _frame(usdview_api)
    messages = []
    try:
        engine = WrinkleEngine(stage, warn=messages.append, ctx=ctx)
    except UsdWrinkleError as exc:
        usdview_api.PrintStatus(f"Wrinkles: {exc.one_line()}")
        return []
    try:
        targets = _targets(usdview_api, engine.wrinkled_paths)
        if not targets:
            usdview_api.PrintStatus("Wrinkles: no mesh on this stage has WrinkleAPI applied")
            return []
        engine.compute_frame(frame)
        records = {path: engine.meshes[path] for path in targets}
        baker = LayerBaker(stage, stage.GetRootLayer().realPath or "", records,
                           engine.meshes, display_color="amplitude",
                           layer=stage.GetSessionLayer())
        baker.add_frame(frame, {path: engine.read_fields(path) for path in targets})
    except UsdWrinkleError as exc:
        usdview_api.PrintStatus(f"Wrinkles: {exc.one_line()}")
        return []
    finally:
        engine.release()
    when = "the default time" if math.isnan(frame) else f"frame {frame:g}"
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
    from ..engine import WrinkleEngine
    from ..errors import UsdWrinkleError
    from ..outputs.images import write_image
    from ..timecode import format_frame

    stage = usdview_api.stage
    frame = _frame(usdview_api)
    camera_prim = getattr(usdview_api, "cameraPrim", None)
    camera = str(camera_prim.GetPath()) if camera_prim else None
    outdir = outdir or tempfile.gettempdir()
    stem = os.path.splitext(os.path.basename(stage.GetRootLayer().identifier))[0] or "stage"
    tag = format_frame(frame)
    paths = [os.path.join(outdir, f"usdwrinkle_{stem}.{tag}{ext}") for ext in (".exr", ".png")]
    try:
        engine = WrinkleEngine(stage, camera=camera, warn=lambda m: None, ctx=ctx)
        try:
            w, h = engine.resolution(width, None, frame)
            buffers = engine.render_frame(frame, w, h)
        finally:
            engine.release()
        for path in paths:
            write_image(path, buffers)
    except UsdWrinkleError as exc:
        usdview_api.PrintStatus(f"Wrinkles: {exc.one_line()}")
        return []
    opener(paths[1])
    usdview_api.PrintStatus(f"Wrinkles: rendered {paths[0]} and {paths[1]}")
    return paths


class WrinklePluginContainer(_PluginBase):
    """usdview's entry point: registers the commands and the "Wrinkles" menu."""

    def registerPlugins(self, plugRegistry, usdviewApi):  # noqa: N802, N803 (usdview API)
        self._bake = plugRegistry.registerCommandPlugin(
            "Wrinkles.BakeCurrentFrame", "Bake current frame", bake_current_frame)
        self._render = plugRegistry.registerCommandPlugin(
            "Wrinkles.RenderCurrentFrame", "Render current frame", render_current_frame)

    def configureView(self, plugRegistry, plugUIBuilder):  # noqa: N802, N803 (usdview API)
        menu = plugUIBuilder.findOrCreateMenu("Wrinkles")
        menu.addItem(self._bake)
        menu.addItem(self._render)


if _PluginBase is not object:  # register with usdview's plugin system
    from pxr import Tf

    Tf.Type.Define(WrinklePluginContainer)
