"""Change tracking as Hydra's HdChangeTracker does it: edits of the stage become dirty
bits per rprim, and only what is dirty is synced again.

:class:`ChangeTracker` listens to ``Usd.Notice.ObjectsChanged`` on one stage and
collects the changed paths. :func:`classify` maps a changed property to the dirty bits
of the meshes it affects; the scene delegate (``StageSceneDelegate.process_changes``)
refreshes its records from them, and the render delegate (``Mesh.sync``) re-uploads only
those parts. What varies per frame (posed points, transforms, visibility) is sampled
at every frame anyway, as Hydra re-pulls time-varying state on a time change.
"""
from __future__ import annotations

from pxr import Sdf, Tf, Usd


class ChangeTracker:
    """Collects the paths that ``Usd.Notice.ObjectsChanged`` reports for one stage."""

    def __init__(self, stage: Usd.Stage):
        self.stage = stage
        #: prim or property paths whose composition changed (added, removed, re-typed)
        self.resynced: set[Sdf.Path] = set()
        #: property paths whose values or metadata changed
        self.changed: set[Sdf.Path] = set()
        #: how many notices resynced a prim (never reset): what is cached from a walk of
        #: the stage (the camera, the lights) is valid while this stays the same
        self.prim_resyncs = 0
        #: how many notices arrived (never reset): what is cached from the stage's values
        #: (the lights of a stage whose lights do not vary in time) is valid while this
        #: stays the same
        self.notices = 0
        self._listener = Tf.Notice.Register(Usd.Notice.ObjectsChanged, self._on_changed,
                                            stage)

    def _on_changed(self, notice, sender) -> None:
        self.notices += 1
        resynced = notice.GetResyncedPaths()
        if any(not path.IsPropertyPath() for path in resynced):
            self.prim_resyncs += 1
        self.resynced.update(resynced)
        self.changed.update(notice.GetChangedInfoOnlyPaths())

    def take(self) -> tuple[set, set]:
        """(resynced paths, changed paths) since the last call."""
        resynced, changed = self.resynced, self.changed
        self.resynced, self.changed = set(), set()
        return resynced, changed

    def revoke(self) -> None:
        if self._listener is not None:
            self._listener.Revoke()
            self._listener = None
