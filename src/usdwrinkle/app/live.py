"""Live wrinkles: the current frame's bake shown in a stage's session layer, frame by frame
(usdview's Wrinkles > Live).

On every frame it is shown, :class:`LiveBake` bakes that frame, exactly as ``usdwrinkle bake
--frames F --sparse --maps normal,parallax --map-size 1024`` does (the wrinkle primvars,
the normal maps and the parallax maps with their MaterialX network, so that Storm shows
the texture moving with the folds), into a layer of its own, and makes that layer the
session layer's strongest sublayer in place of the previous frame's. Baked frames are kept:
scrubbing back to one swaps its layer in without baking. Any edit of the stage other than
its own swaps (a painted stroke, a changed width) empties that cache, because the baked
frames no longer show the stage. :meth:`LiveBake.stop` takes its layer out of the session
layer, which is then as it was, and deletes its files.

Each bake reads the stage as it is shown, without the Live layers themselves: a stage on
the same root layer, with a copy of the session layer that lacks them. The bake itself is
the caller's (``bake(stage, frame, layer_path) -> bool``): in usdview's process a BakeJob
(:func:`bake_in_process`), or ``usdwrinkle bake`` run in another Python where usdview's
lacks usdwrinkle's dependencies. This module imports only the standard library and pxr,
so that both can use it.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable
from typing import Any

#: what each Live frame bakes (BakeOptions' fields): the overs only, with the maps
#: that Storm shows, the texture deformation included
LIVE_OPTIONS: dict[str, Any] = {"sparse": True, "maps": ("normal", "parallax"),
                                "map_size": 1024}

Bake = Callable[[Any, "float | None", str], bool]


class LiveBake:
    """Live wrinkles on ``stage`` (a Usd.Stage, shown with its session layer). ``bake``
    writes one frame of a stage into a layer file and says whether it did. Files go to
    ``folder`` (default: a new temporary folder, removed by stop())."""

    def __init__(self, stage: Any, bake: Bake, folder: str | None = None):
        from pxr import Tf, Usd

        self.stage = stage
        self.bake = bake
        self.folder = folder or tempfile.mkdtemp(prefix="usdwrinkle-live-")
        self._own_folder = folder is None
        #: frame -> the layer file that holds its bake
        self.cache: dict[float | None, str] = {}
        #: the Live layer the session layer holds now (None: none yet)
        self.current: str | None = None
        self.frame: float | None = None
        self.baked = 0  # frames baked (not taken from the cache)
        self._swapping = False
        self._listener = Tf.Notice.Register(Usd.Notice.ObjectsChanged, self._changed, stage)

    # -- the stage as shown, without Live -----------------------------------------------
    def _live_paths(self) -> set[str]:
        """Every Live layer the session layer may hold: the kept ones and the one shown
        (which an edit drops from the cache while it is still shown)."""
        return set(self.cache.values()) | ({self.current} if self.current else set())

    def source_stage(self) -> Any:
        """The stage as it is shown, without the Live layers: the same root layer (its
        unsaved edits included) and a copy of the session layer without them."""
        from pxr import Sdf, Usd

        session = self.stage.GetSessionLayer()
        copy = Sdf.Layer.CreateAnonymous("usdwrinkle-live-session.usda")
        copy.TransferContent(session)
        live = self._live_paths()
        copy.subLayerPaths = [p for p in session.subLayerPaths if p not in live]
        return Usd.Stage.Open(self.stage.GetRootLayer(), copy)

    # -- frames -------------------------------------------------------------------------
    def layer_for(self, frame: float | None) -> str | None:
        """The layer holding ``frame``'s bake: the cached one, or a new bake (None when
        the bake failed; the caller's bake said why)."""
        if frame in self.cache:
            return self.cache[frame]
        from ..process.timecode import format_frame

        # a new name for every bake: a layer the session layer holds is never rewritten
        path = os.path.join(self.folder, f"live.{self.baked + 1}.{format_frame(frame)}.usda")
        if not self.bake(self.source_stage(), frame, path) or not os.path.isfile(path):
            return None
        self.cache[frame] = path
        self.baked += 1
        return path

    def show(self, frame: float | None) -> str | None:
        """Show ``frame``'s bake in the session layer (baking it unless cached); returns
        its layer, None when it could not be baked (the previous frame's is taken out)."""
        path = self.layer_for(frame)
        self._swap(path)
        self.frame = frame
        return path

    def _swap(self, path: str | None) -> None:
        session = self.stage.GetSessionLayer()
        paths = [p for p in session.subLayerPaths if p != self.current]
        if path is not None:
            paths.insert(0, path)
        self._swapping = True
        try:
            if list(session.subLayerPaths) != paths:
                session.subLayerPaths = paths
        finally:
            self._swapping = False
        self.current = path

    def _changed(self, notice: Any, sender: Any) -> None:
        """An edit of the stage that is not Live's own swap: the cached bakes no longer
        show it (the one shown stays until the next frame replaces it)."""
        if not self._swapping:
            self.cache.clear()

    def stop(self) -> None:
        """Take the Live layer out of the session layer (which is then as it was before
        Live, plus any edit made meanwhile) and delete Live's files."""
        if self._listener is not None:
            self._listener.Revoke()
            self._listener = None
        self._swap(None)
        self.cache.clear()
        if self._own_folder:
            shutil.rmtree(self.folder, ignore_errors=True)


def bake_in_process(ctx: Any = None) -> Bake:
    """A ``bake`` for LiveBake that runs a BakeJob in this process (usdwrinkle's
    dependencies import here)."""
    def bake(stage: Any, frame: float | None, path: str) -> bool:
        from .bake import BakeJob
        from .options import BakeOptions
        from .shot import Shot

        BakeJob(Shot(stage), path, None if frame is None else [frame],
                BakeOptions(**LIVE_OPTIONS)).run(ctx)
        return True

    return bake
