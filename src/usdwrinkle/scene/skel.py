"""UsdSkel: find skinned meshes and extract their skinning data as numpy.

Order of operations, as UsdSkel's SkinningQuery.ComputeSkinnedPoints:
blend shapes (rest, local) -> geomBindTransform -> LBS/DQS with the skinning
transforms (skeleton space) -> skeleton space to prim (local) space.
"""
from __future__ import annotations

import numpy as np
from pxr import Gf, Usd, UsdGeom, UsdSkel, Vt

from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_WORLD_COORDINATE
from ..usd.diagnostics import usd_diagnostics
from ..usd.values import finite_in_float32
from .records import SkinData


def gf_matrices(xforms) -> np.ndarray:
    """Vt.Matrix4dArray -> (J, 4, 4) float64 (row-vector convention kept)."""
    return np.asarray(xforms, dtype=np.float64).reshape(-1, 4, 4)


class SkelBindings:
    """All skel bindings of a stage: mesh path -> (skel query, skinning query).

    UsdSkel prints its own complaints about bindings (``ComputeJointInfluences``,
    ``UsdSkelBlendShapeQuery``) on stderr; they are logged as warnings, one line each.
    """

    def __init__(self, stage: Usd.Stage):
        self.cache = UsdSkel.Cache()
        self.by_mesh: dict[str, tuple] = {}
        self.blend_queries: dict[str, UsdSkel.BlendShapeQuery] = {}
        with usd_diagnostics(forward=True):
            self._populate(stage)

    def _populate(self, stage: Usd.Stage) -> None:
        for prim in stage.Traverse(Usd.TraverseInstanceProxies()):
            if not prim.IsA(UsdSkel.Root):
                continue
            root = UsdSkel.Root(prim)
            self.cache.Populate(root, Usd.TraverseInstanceProxies())
            for binding in self.cache.ComputeSkelBindings(root, Usd.TraverseInstanceProxies()):
                skel_query = self.cache.GetSkelQuery(binding.GetSkeleton())
                for target in binding.GetSkinningTargets():
                    path = str(target.GetPrim().GetPath())
                    self.by_mesh[path] = (skel_query, target)
                    if target.HasBlendShapes():
                        self.blend_queries[path] = UsdSkel.BlendShapeQuery(
                            UsdSkel.BindingAPI(target.GetPrim()))

    def get(self, path: str):
        return self.by_mesh.get(path)


def skin_data(path: str, skel_query, skinning_query, num_points: int,
              blend_query=None) -> SkinData:
    """Extract the static skinning data of one mesh, validated."""
    method = str(skinning_query.GetSkinningMethod() or "classicLinear")
    if method not in ("classicLinear", "dualQuaternion"):
        raise UsdWrinkleError(f"unknown skinning method '{method}'", path, "skel:skinningMethod")
    joint_order = skinning_query.GetJointOrder() or skel_query.GetJointOrder()
    num_joints = len(joint_order)
    influences = skinning_query.ComputeJointInfluences() \
        if skinning_query.HasJointInfluences() else None
    if influences:
        indices, weights = influences
        k = max(skinning_query.GetNumInfluencesPerComponent(), 1)
        indices = np.asarray(indices, dtype=np.int32).reshape(-1, k)
        weights = np.asarray(weights, dtype=np.float32).reshape(-1, k)
        if skinning_query.IsRigidlyDeformed() or len(indices) == 1:
            indices = np.repeat(indices[:1], num_points, axis=0)
            weights = np.repeat(weights[:1], num_points, axis=0)
    else:
        # Blend shapes only, or no influences: every point follows the identity.
        indices = np.zeros((num_points, 1), np.int32)
        weights = np.zeros((num_points, 1), np.float32)
        num_joints = max(num_joints, 0)
    if len(indices) != num_points:
        raise UsdWrinkleError(
            f"{len(indices)} joint influences for {num_points} points", path,
            "primvars:skel:jointIndices")
    if not np.all(np.isfinite(weights)):
        raise UsdWrinkleError("joint weights are not finite", path, "primvars:skel:jointWeights")
    used = weights != 0
    if used.any() and (indices[used].min() < 0 or indices[used].max() >= max(num_joints, 1)):
        raise UsdWrinkleError(f"joint indices out of range [0, {num_joints})", path,
                              "primvars:skel:jointIndices")
    geom_bind = np.asarray(skinning_query.GetGeomBindTransform(), dtype=np.float64)
    if not finite_in_float32(geom_bind):
        raise UsdWrinkleError("geomBindTransform is not finite in float32 (NaN, Inf or "
                              "beyond 3.4e38)", path, "primvars:skel:geomBindTransform")
    point_indices: list = []
    offsets: list = []
    normal_offsets: list = []
    if blend_query is not None:
        point_indices, offsets, normal_offsets = _blend_shapes(path, blend_query, num_points)
    return SkinData(method, geom_bind, indices, weights, num_joints, point_indices, offsets,
                    normal_offsets)


