"""Relax pass: seed the phases, then Jacobi phase alignment (ping-pong buffers).

Seed: with phase history (the previous frame of the shot was computed), each
vertex starts from its previous phase, sign-aligned to its new wave vector, so
crests ride with the cloth; otherwise from crush's material-anchored phase.
"""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from ..shaders import compute_shader
from . import bind_storage, groups, set_uniforms


class RelaxPass:
    def __init__(self, ctx):
        self.ctx = ctx
        defines = {"LOCAL_SIZE": bindings.LOCAL_SIZE, **bindings.RELAX}
        self.shader = compute_shader(ctx, "relax.glsl", defines)
        self.seed_shader = compute_shader(ctx, "relax.glsl", {**defines, "SEED": 1})

    def seed(self, res: MeshResources, with_history: bool) -> None:
        set_uniforms(self.seed_shader, {"u_num_points": res.num_points,
                                        "u_has_history": int(with_history)})
        bind_storage(bindings.RELAX, {
            "RELAX_FIELDS": res.fields, "RELAX_PREVIOUS_FIELDS": res.previous_fields,
            "RELAX_ANCHOR": res.anchor_phase, "RELAX_PHASE_OUT": res.phase_buffer()})
        self.seed_shader.run(groups(res.num_points, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()

    def run(self, res: MeshResources, iterations: int, with_history: bool = False) -> None:
        self.seed(res, with_history)
        if iterations <= 0:
            return
        set_uniforms(self.shader, {"u_num_points": res.num_points, **res.topology_uniforms})
        b = bindings.RELAX
        bind_storage(b, {"RELAX_POSED_POINTS": res.posed_points, "RELAX_TOPOLOGY": res.topology,
                         "RELAX_FIELDS": res.fields})
        count = groups(res.num_points, bindings.LOCAL_SIZE)
        for _ in range(iterations):
            src = res.current_phase
            res.phase[src].bind_to_storage_buffer(b["RELAX_PHASE_IN"])
            res.phase[1 - src].bind_to_storage_buffer(b["RELAX_PHASE_OUT"])
            self.shader.run(count)
            self.ctx.memory_barrier()
            res.current_phase = 1 - src
