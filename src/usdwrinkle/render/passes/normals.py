"""Normals pass: the shading normals of one frame (scene/normals.py, shaders/normals.glsl).

Smooth and faceted normals are computed from the posed points; authored normals are
skinned with the points (UsdSkel meshes), uploaded per frame (time-sampled), or were
uploaded once with the resources (static).
"""
from __future__ import annotations

import numpy as np

from ...scene.records import MeshFrame
from ..resources import MeshResources, vec4
from .base import Step, WavePass, wave_pass
from .skin import METHODS, skinning_uniforms


@wave_pass
class NormalsPass(WavePass):
    """The posed shading normals (normals.glsl)."""

    SHADER = "normals.glsl"
    #: its skinned variant also reads the SKIN units of include/skinning.glsl (influences
    #: 1, joints 3)
    UNITS = {"NORMALS_PLAN": 0, "NORMALS_POSED_POINTS": 2, "NORMALS_AUTHORED": 4,
             "SKIN_INFLUENCES": 1, "SKIN_JOINTS": 3,
             # image units
             "NORMALS_OUT": 0}
    TIMING = "skin"
    ORDER = 20

    def run(self, res: MeshResources, step: Step) -> None:
        frame = step.frame
        plan = res.normal_plan
        if plan.source == "authored":
            deformed = blended_normals(res, frame)
            skinned = res.authored_normals is not None and frame.joint_transforms is not None \
                and res.skinned
            if skinned:
                if deformed is not None:  # this frame's rest normals, then skinned
                    res.authored_normals.write(vec4(deformed, 0.0))
                self._skin(res, frame)
            elif deformed is not None:
                length = np.linalg.norm(deformed, axis=1, keepdims=True)
                res.shading_normals.write(vec4(np.where(
                    length > 0, deformed / np.maximum(length, 1e-30), 0.0), 1.0))
            elif frame.normals is not None:
                res.shading_normals.write(vec4(frame.normals, 1.0))
            return
        self.dispatch(plan.entries, {"u_entries": plan.entries},
                      reads={"NORMALS_PLAN": res.normal_plan_table,
                             "NORMALS_POSED_POINTS": res.posed_points},
                      writes={"NORMALS_OUT": res.shading_normals},
                      SMOOTH=plan.source == "smooth", FACETED=plan.source == "faceted")

    def _skin(self, res: MeshResources, frame: MeshFrame) -> None:
        skin = res.record.skin
        self.dispatch(res.normal_plan.entries,
                      {"u_entries": res.normal_plan.entries, "u_method": METHODS[skin.method],
                       **skinning_uniforms(res, frame)},
                      reads={"NORMALS_PLAN": res.normal_plan_table,
                             "NORMALS_AUTHORED": res.authored_normals,
                             "SKIN_INFLUENCES": res.influence_table, "SKIN_JOINTS": res.joints},
                      writes={"NORMALS_OUT": res.shading_normals}, SKINNED=True)


def blended_normals(res: MeshResources, frame: MeshFrame) -> np.ndarray | None:
    """The authored normals plus this frame's blend-shape normal offsets, as UsdSkel
    deforms them (vertex-interpolated normals only), or None: the mesh's blend shapes
    author no normal offsets."""
    skin = res.record.skin
    plan = res.normal_plan
    if skin is None or not any(len(o) for o in skin.subshape_normal_offsets) or \
            plan.interpolation not in ("vertex", "varying") or \
            plan.entries != res.num_points:
        return None
    normals = np.array(frame.normals if frame.normals is not None else plan.authored,
                       np.float64)
    weights = frame.subshape_weights if frame.subshape_weights is not None else []
    for blend_shape, subshape in frame.active_subshapes:
        offsets = skin.subshape_normal_offsets[subshape]
        weight = float(weights[subshape]) if subshape < len(weights) else 0.0
        if not len(offsets) or weight == 0.0:
            continue
        ids = skin.blend_point_indices[blend_shape] if blend_shape < len(
            skin.blend_point_indices) else None
        if ids is None:
            count = min(len(offsets), len(normals))
            normals[:count] += weight * offsets[:count]
        else:
            count = min(len(ids), len(offsets))
            normals[ids[:count]] += weight * offsets[:count]
    return normals.astype(np.float32)


