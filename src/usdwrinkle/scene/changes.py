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


class DirtyBits:
    """As in pxr/imaging/hd/changeTracker.h (same bit positions)."""

    CLEAN = 0
    #: the bound material, its textures and texture coordinates (DirtyMaterialId)
    DIRTY_MATERIAL = 1 << 2
    DIRTY_VISIBILITY = 1 << 3
    #: the posed points of a frame (sampled per frame)
    DIRTY_POINTS = 1 << 5
    #: the wrinkle parameters: width, q, profiles, amplitude scale, relax iterations, and
    #: baked wave fields
    DIRTY_PRIMVAR = 1 << 6
    #: faces, rest pose, skinning: everything is rebuilt, and the phase history restarts
    DIRTY_TOPOLOGY = 1 << 8
    DIRTY_TRANSFORM = 1 << 9
    #: what a new frame dirties: time-varying state, re-sampled
    FRAME = DIRTY_POINTS | DIRTY_TRANSFORM | DIRTY_VISIBILITY
    ALL = DIRTY_MATERIAL | DIRTY_VISIBILITY | DIRTY_POINTS | DIRTY_PRIMVAR | DIRTY_TOPOLOGY \
        | DIRTY_TRANSFORM


#: mesh properties whose change rebuilds the mesh (topology, rest pose, skinning)
TOPOLOGY_PROPERTIES = {"faceVertexCounts", "faceVertexIndices", "holeIndices", "orientation",
                       "points", "primvars:rest", "purpose"}


def classify(name: str) -> int:
    """The dirty bits of a mesh whose property ``name`` changed."""
    if name in TOPOLOGY_PROPERTIES or name.startswith("skel:") \
            or name.startswith("primvars:skel:"):
        return DirtyBits.DIRTY_TOPOLOGY
    if name.startswith("primvars:wrinkle:") or name.startswith("wrinkle:"):
        return DirtyBits.DIRTY_PRIMVAR
    if name.startswith("material:binding") or name.startswith("primvars:"):
        return DirtyBits.DIRTY_MATERIAL  # displayColor, texture coordinates
    if name.startswith("xformOp") or name == "xformOpOrder":
        return DirtyBits.DIRTY_TRANSFORM
    if name == "visibility":
        return DirtyBits.DIRTY_VISIBILITY
    return DirtyBits.CLEAN


class ChangeTracker:
    """Collects the paths that ``Usd.Notice.ObjectsChanged`` reports for one stage."""

    def __init__(self, stage: Usd.Stage):
        self.stage = stage
        #: prim or property paths whose composition changed (added, removed, re-typed)
        self.resynced: set[Sdf.Path] = set()
        #: property paths whose values or metadata changed
        self.changed: set[Sdf.Path] = set()
        self._listener = Tf.Notice.Register(Usd.Notice.ObjectsChanged, self._on_changed,
                                            stage)

    def _on_changed(self, notice, sender) -> None:
        self.resynced.update(notice.GetResyncedPaths())
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
