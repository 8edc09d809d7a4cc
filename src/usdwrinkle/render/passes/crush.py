"""Crush pass: per-vertex compression -> plane wave (docs/method.md, "Crush").

A mesh drawn from baked wave fields runs only the posed-normal part of this pass
(:meth:`CrushPass.run_baked`): the waves come from the bake.
"""
from __future__ import annotations

from ..resources import MeshResources
from .base import Step, WavePass, wave_pass

#: crest damping: a compression direction that lies less than this from the damped one
#: (radians, 5 degrees) is followed beyond the band wrinkle:crestDamping; from twice this
#: on, at once
DAMPING_DEADBAND = 0.0873


def damping_band(degrees: float) -> float:
    """wrinkle:crestDamping's band in radians: the damped direction turns towards the
    strain's only by as much as the two lie further apart (0: no damping)."""
    import math

    return math.radians(max(float(degrees), 0.0))


@wave_pass
class CrushPass(WavePass):
    """Each vertex's compression turned into a plane wave (crush.glsl); with baked wave
    fields, their posed normals alone."""

    SHADER = "crush.glsl"
    UNITS = {"CRUSH_POSED_POINTS": 0, "CRUSH_REST_POINTS": 1, "TOPOLOGY_TABLE": 2,
             "CRUSH_REST_FRAME": 3, "CRUSH_Q_WIDTH": 4, "CRUSH_FACE_NORMALS": 5,
             "CRUSH_TRIANGLES": 6, "CRUSH_BAKED": 7, "CRUSH_HOLD": 8, "CRUSH_COARSENING": 9,
             "CRUSH_DAMPED_IN": 10, "CRUSH_ANCHOR": 11,
             # image units
             "CRUSH_FIELDS": 0, "CRUSH_PHASE": 1, "CRUSH_FACE_NORMALS_OUT": 2,
             "CRUSH_DAMPED": 3}
    TIMING = "crush"
    ORDER = 30

    def _face_normals(self, res: MeshResources) -> None:
        self.bind(reads={"CRUSH_POSED_POINTS": res.posed_points,
                         "TOPOLOGY_TABLE": res.topology})
        if res.num_triangles:
            self.dispatch(res.num_triangles, {"u_num_triangles": res.num_triangles,
                                              **res.topology_uniforms},
                          reads={"CRUSH_TRIANGLES": res.triangles},
                          writes={"CRUSH_FACE_NORMALS_OUT": res.face_normals},
                          FACE_NORMALS=True)

    def run(self, res: MeshResources, step: Step) -> None:
        """Write this frame's fields and damped directions into the wave state it writes
        (``res.waves.begin`` named it), and the anchored phase. With history, crest
        damping reads the damped directions of the shot's previous grid frame's state."""
        if step.baked is not None:
            self.run_baked(res, step.baked)
            return
        waves = res.waves
        params = res.record.params
        scale = params.amplitude_scale if (step.wrinkles and res.record.wrinkled) else 0.0
        waves.set_systems(2 if params.biaxial > 0 else 1)
        uniforms = {"u_num_points": res.num_points, "u_amplitude_scale": scale,
                    "u_biaxial": float(params.biaxial),
                    "u_tension": float(params.tension),
                    "u_tension_threshold": float(params.tension_threshold),
                    "u_slack": float(params.slack),
                    "u_damping_band": damping_band(params.crest_damping),
                    "u_damping_deadband": DAMPING_DEADBAND,
                    "u_has_history": int(step.history),
                    "u_slope": params.slope_table(),
                    **res.topology_uniforms}
        self._face_normals(res)
        self.dispatch(res.num_points, uniforms,
                      reads={"CRUSH_REST_POINTS": res.rest_points,
                             "CRUSH_REST_FRAME": res.rest_frame, "CRUSH_Q_WIDTH": res.q_width,
                             "CRUSH_FACE_NORMALS": res.face_normals, "CRUSH_HOLD": res.hold,
                             "CRUSH_COARSENING": res.coarsening,
                             "CRUSH_DAMPED_IN": waves.history.damped,
                             "CRUSH_ANCHOR": res.anchor},
                      writes={"CRUSH_FIELDS": waves.current, "CRUSH_PHASE": waves.anchor_phase,
                              "CRUSH_DAMPED": waves.written.damped})
        self._deepen_gradient(res)

    def _deepen_gradient(self, res: MeshResources) -> None:
        """Each point's deepening offset's gradient over its ring (crush.glsl
        DEEPEN_GRADIENT), once crush has written every point's offset."""
        self.dispatch(res.num_points, {"u_num_points": res.num_points,
                                       **res.topology_uniforms},
                      reads={"CRUSH_POSED_POINTS": res.posed_points,
                             "TOPOLOGY_TABLE": res.topology},
                      read_writes={"CRUSH_FIELDS": res.waves.current}, DEEPEN_GRADIENT=True)

    def run_baked(self, res: MeshResources, baked) -> None:
        """Fields of a frame drawn from a bake: posed normals computed, waves and phases
        as baked (``baked``: scene.baked.BakedFields)."""
        res.waves.write_baked(baked)
        self._face_normals(res)
        self.dispatch(res.num_points, {"u_num_points": res.num_points,
                                       **res.topology_uniforms},
                      reads={"CRUSH_REST_FRAME": res.rest_frame,
                             "CRUSH_FACE_NORMALS": res.face_normals,
                             "CRUSH_BAKED": res.waves.baked_waves},
                      writes={"CRUSH_FIELDS": res.waves.current}, FROM_BAKE=True)
        self._deepen_gradient(res)
