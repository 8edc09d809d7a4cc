"""Relax pass: seed the phasors and edge rotations, then Jacobi steps (ping-pong).

Seed: with phase history (the wave state of the shot's previous grid frame, read and
never written), each vertex starts from its previous phase, sign-aligned to its new wave
vector, so crests ride with the cloth; otherwise from crush's material-anchored phase.
The seed also writes each vertex's mobility (how far its ring's material waves changed
since that frame). The last step writes the phase that draw and the bake read, moved
from the seed by the mobility's share of the way; then the fit makes each
vertex's wave the one those phases draw (relax.glsl's FIT: k and the amplitude, in place
in the fields). Without iterations (relaxIterations 0) there is no relaxation and no fit.
"""
from __future__ import annotations

from ..resources import MeshResources
from . import set_uniforms
from .base import Step, WavePass, wave_pass


@wave_pass
class RelaxPass(WavePass):
    """Phase alignment (relax.glsl): the seed, Jacobi steps, then the fit."""

    SHADER = "relax.glsl"
    UNITS = {"RELAX_POSED_POINTS": 0, "TOPOLOGY_TABLE": 1, "RELAX_FIELDS": 2,
             "RELAX_PREVIOUS_FIELDS": 3, "RELAX_ANCHOR": 4, "RELAX_EDGES": 5, "RELAX_Z_IN": 6,
             "RELAX_PREVIOUS_PHASE": 7, "RELAX_REST_POINTS": 8, "RELAX_DAMPED": 9,
             "RELAX_PREVIOUS_DAMPED": 10, "RELAX_MOBILITY": 11, "RELAX_COARSENING": 12,
             # image units
             "RELAX_PHASE": 0, "RELAX_Z_OUT": 1, "RELAX_EDGES_OUT": 2, "RELAX_FIELDS_OUT": 3,
             "RELAX_MOBILITY_OUT": 4}
    TIMING = "relax"
    ORDER = 40

    def __init__(self, ctx):
        super().__init__(ctx)
        # the seed, the step and the fit compiled with the pass (not in the first frame)
        self.variants(SEED=True)
        self.variants()
        self.variants(FIT=True)

    def run(self, res: MeshResources, step: Step) -> None:
        if step.baked is not None:
            return  # baked phases: no relaxation and no fit
        waves = res.waves
        iterations = step.iterations
        two = waves.systems > 1
        count = res.num_points
        self.dispatch(count, {"u_num_points": res.num_points, "u_systems": waves.systems,
                              "u_has_history": int(step.history), **res.topology_uniforms},
                      reads={"RELAX_POSED_POINTS": res.posed_points,
                             "TOPOLOGY_TABLE": res.topology, "RELAX_FIELDS": waves.current,
                             "RELAX_PREVIOUS_FIELDS": waves.history.fields,
                             "RELAX_PREVIOUS_PHASE": waves.history.phase,
                             "RELAX_ANCHOR": waves.anchor_phase,
                             "RELAX_REST_POINTS": res.rest_points,
                             "RELAX_DAMPED": waves.written.damped,
                             "RELAX_PREVIOUS_DAMPED": waves.history.damped},
                      writes={"RELAX_Z_OUT": waves.phasors[0],
                              "RELAX_MOBILITY_OUT": waves.mobility,
                              "RELAX_EDGES_OUT": waves.edge_rotations,
                              "RELAX_PHASE": waves.phase},
                      SEED=True, TWO_SYSTEMS=two)
        if iterations <= 0:
            return  # the seed wrote the phase
        self.bind(reads={"RELAX_EDGES": waves.edge_rotations,
                         "RELAX_MOBILITY": waves.mobility})
        uniforms = {"u_num_points": res.num_points, "u_systems": waves.systems,
                    **res.topology_uniforms}
        set_uniforms(self.variants(TWO_SYSTEMS=two), uniforms)  # once, not every step
        for index in range(iterations):
            src = index % 2
            self.dispatch(count, {"u_write_phase": int(index == iterations - 1),
                                  "u_cold_start": int(not step.history)},
                          reads={"RELAX_Z_IN": waves.phasors[src]},
                          writes={"RELAX_Z_OUT": waves.phasors[1 - src]}, TWO_SYSTEMS=two)
        self.dispatch(count, uniforms, reads={"RELAX_Z_IN": waves.phasors[iterations % 2],
                                              "RELAX_COARSENING": res.coarsening},
                      writes={"RELAX_FIELDS_OUT": waves.current}, FIT=True, TWO_SYSTEMS=two)
