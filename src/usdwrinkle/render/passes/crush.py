"""Crush pass: per-vertex compression -> plane wave (docs/method.md, "Crush").

A mesh drawn from baked wave fields runs only the posed-normal part of this pass
(:meth:`CrushPass.run_baked`): the waves come from the bake.
"""
from __future__ import annotations

from .. import bindings
from ..resources import MeshResources
from ..shaders import compute_shader
from . import bind, groups, set_uniforms

#: crest damping: a turn of the compression direction by less than this a frame (radians,
#: 5 degrees) is followed with the time constant wrinkle:crestDamping; by twice this and
#: more, at once
DAMPING_DEADBAND = 0.0873


def damping_alpha(tau: float) -> float:
    """The share of the change that the damped strain follows a frame: 1 - exp(-1/tau)
    for a time constant of ``tau`` frames (0: no damping, 1)."""
    import math

    return 1.0 if tau <= 0 else 1.0 - math.exp(-1.0 / tau)


class CrushPass:
    def __init__(self, ctx):
        self.ctx = ctx
        defines = {**bindings.COMMON, **bindings.CRUSH}
        self.shader = compute_shader(ctx, "crush.glsl", defines)
        self.face_shader = compute_shader(ctx, "crush.glsl", {**defines, "FACE_NORMALS": 1})
        self.baked_shader = compute_shader(ctx, "crush.glsl", {**defines, "FROM_BAKE": 1})

    def _face_normals(self, res: MeshResources) -> None:
        set_uniforms(self.face_shader, {"u_num_triangles": res.num_triangles,
                                        **res.topology_uniforms})
        bind(bindings.CRUSH, reads={"CRUSH_POSED_POINTS": res.posed_points,
                                    "TOPOLOGY_TABLE": res.topology})
        if res.num_triangles:
            bind(bindings.CRUSH, reads={"CRUSH_TRIANGLES": res.triangles},
                 writes={"CRUSH_FACE_NORMALS_OUT": res.face_normals})
            self.face_shader.run(groups(res.num_triangles, bindings.LOCAL_SIZE))
            self.ctx.memory_barrier()

    def run(self, res: MeshResources, wrinkles: bool = True, history: bool = False) -> None:
        """Write this frame's fields and damped directions into the wave state it writes
        (``res.waves.begin`` named it), and the anchored phase. ``history``: crest damping
        reads the damped directions of the shot's previous grid frame's state."""
        waves = res.waves
        params = res.record.params
        scale = params.amplitude_scale if (wrinkles and res.record.wrinkled) else 0.0
        waves.set_systems(2 if params.biaxial > 0 else 1)
        set_uniforms(self.shader, {"u_num_points": res.num_points, "u_amplitude_scale": scale,
                                   "u_biaxial": float(params.biaxial),
                                   "u_tension": float(params.tension),
                                   "u_tension_threshold": float(params.tension_threshold),
                                   "u_slack": float(params.slack),
                                   "u_damping_alpha": damping_alpha(params.crest_damping),
                                   "u_damping_deadband": DAMPING_DEADBAND,
                                   "u_has_history": int(history),
                                   "u_slope": params.slope_table(),
                                   **res.topology_uniforms})
        self._face_normals(res)
        bind(bindings.CRUSH, reads={"CRUSH_REST_POINTS": res.rest_points,
                           "CRUSH_REST_FRAME": res.rest_frame, "CRUSH_Q_WIDTH": res.q_width,
                           "CRUSH_FACE_NORMALS": res.face_normals, "CRUSH_HOLD": res.hold,
                           "CRUSH_GAIN": res.gain,
                           "CRUSH_DAMPED_IN": waves.history.damped},
             writes={"CRUSH_FIELDS": waves.current, "CRUSH_PHASE": waves.anchor_phase,
                     "CRUSH_DAMPED": waves.written.damped})
        self.shader.run(groups(res.num_points, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()

    def run_baked(self, res: MeshResources, baked) -> None:
        """Fields of a frame drawn from a bake: posed normals computed, waves and phases
        as baked (``baked``: scene.baked.BakedFields)."""
        res.waves.write_baked(baked)
        self._face_normals(res)
        set_uniforms(self.baked_shader, {"u_num_points": res.num_points,
                                         **res.topology_uniforms})
        bind(bindings.CRUSH, reads={"CRUSH_REST_FRAME": res.rest_frame,
                                    "CRUSH_FACE_NORMALS": res.face_normals,
                                    "CRUSH_BAKED": res.waves.baked_waves},
             writes={"CRUSH_FIELDS": res.waves.current})
        self.baked_shader.run(groups(res.num_points, bindings.LOCAL_SIZE))
        self.ctx.memory_barrier()
