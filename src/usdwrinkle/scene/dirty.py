"""Hydra's dirty bits (pxr/imaging/hd/changeTracker.h) and the property classifier, free
of pxr: the render delegate reads them (render/delegate.py) and must not import USD.
scene/changes.py turns ``Usd.Notice.ObjectsChanged`` into these bits.
"""
from __future__ import annotations


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
