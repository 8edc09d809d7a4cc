"""Crush pass: per-vertex compression -> plane wave (GUIDE sec. 1.2)."""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from ..shaders import compute_shader
from . import bind, groups, set_uniforms

#: Floor of the compression ratio used for the wave vector: |k| <= 2 pi / (W r_min).
MIN_RATIO = 0.05


class CrushPass:
    def __init__(self, ctx):
        self.ctx = ctx
        defines = {**bindings.COMMON, **bindings.CRUSH}
        self.shader = compute_shader(ctx, "crush.glsl", defines)
        self.face_shader = compute_shader(ctx, "crush.glsl", {**defines, "FACE_NORMALS": 1})

    def run(self, res: MeshResources, wrinkles: bool = True) -> None:
        """Write this frame's fields into the other field buffer (the previous frame's
        stay readable for the relax pass's seed step) and the anchored phase."""
        res.current_fields = 1 - res.current_fields
        params = res.record.params
        scale = params.amplitude_scale if (wrinkles and res.record.wrinkled) else 0.0
        set_uniforms(self.shader, {"u_num_points": res.num_points, "u_amplitude_scale": scale,
                                   "u_min_ratio": MIN_RATIO, **res.topology_uniforms})
        set_uniforms(self.face_shader, {"u_num_triangles": res.num_triangles,
                                        **res.topology_uniforms})
        units = bindings.CRUSH
        bind(units, reads={"CRUSH_POSED_POINTS": res.posed_points, "TOPOLOGY_TABLE": res.topology})
        if res.num_triangles:
            bind(units, reads={"CRUSH_TRIANGLES": res.triangles},
                 writes={"CRUSH_FACE_NORMALS_OUT": res.face_normals})
            self.face_shader.run(groups(res.num_triangles, bindings.LOCAL_SIZE))
            self.ctx.memory_barrier()
        bind(units, reads={"CRUSH_REST_POINTS": res.rest_points,
                           "CRUSH_REST_FRAME": res.rest_frame, "CRUSH_Q_WIDTH": res.q_width,
                           "CRUSH_FACE_NORMALS": res.face_normals},
             writes={"CRUSH_FIELDS": res.fields, "CRUSH_PHASE": res.anchor_phase})
        self.shader.run(groups(res.num_points, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()