def _blend_shapes(path: str, blend_query, num_points: int) -> tuple[list, list, list]:
    """(point indices per blend shape, offsets per sub-shape, normal offsets per sub-shape
    (empty where none are authored)), validated: every target a BlendShape, indices within
    the mesh's points, offsets finite."""
    shapes = [blend_query.GetBlendShape(i) for i in range(blend_query.GetNumBlendShapes())]
    for shape in shapes:
        if not shape:
            raise UsdWrinkleError("a blend shape target is not a valid BlendShape prim", path,
                                  "skel:blendShapeTargets")
    point_indices = []
    for shape, ids in zip(shapes, blend_query.ComputeBlendShapePointIndices(), strict=True):
        ids = np.asarray(ids, dtype=np.int64)
        if ids.size and (ids.min() < 0 or ids.max() >= num_points):
            raise UsdWrinkleError(f"blend shape point indices out of range [0, {num_points})",
                                  str(shape.GetPrim().GetPath()), "pointIndices")
        point_indices.append(ids.astype(np.int32) if ids.size else None)
    offsets = []
    for sub, values in enumerate(blend_query.ComputeSubShapePointOffsets()):
        values = np.asarray(values, dtype=np.float64).reshape(-1, 3)
        if not finite_in_float32(values):
            shape = shapes[blend_query.GetBlendShapeIndex(sub)]
            inbetween = blend_query.GetInbetween(sub)
            raise UsdWrinkleError("blend shape offsets are not finite in float32 (NaN, Inf or "
                                  "beyond 3.4e38)", str(shape.GetPrim().GetPath()),
                                  inbetween.GetAttr().GetName() if inbetween else "offsets")
        offsets.append(values.astype(np.float32))
    normal_offsets = []
    for sub in range(len(offsets)):
        shape = shapes[blend_query.GetBlendShapeIndex(sub)]
        inbetween = blend_query.GetInbetween(sub)
        values = inbetween.GetNormalOffsets() if inbetween else \
            shape.GetNormalOffsetsAttr().Get()
        values = np.asarray(values if values is not None else [], np.float64).reshape(-1, 3)
        if not finite_in_float32(values):
            raise UsdWrinkleError("blend shape normal offsets are not finite in float32",
                                  str(shape.GetPrim().GetPath()), "normalOffsets")
        normal_offsets.append(values.astype(np.float32) if np.any(values) else
                              np.zeros((0, 3), np.float32))
    return point_indices, offsets, normal_offsets


def check_blend_weights(path: str, skin: SkinData, weights: np.ndarray, frame,
                        extent: float) -> None:
    """Refuse sub-shape weights that are not finite, or that move points beyond
    +-MAX_WORLD_COORDINATE (where the GPU's float32 squares of lengths overflow)."""
    if not np.all(np.isfinite(weights)):
        raise UsdWrinkleError("blend shape weights are not finite", path, "skel:blendShapes",
                              frame)
    reach = extent + sum(abs(float(w)) * float(np.abs(o).max(initial=0.0))
                         for w, o in zip(weights, skin.subshape_offsets, strict=False))
    if reach > MAX_WORLD_COORDINATE:
        raise UsdWrinkleError(f"blend shape weights move points {reach:.3g} scene units, "
                              f"beyond +-{MAX_WORLD_COORDINATE:g} (the GPU's float32 range)",
                              path, "skel:blendShapes", frame)


