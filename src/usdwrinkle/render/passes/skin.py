"""Skin pass: blend shapes and LBS/DQS on the GPU; point caches are uploaded as posed."""
from __future__ import annotations

import numpy as np

from ...method.contract import JOINT_TEXELS
from ...scene.records import MeshFrame
from ..resources import MeshResources, vec4
from . import gl_matrix, normal_matrix
from .base import Step, WavePass, wave_pass

METHODS = {"classicLinear": 1, "dualQuaternion": 2}


def joint_block(joint_transforms: np.ndarray, method: str, geom_bind: np.ndarray,
                skel_to_local: np.ndarray, dual_quaternions: tuple | None = None
                ) -> tuple[np.ndarray, bool]:
    """The Joint structs of skin.glsl for one frame, and whether any joint scales (DQS:
    the scene's split of the transforms, MeshFrame.dual_quaternions).

    For LBS each joint's matrix is geomBind @ skinning transform @ skel-to-local
    (row-vector, float64, then float32): local rest to local posed in one product, stored
    as its first three columns.
    """
    count = len(joint_transforms)
    block = np.zeros((max(count, 1), JOINT_TEXELS * 4), np.float32)
    if count == 0:
        return block, False
    if method == "classicLinear":
        combined = geom_bind[None] @ joint_transforms @ skel_to_local[None]
        # texels 0..2: the first three columns of the row-vector matrix, so that posed
        # coordinate c = dot(column c, (p, 1)); the fourth column of an affine matrix is
        # (0, 0, 0, 1) and is not needed
        block[:count, :12] = combined.transpose(0, 2, 1)[:, :3, :].reshape(count, 12)
        # texels 4..6: the rows of the 3x3 inverse, the normals' matrix (skinning.glsl)
        linear = combined[:, :3, :3]
        singular = np.abs(np.linalg.det(linear)) < 1e-300
        linear = np.where(singular[:, None, None], np.eye(3), linear)
        block[:count, 16:28] = np.concatenate(
            [np.linalg.inv(linear), np.zeros((count, 3, 1))], axis=2).reshape(count, 12)
    has_scale = False
    if method == "dualQuaternion":
        real, dual, scale, has_scale = dual_quaternions
        block[:count, 16:20] = real
        block[:count, 20:24] = dual
        rows = np.zeros((count, 3, 4))
        rows[:, :, :3] = scale
        block[:count, 24:36] = rows.reshape(count, 12)
    return block, has_scale


def skinning_uniforms(res: MeshResources, frame: MeshFrame) -> dict:
    """The uniforms of include/skinning.glsl for this frame (its joints are uploaded)."""

    skin = res.record.skin
    skel_to_local = frame.skel_to_local if res.skinned else np.eye(4)
    return {"u_influences": res.influences,
            "u_num_joints": min(skin.num_joints, len(frame.joint_transforms)),
            "u_has_scale": int(res.has_scale),
            "u_geom_bind": gl_matrix(skin.geom_bind),
            "u_skel_to_local": gl_matrix(skel_to_local),
            "u_geom_bind_normal": normal_matrix(skin.geom_bind),
            "u_skel_to_local_normal": normal_matrix(skel_to_local)}


@wave_pass
class SkinPass(WavePass):
    """The posed points (skin.glsl): blend shapes, then LBS or DQS; a point cache's
    points are uploaded as they are."""

    SHADER = "skin.glsl"
    UNITS = {"SKIN_REST_POINTS": 0, "SKIN_INFLUENCES": 1, "SKIN_JOINTS": 3,
             # image units (writes)
             "SKIN_POSED_POINTS": 0,
             # storage buffers: blend shapes (only the sub-shapes with a weight are read)
             "SKIN_SUBSHAPE_OFFSETS": 0, "SKIN_SUBSHAPE_WEIGHTS": 1}
    TIMING = "skin"
    ORDER = 10

    def run(self, res: MeshResources, step: Step) -> None:
        self.skin(res, step.frame)

    def skin(self, res: MeshResources, frame: MeshFrame) -> None:
        """Pose ``res``'s points for ``frame``."""
        record = res.record
        if record.skin is None:
            points = frame.points if frame.points is not None else record.rest_points
            res.posed_points.write(vec4(points))
            return
        skin = record.skin
        for blend_shape, subshape in frame.active_subshapes:
            res.upload_subshape(blend_shape, subshape)
        weights = frame.subshape_weights if frame.subshape_weights is not None else np.zeros(0)
        if len(weights):
            res.subshape_weights.write(np.asarray(weights, np.float32).tobytes())
        block, has_scale = joint_block(frame.joint_transforms, skin.method, skin.geom_bind,
                                       frame.skel_to_local, frame.dual_quaternions)
        res.joints.write(block)
        res.has_scale = has_scale
        self.dispatch(res.num_points, {
            "u_num_points": res.num_points, "u_num_subshapes": skin.num_subshapes,
            "u_method": METHODS[skin.method] if res.skinned else 0,
            **skinning_uniforms(res, frame)},
            reads={"SKIN_REST_POINTS": res.rest_points, "SKIN_INFLUENCES": res.influence_table,
                   "SKIN_JOINTS": res.joints},
            writes={"SKIN_POSED_POINTS": res.posed_points},
            storage={"SKIN_SUBSHAPE_OFFSETS": res.subshape_offsets,
                     "SKIN_SUBSHAPE_WEIGHTS": res.subshape_weights})
