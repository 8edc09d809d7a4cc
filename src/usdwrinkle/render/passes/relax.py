"""Relax pass: Jacobi phase alignment with sign alignment, ping-pong buffers."""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from ..shaders import compute_shader
from . import groups, set_uniforms


class RelaxPass:
    def __init__(self, ctx):
        self.ctx = ctx
        self.shader = compute_shader(ctx, "relax.glsl",
                                     {"LOCAL_SIZE": bindings.LOCAL_SIZE, **bindings.RELAX})

    def run(self, res: MeshResources, iterations: int) -> None:
        if iterations <= 0:
            return
        set_uniforms(self.shader, {"u_num_points": res.num_points, **res.topology_uniforms})
        b = bindings.RELAX
        res.posed_points.bind_to_storage_buffer(b["RELAX_POSED_POINTS"])
        res.topology.bind_to_storage_buffer(b["RELAX_TOPOLOGY"])
        res.fields.bind_to_storage_buffer(b["RELAX_FIELDS"])
        count = groups(res.num_points, bindings.LOCAL_SIZE)
        for _ in range(iterations):
            src = res.current_phase
            res.phase[src].bind_to_storage_buffer(b["RELAX_PHASE_IN"])
            res.phase[1 - src].bind_to_storage_buffer(b["RELAX_PHASE_OUT"])
            self.shader.run(count)
            self.ctx.memory_barrier()
            res.current_phase = 1 - src
