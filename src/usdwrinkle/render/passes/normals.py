"""Normals pass: the shading normals of one frame (scene/normals.py, shaders/normals.glsl).

Smooth and faceted normals are computed from the posed points; authored normals are
skinned with the points (UsdSkel meshes), uploaded per frame (time-sampled), or were
uploaded once with the resources (static).
"""
from __future__ import annotations

import numpy as np

from ...scene.records import MeshFrame
from .. import bindings
from ..resources import MeshResources, vec4
from ..shaders import Variants, compute_shader
from . import bind, groups, set_uniforms
from .skin import METHODS, skinning_uniforms


class NormalsPass:
    def __init__(self, ctx):
        self.ctx = ctx
        defines = {**bindings.COMMON, **bindings.NORMALS}
        self.variants = Variants(lambda extra: compute_shader(ctx, "normals.glsl",
                                                              {**defines, **extra}))

    def run(self, res: MeshResources, frame: MeshFrame) -> None:
        plan = res.normal_plan
        if plan.source == "authored":
            if res.authored_normals is not None and frame.joint_transforms is not None \
                    and res.skinned:
                self._skin(res, frame)
            elif frame.normals is not None:
                res.shading_normals.write(vec4(frame.normals, 1.0))
            return
        shader = self.variants(SMOOTH=plan.source == "smooth",
                               FACETED=plan.source == "faceted")
        set_uniforms(shader, {"u_entries": plan.entries})
        bind(bindings.NORMALS, reads={"NORMALS_PLAN": res.normal_plan_table,
                                      "NORMALS_POSED_POINTS": res.posed_points},
             writes={"NORMALS_OUT": res.shading_normals})
        shader.run(groups(plan.entries, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()

    def _skin(self, res: MeshResources, frame: MeshFrame) -> None:
        skin = res.record.skin
        shader = self.variants(SKINNED=True)
        set_uniforms(shader, {"u_entries": res.normal_plan.entries,
                              "u_method": METHODS[skin.method],
                              **skinning_uniforms(res, frame)})
        bind(bindings.NORMALS, reads={"NORMALS_PLAN": res.normal_plan_table,
                                      "NORMALS_AUTHORED": res.authored_normals,
                                      "SKIN_INFLUENCES": res.influence_table,
                                      "SKIN_JOINTS": res.joints},
             writes={"NORMALS_OUT": res.shading_normals})
        shader.run(groups(res.normal_plan.entries, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()


def normal_matrix(row_vector_matrix: np.ndarray) -> np.ndarray:
    """The column-vector 3x3 that takes normals through a row-vector matrix (the inverse
    transpose), as GLSL mat3 bytes."""
    m3 = np.asarray(row_vector_matrix, np.float64)[:3, :3]
    try:
        inverse = np.linalg.inv(m3)
    except np.linalg.LinAlgError:
        inverse = np.eye(3)
    # row-vector normals: n' = n inverse(M3)^T, i.e. column-vector n' = inverse(M3) n;
    # GLSL reads the uploaded rows as columns, so upload the transpose
    return np.ascontiguousarray(inverse.T, np.float32)
