"""The fine render mesh in the bake layer, with the coarse mesh as its proxy.

For a coarse mesh ``/.../Shirt``, the layer defines ``/.../Shirt_wrinkled`` beside it:

- ``purpose = "render"``, ``proxyPrim`` targeting the coarse mesh, which gets
  ``purpose = "proxy"``: viewers show the light mesh while you work, renderers render the
  wrinkled one (UsdGeomImageable's purpose convention);
- triangles of the subdivided rest topology (the same at every frame),
  ``subdivisionScheme = "none"``; time-sampled ``points``, ``normals`` (vertex) and
  ``extent``, in the coarse mesh's local space;
- the coarse mesh's own transform (its xformOps evaluated to one ``xformOp:transform``,
  time-sampled when it moves) under the same parent, so the two line up at every frame;
- its primvars carried through the subdivision (face-varying; constant ones copied), its
  ``doubleSided`` and ``orientation``, and its bound material.

A skinned coarse mesh has the skinned points: the fine mesh holds posed points and binds
no skeleton and no joint influences, so UsdSkel does not skin it again (README).
"""
from __future__ import annotations

import logging

import numpy as np
from pxr import Sdf, UsdGeom, Vt

from ..outputs.layers import attribute_spec, bind_material, define_prim, set_value
from ..outputs.sink import BakeScene
from .subdivide import FineMesh

_log = logging.getLogger(__name__)

SUFFIX = "_wrinkled"
VT = Sdf.ValueTypeNames
#: the authored uniform attributes of the coarse mesh that the fine mesh repeats
UNIFORM_TYPES = {"doubleSided": VT.Bool, "orientation": VT.Token}


def fine_path(coarse: str, siblings) -> Sdf.Path:
    """``<coarse>_wrinkled`` beside the coarse mesh: a name none of ``siblings`` (the
    names of the prims beside it) has."""
    path = Sdf.Path(coarse)
    name = path.name + SUFFIX
    index = 2
    while name in siblings:
        name = f"{path.name}{SUFFIX}{index}"
        index += 1
    return path.GetParentPath().AppendChild(name)


def _array(type_name, values: np.ndarray):
    """A numpy array as the Vt array of ``type_name`` (float-like types only), or None."""
    cls = type_name.type.pythonClass
    if cls is None or not hasattr(cls, "FromNumpy"):
        return None
    for dtype in (np.float32, np.float64, np.float16):
        try:
            return cls.FromNumpy(np.ascontiguousarray(values, dtype))
        except (TypeError, ValueError, RuntimeError):
            continue
    return None


class FineMeshWriter:
    """Authors one fine mesh: :meth:`define` once, :meth:`add_frame` per frame, from what
    the scene read of the coarse mesh (``scene.facts.meshes[coarse]``,
    scene/overrides.MeshFacts)."""

    def __init__(self, scene: BakeScene, coarse: str, fine: FineMesh):
        self.layer: Sdf.Layer | None = None
        self.coarse = coarse
        self.mesh = scene.facts.meshes[coarse]
        self.path = fine_path(coarse, self.mesh.siblings)
        self.fine = fine
        self.transform = self.mesh.transform

    def define(self, layer: Sdf.Layer) -> None:
        self.layer = layer
        fine = self.fine
        spec = define_prim(layer, self.path, "Mesh")
        attribute_spec(spec, "faceVertexCounts", VT.IntArray,
                       Vt.IntArray.FromNumpy(np.full(len(fine.faces), 3, np.int32)))
        attribute_spec(spec, "faceVertexIndices", VT.IntArray, Vt.IntArray.FromNumpy(
            np.ascontiguousarray(fine.faces.ravel(), np.int32)))
        attribute_spec(spec, "subdivisionScheme", VT.Token, UsdGeom.Tokens.none, uniform=True)
        attribute_spec(spec, "purpose", VT.Token, UsdGeom.Tokens.render, uniform=True)
        for name, value in self.mesh.uniform.items():
            attribute_spec(spec, name, UNIFORM_TYPES[name], value, uniform=True)
        proxy = Sdf.RelationshipSpec(spec, "proxyPrim", custom=False)
        proxy.targetPathList.explicitItems = [Sdf.Path(self.coarse)]
        coarse = Sdf.CreatePrimInLayer(layer, self.coarse)
        attribute_spec(coarse, "purpose", VT.Token, UsdGeom.Tokens.proxy, uniform=True)
        transform = self.transform
        if transform is not None:
            order = (["!resetXformStack!"] if transform.reset else []) + ["xformOp:transform"]
            attribute_spec(spec, "xformOpOrder", VT.TokenArray, Vt.TokenArray(order),
                           uniform=True)
            if not transform.moves:
                attribute_spec(spec, "xformOp:transform", VT.Matrix4d, transform.static)
        if self.mesh.look.material:
            bind_material(layer, self.path, self.mesh.look.material)
        for purpose, look in self.mesh.looks.items():
            if look.material:   # the coarse mesh's own binding for that purpose
                bind_material(layer, self.path, look.material, purpose=purpose)
        self._primvars(spec)

    def _primvars(self, spec: Sdf.PrimSpec) -> None:
        """The coarse mesh's primvars on the fine mesh: face-varying, interpolated with
        each fine corner's barycentrics in its coarse triangle; constant ones copied."""
        fine = self.fine
        for primvar in self.mesh.primvars:
            name, type_name = primvar.name, primvar.type_name
            if primvar.constant:
                attribute_spec(spec, name, type_name, primvar.value,
                               interpolation=UsdGeom.Tokens.constant)
                continue
            value = None
            if primvar.value is not None:
                coarse = primvar.value[fine.face_triangle]                  # (m, 3, c)
                values = np.einsum("mjk,mkc->mjc", fine.corner_bary, coarse)
                value = _array(type_name, values.reshape(-1, coarse.shape[-1]).squeeze())
            if value is None:
                _log.warning(f"primvar {name} ({type_name}) cannot be interpolated onto the "
                             f"wrinkled mesh; not carried ({self.coarse})")
                continue
            attribute_spec(spec, name, type_name, value,
                           interpolation=UsdGeom.Tokens.faceVarying)

    def add_frame(self, frame: float, points: np.ndarray, normals: np.ndarray) -> None:
        layer = self.layer
        spec = layer.GetPrimAtPath(self.path)
        values = {
            "points": (VT.Point3fArray, None, Vt.Vec3fArray.FromNumpy(
                np.ascontiguousarray(points, np.float32))),
            "normals": (VT.Normal3fArray, UsdGeom.Tokens.vertex, Vt.Vec3fArray.FromNumpy(
                np.ascontiguousarray(normals, np.float32))),
            "extent": (VT.Float3Array, None, Vt.Vec3fArray.FromNumpy(
                np.stack([points.min(0), points.max(0)]).astype(np.float32))),
        }
        if self.transform is not None and self.transform.moves:
            values["xformOp:transform"] = (VT.Matrix4d, None, self.transform.at(frame))
        for name, (type_name, interpolation, value) in values.items():
            attr = attribute_spec(spec, name, type_name, interpolation=interpolation)
            set_value(layer, attr.path, frame, value)
