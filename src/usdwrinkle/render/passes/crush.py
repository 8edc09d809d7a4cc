"""Crush pass: per-vertex compression -> plane wave (GUIDE sec. 1.2)."""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from ..shaders import compute_shader
from . import groups, set_uniforms

#: Floor of the compression ratio used for the wave vector: |k| <= 2 pi / (W r_min).
MIN_RATIO = 0.05


class CrushPass:
    def __init__(self, ctx):
        self.ctx = ctx
        self.shader = compute_shader(ctx, "crush.glsl",
                                     {"LOCAL_SIZE": bindings.LOCAL_SIZE, **bindings.CRUSH})

    def run(self, res: MeshResources, wrinkles: bool = True) -> None:
        """Write this frame's fields into the other field buffer (the previous frame's
        stay readable for the relax pass's seed step) and the anchored phase."""
        res.current_fields = 1 - res.current_fields
        params = res.record.params
        scale = params.amplitude_scale if (wrinkles and res.record.wrinkled) else 0.0
        set_uniforms(self.shader, {"u_num_points": res.num_points, "u_amplitude_scale": scale,
                                   "u_min_ratio": MIN_RATIO, **res.topology_uniforms})
        b = bindings.CRUSH
        res.posed_points.bind_to_storage_buffer(b["CRUSH_POSED_POINTS"])
        res.rest_points.bind_to_storage_buffer(b["CRUSH_REST_POINTS"])
        res.topology.bind_to_storage_buffer(b["CRUSH_TOPOLOGY"])
        res.rest_frame.bind_to_storage_buffer(b["CRUSH_REST_FRAME"])
        res.q_width.bind_to_storage_buffer(b["CRUSH_Q_WIDTH"])
        res.fields.bind_to_storage_buffer(b["CRUSH_FIELDS"])
        res.anchor_phase.bind_to_storage_buffer(b["CRUSH_PHASE"])
        self.shader.run(groups(res.num_points, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()
