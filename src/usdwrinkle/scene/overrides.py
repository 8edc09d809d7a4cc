"""What a bake layer must know of the stage it overrides, read once before the first frame.

frameloop.bake_layer reads these facts with :func:`read_overrides` and hands them to the bake's
writers (outputs/layers.py, maps/, geometry/) in ``outputs.sink.BakeScene``: the writers
author the layer from plain values and never hold the stage, so the data of a bake only
flows down (scene -> GPU -> writers), as it does for a render.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from pxr import Sdf, Usd, UsdGeom, UsdShade, UsdSkel

from ..usd.values import flattened
from .material import bound_surface, corner_values, display_color, look_inputs
from .sampling import time_code
from .stage import stage_inputs


def frame_key(frame: float | None) -> float | None:
    """A frame as a dict key (None: the default time)."""
    return None if frame is None else float(frame)


@dataclass(frozen=True)
class SourceLook:
    """The material a mesh binds for one purpose: its path, its UsdPreviewSurface's path
    when that lies inside it, and whether that surface's ``inputs:normal`` is connected."""

    material: str | None = None
    surface: str | None = None
    normal_mapped: bool = False
    #: the surface's inputs as scene/material.look_inputs reads them (maps/mtlx.py)
    inputs: tuple = ()


@dataclass(frozen=True)
class CarriedPrimvar:
    """A primvar of a coarse mesh that its fine render mesh carries (geometry/layer.py).
    ``value``: a constant primvar's flattened value; else its values per triangle corner
    (m, 3, c), or None where they cannot be read per corner."""

    name: str
    type_name: object  # Sdf.ValueTypeName
    constant: bool
    value: object


@dataclass(frozen=True)
class MeshTransform:
    """A mesh's local transform, as a layer repeats it on another prim beside the mesh:
    ``reset`` (the mesh resets the transform stack); ``static`` (the default-time matrix)
    when it does not move, else ``samples`` (frame_key -> matrix) at the bake's frames."""

    reset: bool
    moves: bool
    static: object = None
    samples: dict = field(default_factory=dict)

    def at(self, frame: float):
        return self.samples[frame_key(frame)]


@dataclass(frozen=True)
class MeshFacts:
    """One wrinkled mesh as its overrides need it.

    ``skel_roots``: the SkelRoots above it. ``look``: its bound material for all
    purposes (a SourceLook). ``looks``: for "preview" and "full", where that purpose
    resolves another material than ``look``'s, its SourceLook (look_for).
    ``display_color``: its first displayColor (linear). ``siblings``: the names of the
    prims beside it (a new prim needs a free name). ``uniform``: its authored doubleSided
    and orientation. ``transform``: None when it authors no xformOps and no reset. ``primvars``: its
    CarriedPrimvars (read only when the bake asks for them). ``face_counts``: its
    faceVertexCounts (the length of a faceVarying primvar the bake authors)."""

    path: str
    skel_roots: tuple = ()
    look: SourceLook = SourceLook()
    looks: dict = field(default_factory=dict)
    display_color: tuple = ()
    siblings: frozenset = frozenset()
    uniform: dict = field(default_factory=dict)
    transform: MeshTransform | None = None
    primvars: tuple = ()
    face_counts: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    #: the nearest ancestor that binds a material with bindMaterialAs =
    #: strongerThanDescendants (for any purpose): a binding the bake authors on the mesh
    #: never resolves under it
    stronger_ancestor: str | None = None

    def look_for(self, purpose: str) -> SourceLook:
        """The material ``purpose`` resolves: its own binding, else the all-purpose one."""
        return self.looks.get(purpose, self.look)


@dataclass(frozen=True)
class StageFacts:
    """The input stage as a bake layer overrides it: ``path`` (the layer sublayers it by a
    relative path), its time codes and frames per second, ``layer_info`` (upAxis and
    metersPerUnit where its root layer authors them), ``default_prim`` (the root layer's
    defaultPrim name, or "") and ``default_prim_path`` (the stage's default prim, when it
    exists), ``inputs`` (scene/inputs.StageInputs: every file it reads, which no output
    may overwrite) and ``meshes`` (path -> MeshFacts)."""

    path: str
    time_codes_per_second: float = 24.0
    frames_per_second: float = 24.0
    layer_info: dict = field(default_factory=dict)
    default_prim: str = ""
    default_prim_path: str | None = None
    inputs: object = None
    meshes: dict = field(default_factory=dict)
    #: the names of the prims the stage already has in the bake's material scope
    #: (<default prim>/WrinkleMaterials): a bake of a bake must not define them again
    material_names: frozenset = frozenset()
    #: the composition the stage was opened with (scene/composition.py): absolute paths of
    #: the layers over it, strongest first, and (prim, set, name) variant selections; a
    #: bake layer records them, so that it renders as the composed stage did
    sublayers: tuple = ()
    variant_selections: tuple = ()
    #: the stage's own frame range (start, end), or None: automatic framing of a bake's
    #: layer takes its bounds over it, not over the baked frames only
    shot_range: tuple | None = None


def read_overrides(stage: Usd.Stage, stage_path: str, records: dict, frames,
                   carry_primvars: bool = False) -> StageFacts:
    """The facts of ``stage`` (at ``stage_path``) that a layer overriding the meshes of
    ``records`` (path -> MeshRecord) at ``frames`` needs; each mesh's primvars too when
    ``carry_primvars`` (the displaced render meshes carry them)."""
    root = stage.GetRootLayer()
    default = stage.GetDefaultPrim()
    return StageFacts(
        path=stage_path,
        time_codes_per_second=stage.GetTimeCodesPerSecond(),
        frames_per_second=stage.GetFramesPerSecond(),
        layer_info={key: root.pseudoRoot.GetInfo(key) for key in ("upAxis", "metersPerUnit")
                    if root.pseudoRoot.HasInfo(key)},
        default_prim=root.defaultPrim or "",
        default_prim_path=str(default.GetPath()) if default else None,
        inputs=stage_inputs(stage),
        meshes={path: _mesh_facts(stage.GetPrimAtPath(path), record, tuple(frames),
                                  carry_primvars)
                for path, record in records.items()},
        material_names=_material_names(stage, default),
        **_composition(stage))