def sample_skin(path: str, skel_query, skinning_query, blend_query, time: Usd.TimeCode,
                xform_cache: UsdGeom.XformCache, num_subshapes: int):
    """Per-frame skinning inputs: joint transforms (mesh order), skel -> local, weights."""
    xforms = skel_query.ComputeSkinningTransforms(time)
    if xforms is None or len(xforms) == 0:
        xforms = None
    mapper = skinning_query.GetJointMapper()
    if xforms is not None and mapper is not None and not mapper.IsNull() \
            and not mapper.IsIdentity():
        # joints the mesh names but the skeleton lacks keep the identity
        order = skinning_query.GetJointOrder()
        xforms = mapper.RemapTransforms(xforms, Vt.Matrix4dArray(len(order), Gf.Matrix4d(1)))
    joint_transforms = gf_matrices(xforms) if xforms is not None else np.zeros((0, 4, 4))
    skel_prim = skel_query.GetSkeleton().GetPrim()
    skel_to_world = xform_cache.GetLocalToWorldTransform(skel_prim)
    mesh_to_world = xform_cache.GetLocalToWorldTransform(skinning_query.GetPrim())
    skel_to_local = np.asarray(skel_to_world * mesh_to_world.GetInverse(), dtype=np.float64)
    weights = np.zeros(num_subshapes, np.float32)
    active = ()
    if blend_query is not None:
        anim = skel_query.GetAnimQuery()
        shape_weights = anim.ComputeBlendShapeWeights(time) if anim else None
        if shape_weights is not None and len(shape_weights):
            bmapper = skinning_query.GetBlendShapeMapper()
            if bmapper is not None and not bmapper.IsNull():
                shape_weights = bmapper.Remap(shape_weights)
            sub_w, blend_ids, sub_ids = blend_query.ComputeSubShapeWeights(shape_weights)
            for w, s in zip(sub_w, sub_ids, strict=True):
                weights[int(s)] += float(w)
            active = tuple(sorted({(int(b), int(s))
                                   for b, s in zip(blend_ids, sub_ids, strict=True)}))
    return joint_transforms, skel_to_local, weights, active


def dual_quaternions(joint_transforms: np.ndarray):
    """Split skinning transforms for DQS as UsdSkel does.

    Each matrix is factored into rotation, translation and a 3x3 scale/shear
    remainder (applied by LBS). Returns (real (J,4) xyzw, dual (J,4) xyzw,
    scale (J,3,3) row-vector, has_scale).
    """
    count = len(joint_transforms)
    real = np.zeros((count, 4))
    dual = np.zeros((count, 4))
    scale = np.tile(np.eye(3), (count, 1, 1))
    has_scale = False
    for j in range(count):  # loops over joints, not vertices
        matrix = Gf.Matrix4d(*joint_transforms[j].reshape(-1).tolist())
        ok, _scale_orient, _s, rot, translation, _persp = matrix.Factor()
        if not ok:
            continue
        rot = Gf.Matrix4d(rot)
        rot.Orthonormalize()
        quat = rot.ExtractRotationMatrix().ExtractRotation().GetQuaternion()
        dq = Gf.DualQuatd(Gf.Quatd(quat.GetReal(), Gf.Vec3d(quat.GetImaginary())),
                          Gf.Vec3d(translation))
        r, d = dq.GetReal(), dq.GetDual()
        real[j] = [*r.GetImaginary(), r.GetReal()]
        dual[j] = [*d.GetImaginary(), d.GetReal()]
        non_scale = rot * Gf.Matrix4d(1.0).SetTranslate(translation)
        remainder = np.asarray((matrix * non_scale.GetInverse()).ExtractRotationMatrix())
        scale[j] = remainder
        if not np.allclose(remainder, np.eye(3), atol=1e-6, rtol=0):
            has_scale = True
    return real, dual, scale, has_scale
