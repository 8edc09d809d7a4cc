"""Relax pass: seed the phasors and edge rotations, then Jacobi steps (ping-pong).

Seed: with phase history (the wave state of the shot's previous grid frame, read and
never written), each vertex starts from its previous phase, sign-aligned to its new wave
vector, so crests ride with the cloth; otherwise from crush's material-anchored phase.
The last step writes the phase that draw and the bake read; then the fit makes each
vertex's wave the one those phases draw (relax.glsl's FIT: k and the amplitude, in place
in the fields). Without iterations (relaxIterations 0) there is no relaxation and no fit.
"""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from ..shaders import Variants, compute_shader
from . import bind, groups, set_uniforms


class RelaxPass:
    def __init__(self, ctx):
        self.ctx = ctx
        defines = {**bindings.COMMON, **bindings.RELAX}
        # per wave-system count (render/shaders.py: Variants)
        self.steps = Variants(
            lambda extra: compute_shader(ctx, "relax.glsl", {**defines, **extra}))
        self.seeds = Variants(
            lambda extra: compute_shader(ctx, "relax.glsl", {**defines, "SEED": 1, **extra}))
        self.fits = Variants(
            lambda extra: compute_shader(ctx, "relax.glsl", {**defines, "FIT": 1, **extra}))
        self.steps()
        self.seeds()
        self.fits()

    def run(self, res: MeshResources, iterations: int, with_history: bool = False) -> None:
        units, waves = bindings.RELAX, res.waves
        count = groups(res.num_points, bindings.LOCAL_SIZE)
        seed_shader, shader = self.seeds(TWO_SYSTEMS=waves.systems > 1), self.steps(
            TWO_SYSTEMS=waves.systems > 1)
        set_uniforms(seed_shader, {"u_num_points": res.num_points,
                                        "u_systems": waves.systems,
                                        "u_has_history": int(with_history),
                                        **res.topology_uniforms})
        bind(units, reads={
            "RELAX_POSED_POINTS": res.posed_points, "TOPOLOGY_TABLE": res.topology,
            "RELAX_FIELDS": waves.current, "RELAX_PREVIOUS_FIELDS": waves.history.fields,
            "RELAX_PREVIOUS_PHASE": waves.history.phase, "RELAX_ANCHOR": waves.anchor_phase},
            writes={"RELAX_Z_OUT": waves.phasors[0], "RELAX_EDGES_OUT": waves.edge_rotations,
                    "RELAX_PHASE": waves.phase})
        seed_shader.run(count)
        self.ctx.memory_barrier()
        if iterations <= 0:
            return  # the seed wrote the phase
        set_uniforms(shader, {"u_num_points": res.num_points, "u_systems": waves.systems,
                              **res.topology_uniforms})
        bind(units, reads={"RELAX_EDGES": waves.edge_rotations})
        for step in range(iterations):
            src = step % 2
            bind(units, reads={"RELAX_Z_IN": waves.phasors[src]},
                 writes={"RELAX_Z_OUT": waves.phasors[1 - src]})
            set_uniforms(shader, {"u_write_phase": int(step == iterations - 1)})
            shader.run(count)
            self.ctx.memory_barrier()
        fit = self.fits(TWO_SYSTEMS=waves.systems > 1)
        set_uniforms(fit, {"u_num_points": res.num_points, "u_systems": waves.systems,
                           **res.topology_uniforms})
        bind(units, reads={"RELAX_Z_IN": waves.phasors[iterations % 2]},
             writes={"RELAX_FIELDS_OUT": waves.current})
        fit.run(count)
        self.ctx.memory_barrier()
