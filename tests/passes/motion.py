"""The smallest real wave pass (docs/architecture.md, "A new wave pass"): each point's
motion from its rest position, in its mesh's local space, in a table of its own.

Placed in src/usdwrinkle/render/passes/ with its shader in shaders/, it would run in every
render as it is; the tests register it for one block (render/passes/base.registered).
"""
from __future__ import annotations

from pathlib import Path

from usdwrinkle.render.passes.base import Step, TableSpec, WavePass


class MotionPass(WavePass):
    SHADER = "motion.glsl"
    ROOT = Path(__file__).parent  # in the package: the default, shaders/
    UNITS = {"MOTION_REST_POINTS": 0, "MOTION_POSED_POINTS": 1,  # texture units (reads)
             "MOTION_OUT": 0}                                    # image units (writes)
    TABLES = {"motion": TableSpec("point", 4)}  # xyz: posed - rest; w: its length
    TIMING = "skin"
    ORDER = 15  # after skin (10), before normals (20)

    def run(self, res, step: Step) -> None:
        self.dispatch(res.num_points, {"u_num_points": res.num_points},
                      reads={"MOTION_REST_POINTS": res.rest_points,
                             "MOTION_POSED_POINTS": res.posed_points},
                      writes={"MOTION_OUT": self.table(res, "motion")})