def _composition(stage: Usd.Stage) -> dict:
    from .composition import recorded

    sublayers, selections = recorded(stage)
    shot_range = None
    if stage.HasAuthoredTimeCodeRange():
        shot_range = (float(stage.GetStartTimeCode()), float(stage.GetEndTimeCode()))
    return {"sublayers": tuple(sublayers), "variant_selections": tuple(selections),
            "shot_range": shot_range}


def _material_names(stage: Usd.Stage, default) -> frozenset:
    """The children of the stage's WrinkleMaterials scopes (where a bake defines its
    materials: under the default prim, or at the root), by name."""
    roots = [Sdf.Path.absoluteRootPath] + ([default.GetPath()] if default else [])
    names = set()
    for root in roots:
        scope = stage.GetPrimAtPath(root.AppendChild("WrinkleMaterials"))
        if scope:
            names.update(child.GetName() for child in scope.GetAllChildren())
    return frozenset(names)


def _look(prim: Usd.Prim, purpose: str) -> SourceLook:
    material, shader = bound_surface(prim, purpose)
    surface = shader.GetPath() if shader is not None and material and \
        shader.GetPath().HasPrefix(material.GetPath()) else None
    normal = shader.GetInput("normal") if surface is not None else None
    return SourceLook(str(material.GetPath()) if material else None,
                      str(surface) if surface is not None else None,
                      bool(normal) and normal.HasConnectedSource(),
                      look_inputs(shader) if shader is not None else ())


def _mesh_facts(prim: Usd.Prim, record, frames: tuple, carry_primvars: bool) -> MeshFacts:
    look = _look(prim, UsdShade.Tokens.allPurpose)
    looks = {purpose: other for purpose in ("preview", "full")
             if (other := _look(prim, purpose)).material != look.material}
    mesh = UsdGeom.Mesh(prim)
    uniform = {attr.GetName(): attr.Get()
               for attr in (mesh.GetDoubleSidedAttr(), mesh.GetOrientationAttr())
               if attr.HasAuthoredValue()}
    return MeshFacts(
        path=str(prim.GetPath()),
        skel_roots=tuple(str(a.GetPath()) for a in _ancestors(prim) if a.IsA(UsdSkel.Root)),
        look=look,
        looks=looks,
        display_color=tuple(float(c) for c in display_color(prim, Usd.TimeCode.Default())),
        siblings=frozenset(prim.GetParent().GetAllChildrenNames()),
        uniform=uniform,
        transform=_transform(UsdGeom.Xformable(prim), frames),
        primvars=_primvars(prim, record.topology) if carry_primvars else (),
        face_counts=np.asarray(mesh.GetFaceVertexCountsAttr().Get(Usd.TimeCode.EarliestTime())
                               or [], np.int64),
        stronger_ancestor=_stronger_ancestor(prim))


def _stronger_ancestor(prim: Usd.Prim) -> str | None:
    """The nearest ancestor of ``prim`` with a direct binding of strength
    strongerThanDescendants (UsdShade's rule: it wins over the bindings below it)."""
    for ancestor in _ancestors(prim):
        for rel in ancestor.GetRelationships():
            name = rel.GetName()
            if not name.startswith("material:binding") or name.startswith(
                    "material:binding:collection") or not rel.GetTargets():
                continue
            if UsdShade.MaterialBindingAPI.GetMaterialBindingStrength(rel) == \
                    UsdShade.Tokens.strongerThanDescendants:
                return str(ancestor.GetPath())
    return None


def _ancestors(prim: Usd.Prim):
    prim = prim.GetParent()
    while prim and not prim.IsPseudoRoot():
        yield prim
        prim = prim.GetParent()


def _transform(xformable: UsdGeom.Xformable, frames: tuple) -> MeshTransform | None:
    has_ops, reset = bool(xformable.GetOrderedXformOps()), xformable.GetResetXformStack()
    if not (has_ops or reset):
        return None
    if has_ops and xformable.TransformMightBeTimeVarying():
        return MeshTransform(reset, True, samples={
            frame_key(f): xformable.GetLocalTransformation(time_code(f)) for f in frames})
    return MeshTransform(reset, False, xformable.GetLocalTransformation(Usd.TimeCode.Default()))


#: primvars a fine mesh does not carry: the wrinkle fields, skinning, the rest pose, normals
SKIPPED_PRIMVARS = ("primvars:wrinkle:", "primvars:skel:", "primvars:rest", "primvars:normals")


def _primvars(prim: Usd.Prim, topology) -> tuple:
    """The primvars a fine mesh carries, at the earliest time: constant ones flattened,
    the others per triangle corner (array-valued ones only)."""
    time = Usd.TimeCode.EarliestTime()
    carried = []
    for primvar in UsdGeom.PrimvarsAPI(prim).GetPrimvarsWithValues():
        name = primvar.GetAttr().GetName()
        if name.startswith(SKIPPED_PRIMVARS):
            continue
        type_name = primvar.GetTypeName()
        if primvar.GetInterpolation() == UsdGeom.Tokens.constant:
            carried.append(CarriedPrimvar(name, type_name, True,
                                          flattened(primvar, time)))
            continue
        corners = corner_values(primvar, topology, time) if type_name.isArray else None
        carried.append(CarriedPrimvar(name, type_name, False, corners))
    return tuple(carried)
