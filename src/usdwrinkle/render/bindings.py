"""Texture units, image units and storage-buffer bindings of each pass, declared once
here and injected into the shaders as #defines.

Tables (resources.Table) are read through texture units (``layout(binding=N) uniform
sampler2D``) and written through image units (``layout(binding=N) uniform image2D``);
the two are separate namespaces in GL. Each pass binds what it uses before it runs, so
no stage needs more than 8 image units or 16 texture units (the GL 4.5 minimums).
"""
from __future__ import annotations

from ..aovs import OFFSET_SLOTS
from ..contract import SHADER_DEFINES

#: Work group size of every compute pass.
LOCAL_SIZE = 64

#: Tables are 2^TABLE_WIDTH_LOG2 texels wide: 2048 x 16384 (GL 4.5's minimum
#: GL_MAX_TEXTURE_SIZE) holds 33 M elements.
TABLE_WIDTH_LOG2 = 11
TABLE_WIDTH = 1 << TABLE_WIDTH_LOG2

#: Defines every shader gets: these, and the constants of the contract (contract.py).
COMMON = {"LOCAL_SIZE": LOCAL_SIZE, "TABLE_WIDTH": TABLE_WIDTH,
          "TABLE_WIDTH_LOG2": TABLE_WIDTH_LOG2, **SHADER_DEFINES}

# texture units (reads)
SKIN = {"SKIN_REST_POINTS": 0, "SKIN_INFLUENCES": 1, "SKIN_JOINTS": 3,
        # image units (writes)
        "SKIN_POSED_POINTS": 0,
        # storage buffers: blend shapes (only the sub-shapes with a weight are read)
        "SKIN_SUBSHAPE_OFFSETS": 0, "SKIN_SUBSHAPE_WEIGHTS": 1}
#: the normals pass (shaders/normals.glsl); its skinned variant also reads the SKIN units
#: of include/skinning.glsl (influences 1, joints 3)
NORMALS = {"NORMALS_PLAN": 0, "NORMALS_POSED_POINTS": 2, "NORMALS_AUTHORED": 4,
           "SKIN_INFLUENCES": 1, "SKIN_JOINTS": 3,
           # image units
           "NORMALS_OUT": 0}
CRUSH = {"CRUSH_POSED_POINTS": 0, "CRUSH_REST_POINTS": 1, "TOPOLOGY_TABLE": 2,
         "CRUSH_REST_FRAME": 3, "CRUSH_Q_WIDTH": 4, "CRUSH_FACE_NORMALS": 5,
         "CRUSH_TRIANGLES": 6, "CRUSH_BAKED": 7, "CRUSH_HOLD": 8, "CRUSH_GAIN": 9,
         "CRUSH_DAMPED_IN": 10,
         # image units
         "CRUSH_FIELDS": 0, "CRUSH_PHASE": 1, "CRUSH_FACE_NORMALS_OUT": 2, "CRUSH_DAMPED": 3}
RELAX = {"RELAX_POSED_POINTS": 0, "TOPOLOGY_TABLE": 1, "RELAX_FIELDS": 2,
         "RELAX_PREVIOUS_FIELDS": 3, "RELAX_ANCHOR": 4, "RELAX_EDGES": 5, "RELAX_Z_IN": 6,
         "RELAX_PREVIOUS_PHASE": 7,
         # image units
         "RELAX_PHASE": 0, "RELAX_Z_OUT": 1, "RELAX_EDGES_OUT": 2, "RELAX_FIELDS_OUT": 3}
#: the wave blend (include/wave.glsl): the same units in every pass that includes it
WAVE = {"WAVE_HEIGHT_PROFILE": 0, "WAVE_GRADIENT_PROFILE": 1, "WAVE_POSED_POINTS": 3,
        "WAVE_FIELDS": 4, "WAVE_PHASE": 5, "WAVE_TRIANGLES": 8}
DRAW = {**WAVE, "DRAW_DIFFUSE_TEXTURE": 2, "DRAW_CORNER_ST": 7,
        "DRAW_NORMAL_ST": 9, "DRAW_NORMAL_TEXTURE": 10, "DRAW_SHADING_NORMALS": 11,
        "DRAW_NORMAL_CORNERS": 12, "DRAW_DOME_TEXTURE": 13, "DRAW_CORNER_COLORS": 14}
#: wrinkle maps (maps/): the blend rasterised in UV space
MAPS = {**WAVE, "MAPS_UV": 7, "MAPS_Q_WIDTH": 9, "MAPS_SHADING_NORMALS": 10,
        "MAPS_NORMAL_CORNERS": 11, "MAPS_TANGENTS": 12, "MAPS_GAIN": 13,
        "MAPS_FRAME_NORMALS": 14}
#: displaced geometry (geometry/): the blend at every fine vertex
GEOMETRY = {**WAVE, "GEOMETRY_RANGES": 9, "GEOMETRY_ENTRIES": 10,
            "GEOMETRY_SHADING_NORMALS": 11, "GEOMETRY_NORMAL_CORNERS": 12,
            # image units
            "GEOMETRY_POINTS": 0, "GEOMETRY_NORMALS": 1}
#: the resolve pass (render/resolve.py): the three colour attachments (texture units) and
#: the output words and the count of non-finite values (storage buffers)
#: the resolve pass's sizes from the image contract (aovs.py)
RESOLVE_SHAPE = {"OFFSET_SLOTS": OFFSET_SLOTS}
RESOLVE = {"RESOLVE_COLOR": 0, "RESOLVE_WRINKLE": 1, "RESOLVE_NORMAL": 2,
           "RESOLVE_OUT": 0, "RESOLVE_BAD": 1}
#: the mipmap pass (render/mipmaps.py): the whole chain of a texture (storage buffer)
MIPMAP = {"MIPMAP_LEVELS": 0}
