"""Texture units, image units and storage-buffer bindings shared by several passes (the
wave blend's, WAVE), and those of the resolve and mipmap passes, injected into the
shaders as #defines. Every other pass declares its own units in its file (its class's
UNITS: render/passes/base.py).

Tables (resources.Table) are read through texture units (``layout(binding=N) uniform
sampler2D``) and written through image units (``layout(binding=N) uniform image2D``);
the two are separate namespaces in GL. Each pass binds what it uses before it runs, so
no stage needs more than 8 image units or 16 texture units (the GL 4.5 minimums).
"""
from __future__ import annotations

from ..images.aovs import OFFSET_SLOTS
from ..method.contract import SHADER_DEFINES

#: Work group size of every compute pass.
LOCAL_SIZE = 64

#: Tables are 2^TABLE_WIDTH_LOG2 texels wide: 2048 x 16384 (GL 4.5's minimum
#: GL_MAX_TEXTURE_SIZE) holds 33 M elements.
TABLE_WIDTH_LOG2 = 11
TABLE_WIDTH = 1 << TABLE_WIDTH_LOG2

#: Defines every shader gets: these, and the constants of the contract (method/contract.py).
COMMON = {"LOCAL_SIZE": LOCAL_SIZE, "TABLE_WIDTH": TABLE_WIDTH,
          "TABLE_WIDTH_LOG2": TABLE_WIDTH_LOG2, **SHADER_DEFINES}

#: the wave blend (include/wave.glsl): the same units in every pass that includes it
WAVE = {"WAVE_HEIGHT_PROFILE": 0, "WAVE_GRADIENT_PROFILE": 1, "WAVE_POSED_POINTS": 3,
        "WAVE_FIELDS": 4, "WAVE_PHASE": 5, "WAVE_REST_POINTS": 6, "WAVE_TRIANGLES": 8}
#: the resolve pass (render/resolve.py): the three colour attachments (texture units) and
#: the output words and the count of non-finite values (storage buffers)
#: the resolve pass's sizes from the image contract (images/aovs.py)
RESOLVE_SHAPE = {"OFFSET_SLOTS": OFFSET_SLOTS}
RESOLVE = {"RESOLVE_COLOR": 0, "RESOLVE_WRINKLE": 1, "RESOLVE_NORMAL": 2,
           "RESOLVE_OUT": 0, "RESOLVE_BAD": 1}
#: the mipmap pass (render/mipmaps.py): the whole chain of a texture (storage buffer)
MIPMAP = {"MIPMAP_LEVELS": 0}
