"""Length pass: no ring of the wrinkled surface draws more than the cloth's rest area
around it (length.glsl; docs/method.md, "The cloth's length").

After the relaxation and its fit, per vertex, the blend's surface over the triangles
around it is sampled with its exact gradient; where the ring is compressed beyond the
slack the drawn folds leave (contract.DRAWN_SLACK of wrinkle:slack), the vertex's drawn
folds are scaled down as far as the ring needs to draw no more than the rest area that
slack leaves. A second dispatch writes the scales into the fields'
length texels, once every vertex's is computed, since each vertex's samples read its
neighbours' folds; the blend multiplies the drawn amplitudes by them, and a bake writes
the drawn amplitudes. A frame drawn from a bake has its scales in its amplitudes
already; a frame without relaxation (relaxIterations 0) draws crush's waves as they are,
and has no scale either, and a preroll step (computed for the phase history alone, never
drawn) leaves the pass out.
"""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from . import bind_wave, irregular
from .base import Step, TableSpec, WavePass, wave_pass


@wave_pass
class LengthPass(WavePass):
    """No ring drawing more than the cloth's length (length.glsl): scales, then applied."""

    SHADER = "length.glsl"
    UNITS = {**bindings.WAVE, "TOPOLOGY_TABLE": 9, "LENGTH_SCALE": 10,
             "LENGTH_REST_POINTS": 11,
             # image units
             "LENGTH_SCALE_OUT": 0, "LENGTH_FIELDS": 1}
    TABLES = {"scale": TableSpec("point", 1)}
    TIMING = "relax"
    ORDER = 50

    def run(self, res: MeshResources, step: Step) -> None:
        if step.baked is not None or step.iterations <= 0:
            return
        # a preroll step is never drawn, and its scales are read by nothing else: crush
        # sets them to 1 each frame, and relax and the next frame read the weights beside
        # them, not them
        if not step.drawn:
            return
        if not (step.wrinkles and res.record.wrinkled) or not res.num_triangles:
            return
        two = res.waves.systems > 1
        rough = irregular(res)
        scale = self.table(res, "scale")
        shader = self.variants(TWO_SYSTEMS=two, IRREGULAR=rough)
        bind_wave(self.UNITS, res, shader)
        self.dispatch(res.num_points, {"u_num_points": res.num_points,
                                       "u_slack": float(res.record.params.slack),
                                       **res.topology_uniforms},
                      reads={"TOPOLOGY_TABLE": res.topology,
                             "LENGTH_REST_POINTS": res.rest_points},
                      writes={"LENGTH_SCALE_OUT": scale}, TWO_SYSTEMS=two, IRREGULAR=rough)
        self.dispatch(res.num_points, {"u_num_points": res.num_points},
                      reads={"LENGTH_SCALE": scale},
                      read_writes={"LENGTH_FIELDS": res.waves.current}, APPLY=True)
