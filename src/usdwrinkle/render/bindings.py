"""Shader storage binding points, declared once here and injected as #defines.

Each pass binds its own buffers before it runs, so no shader uses more than 8
blocks (the GL 4.3 minimum per stage).
"""
from __future__ import annotations

SKIN = {"SKIN_REST_POINTS": 0, "SKIN_POSED_POINTS": 1, "SKIN_JOINT_INDICES": 2,
        "SKIN_JOINT_WEIGHTS": 3, "SKIN_JOINTS": 4, "SKIN_SUBSHAPE_OFFSETS": 5,
        "SKIN_SUBSHAPE_WEIGHTS": 6}
CRUSH = {"CRUSH_POSED_POINTS": 0, "CRUSH_REST_POINTS": 1, "CRUSH_TOPOLOGY": 2,
         "CRUSH_REST_FRAME": 3, "CRUSH_Q_WIDTH": 4, "CRUSH_FIELDS": 5, "CRUSH_PHASE": 6,
         "CRUSH_FACE_NORMALS": 7}
RELAX = {"RELAX_POSED_POINTS": 0, "RELAX_TOPOLOGY": 1, "RELAX_FIELDS": 2,
         "RELAX_PREVIOUS_FIELDS": 3, "RELAX_ANCHOR": 4, "RELAX_PHASE": 5, "RELAX_EDGES": 6,
         # the iteration kernel has no previous fields: its phasors take binding 3
         "RELAX_Z_IN": 3, "RELAX_Z_OUT": 7}
DRAW = {"DRAW_POSED_POINTS": 0, "DRAW_FIELDS": 1, "DRAW_PHASE": 2, "DRAW_TOPOLOGY": 3,
        "DRAW_CORNER_ST": 4}

#: Work group size of every compute pass.
LOCAL_SIZE = 64
