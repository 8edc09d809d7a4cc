"""The one protocol of a bake's writers: the wrinkle primvars (outputs/layers.py), the
wrinkle maps (maps/bake.py) and the displaced render meshes (geometry/bake.py).

frameloop.bake_layer makes one ``Sdf.Layer`` and drives every sink the same way::

    sink.begin(layer)                              # once, before the first frame
    sink.add_frame(frame, fields, resources)       # each frame, in time order
    metadata = sink.finish()                       # author what spans the frames
    ... the layer is exported under a temporary name ...
    sink.commit()                                  # move side files into place
    sink.release()                                 # always, also after an error

A frame reaches the sinks one way: ``fields`` maps each wrinkled mesh to the
``aovs.WrinkleFields`` the loop read back once; ``resources`` maps every mesh to its GPU
tables (``render.resources.MeshResources``), which the GPU sinks (maps, geometry) draw
from and through which any other read-back goes. No sink holds the engine.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol


@dataclass(frozen=True)
class BakeScene:
    """What the writers of one bake are given, gathered once by frameloop.bake_layer.

    ``facts``: what the layer needs to know of the input stage, read before the first
    frame (scene/overrides.StageFacts: its path, metadata, default prim, input files,
    and per wrinkled mesh its SkelRoots, materials, transform, sibling names and
    primvars); no writer holds the stage. ``output``: the layer's path (side files are
    placed beside it). ``frames``: the bake's frames, in order. ``meshes``: path ->
    MeshRecord of the wrinkled meshes the layer overrides; ``records``: path ->
    MeshRecord of every mesh of the stage. ``ctx``: the moderngl context the GPU sinks
    draw with. ``corner_primvar(path, name)``: the scene's reader of a primvar per
    triangle corner (the maps' UVs). ``local_to_world(path)``: a mesh's transform at the
    frame being added (the parallax maps are in world space)."""

    facts: object
    output: str
    frames: tuple = ()
    meshes: dict = field(default_factory=dict)
    records: dict = field(default_factory=dict)
    ctx: object = None
    corner_primvar: Callable | None = None
    local_to_world: Callable | None = None


class BakeSink(Protocol):
    """A writer of a bake (see the module's docstring for the order of the calls)."""

    def begin(self, layer) -> None: ...

    def add_frame(self, frame: float, fields: dict, resources: dict) -> None: ...

    def finish(self) -> dict:
        """Author what spans the frames; returns the metadata recorded in the layer's
        ``customLayerData["usdwrinkle"]`` (merged over every sink's)."""
        ...

    def commit(self) -> None: ...

    def release(self) -> None: ...
