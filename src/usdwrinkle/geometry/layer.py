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
from pxr import Sdf, Usd, UsdGeom, UsdShade, Vt

from ..outputs.layers import attribute_spec, bind_material, define_prim
from ..outputs.sink import BakeScene
from ..scene.material import corner_values
from .subdivide import FineMesh

_log = logging.getLogger(__name__)

SUFFIX = "_wrinkled"
#: primvars that are not carried: the wrinkle fields, skinning, the rest pose, normals
SKIPPED_PRIMVARS = ("primvars:wrinkle:", "primvars:skel:", "primvars:rest", "primvars:normals")
VT = Sdf.ValueTypeNames


def fine_path(stage: Usd.Stage, coarse: str) -> Sdf.Path:
    """``<coarse>_wrinkled`` beside the coarse mesh (a free name)."""
    path = Sdf.Path(coarse)
    candidate = path.GetParentPath().AppendChild(path.name + SUFFIX)
    index = 2
    while stage.GetPrimAtPath(candidate):
        candidate = path.GetParentPath().AppendChild(f"{path.name}{SUFFIX}{index}")
        index += 1
    return candidate


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
    """Authors one fine mesh: :meth:`define` once, :meth:`add_frame` per frame."""

    def __init__(self, scene: BakeScene, coarse: str, fine: FineMesh):
        self.layer: Sdf.Layer | None = None
        self.coarse = coarse
        self.path = fine_path(scene.stage, coarse)
        self.prim = scene.stage.GetPrimAtPath(coarse)
        self.fine = fine
        self.topology = scene.meshes[coarse].topology
        self.xformable = UsdGeom.Xformable(self.prim)
        self.moves = bool(self.xformable.GetOrderedXformOps()) and \
            self.xformable.TransformMightBeTimeVarying()

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
        mesh = UsdGeom.Mesh(self.prim)
        for attr, type_name in ((mesh.GetDoubleSidedAttr(), VT.Bool),
                                (mesh.GetOrientationAttr(), VT.Token)):
            if attr.HasAuthoredValue():
                attribute_spec(spec, attr.GetName(), type_name, attr.Get(), uniform=True)
        proxy = Sdf.RelationshipSpec(spec, "proxyPrim", custom=False)
        proxy.targetPathList.explicitItems = [Sdf.Path(self.coarse)]
        coarse = Sdf.CreatePrimInLayer(layer, self.coarse)
        attribute_spec(coarse, "purpose", VT.Token, UsdGeom.Tokens.proxy, uniform=True)
        if self.xformable.GetOrderedXformOps() or self.xformable.GetResetXformStack():
            order = (["!resetXformStack!"] if self.xformable.GetResetXformStack() else []) + \
                ["xformOp:transform"]
            attribute_spec(spec, "xformOpOrder", VT.TokenArray, Vt.TokenArray(order),
                           uniform=True)
            if not self.moves:
                attribute_spec(spec, "xformOp:transform", VT.Matrix4d,
                               self.xformable.GetLocalTransformation(Usd.TimeCode.Default()))
        material, _ = UsdShade.MaterialBindingAPI(self.prim).ComputeBoundMaterial()
        if material:
            bind_material(layer, self.path, material.GetPath())
        self._primvars(spec)

    def _primvars(self, spec: Sdf.PrimSpec) -> None:
        """The coarse mesh's primvars on the fine mesh: face-varying, interpolated with
        each fine corner's barycentrics in its coarse triangle; constant ones copied."""
        time = Usd.TimeCode.EarliestTime()
        fine = self.fine
        for primvar in UsdGeom.PrimvarsAPI(self.prim).GetPrimvarsWithValues():
            name = primvar.GetAttr().GetName()
            if name.startswith(SKIPPED_PRIMVARS):
                continue
            type_name = primvar.GetTypeName()
            if primvar.GetInterpolation() == UsdGeom.Tokens.constant:
                attribute_spec(spec, name, type_name, primvar.ComputeFlattened(time),
                               interpolation=UsdGeom.Tokens.constant)
                continue
            corners = corner_values(primvar, self.topology, time) if type_name.isArray \
                else None
            value = None
            if corners is not None:
                coarse = corners[fine.face_triangle]                        # (m, 3, c)
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
        if self.moves:
            time = Usd.TimeCode.Default() if np.isnan(frame) else Usd.TimeCode(frame)
            values["xformOp:transform"] = (VT.Matrix4d, None,
                                           self.xformable.GetLocalTransformation(time))
        for name, (type_name, interpolation, value) in values.items():
            attr = attribute_spec(spec, name, type_name, interpolation=interpolation)
            if np.isnan(frame):
                attr.default = value
            else:
                layer.SetTimeSample(attr.path, frame, value)
