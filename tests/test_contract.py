"""The Python <-> GLSL contract is written once (src/usdwrinkle/method/contract.py and
render/bindings.py): every upper-case name a shader uses is defined by Python or by the
shader itself, and no shader re-types a Python constant."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from usdwrinkle.method import contract
from usdwrinkle.method.contract import FIELD_TEXELS, WrinkleFields
from usdwrinkle.render import bindings

SHADERS = Path(__file__).resolve().parents[1] / "shaders"
NAME = re.compile(r"\b([A-Z][A-Z0-9_]*[A-Z0-9])\b")
DEFINE = re.compile(r"^\s*#\s*(?:define|ifndef|ifdef)\s+([A-Za-z_]\w*)", re.M)
CONST = re.compile(r"\bconst\s+\w+\s+([A-Z][A-Z0-9_]*)\s*=")
#: upper-case local variables and parameters (N0, T1: the method's symbols)
LOCAL = re.compile(r"\b(?:float|int|uint|bool|[iu]?vec[234]|mat[234](?:x[234])?)\s+"
                   r"([A-Z][A-Z0-9_]*)\b(?!\s*\()")
#: what the shaders use without defining: GLSL's own names and the stage switches
#: that render/shaders.py and the passes add per program
GLSL = {"GL_ARB_shader_draw_parameters"}
STAGE_SWITCHES = {"VERTEX_SHADER", "FRAGMENT_SHADER", "FACE_NORMALS", "FROM_BAKE",
                  "DEEPEN_GRADIENT", "SEED",
                  "STEP", "FIT", "TWO_SYSTEMS", "NORMAL_MAP",
                  # the wave blend's (render/passes/__init__.py, irregular)
                  "IRREGULAR",
                  # the normals pass's (render/passes/normals.py)
                  "SMOOTH", "FACETED", "SKINNED",
                  # the draw pass's (render/passes/draw.py)
                  "FALLBACK_SURFACE", "TEXTURED", "DOME", "MASKED", "VERTEX_COLOR",
                  "SHADE_SAMPLES", "RELIEF",
                  # the resolve pass's (render/resolve.py)
                  "SAMPLES", "NEED_FIELDS", "NEED_NORMAL", "OUTPUT_AOVS", "OUTPUT_EXR",
                  "OUTPUT_8BIT", "HALF_COLOR_NORMAL", "OVER_BLACK",
                  # the maps' (maps/raster.py)
                  "MIKKTSPACE", "PARALLAX",
                  # the length pass's (render/passes/length.py)
                  "APPLY",
                  # the mipmap pass's (render/mipmaps.py)
                  "FLOAT"}
def pass_classes():
    """Every pass of the package: the wave passes (render/passes/base.py's registry), the
    draw, the maps' and the displaced geometry's."""
    from usdwrinkle.geometry.evaluate import GeometryEvaluator
    from usdwrinkle.maps.raster import MapRasterizer
    from usdwrinkle.render.passes.base import wave_passes
    from usdwrinkle.render.passes.draw import DrawPass

    return [*wave_passes(), DrawPass, MapRasterizer, GeometryEvaluator]


PYTHON = {name for table in (bindings.COMMON, bindings.RESOLVE, bindings.RESOLVE_SHAPE,
                             bindings.MIPMAP, *(cls.UNITS for cls in pass_classes()))
          for name in table}


def shader_files():
    return sorted(SHADERS.rglob("*.glsl"))


def strip_comments(text: str) -> str:
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def test_every_shader_name_is_defined_once():
    own = set()
    for path in shader_files():
        text = strip_comments(path.read_text())
        own |= set(DEFINE.findall(text)) | set(CONST.findall(text)) | set(LOCAL.findall(text))
    retyped = own & PYTHON
    assert not retyped, f"shaders define names that Python injects: {sorted(retyped)}"
    for path in shader_files():
        text = strip_comments(path.read_text())
        used = set(NAME.findall(text)) - own - PYTHON - GLSL - STAGE_SWITCHES
        assert not used, f"{path.name} uses names that nothing defines: {sorted(used)}"


def test_the_contract_reaches_every_shader():
    for name in ("MIN_RATIO", "WEIGHT_FLOOR", "MAX_LIGHTS", "JOINT_TEXELS", "FIELD_TEXELS"):
        assert name in bindings.COMMON
        assert float(bindings.COMMON[name]) == float(getattr(contract, name))
    assert contract.glsl_literal(0.05) == "0.05" and contract.glsl_literal(1e-7) == "1e-07"
    assert contract.glsl_literal(4.0) == "4.0" and contract.glsl_literal(8) == "8"


def test_fields_follow_the_layout():
    n = 5
    table = np.arange(n * FIELD_TEXELS * 4, dtype=np.float32).reshape(-1, 4)
    posed = np.arange(n * 4, dtype=np.float32).reshape(n, 4)
    phases = np.arange(2 * n, dtype=np.float32).reshape(n, 2)
    fields = WrinkleFields.from_tables(posed, table, phases, phases + 100)
    texel = table.reshape(n, FIELD_TEXELS, 4)
    np.testing.assert_array_equal(fields.wave_vector, texel[:, contract.FIELD_WAVE_TEXEL, :3])
    np.testing.assert_array_equal(fields.amplitude, texel[:, contract.FIELD_WAVE_TEXEL, 3])
    np.testing.assert_array_equal(fields.compression,
                                  texel[:, contract.FIELD_DIRECTION_TEXEL, 3])
    np.testing.assert_array_equal(fields.normals, texel[:, contract.FIELD_NORMAL_TEXEL, :3])
    np.testing.assert_array_equal(fields.points, posed[:, :3])
    np.testing.assert_array_equal(fields.wave_vector2, texel[:, contract.FIELD_WAVE2_TEXEL, :3])
    np.testing.assert_array_equal(fields.amplitude2, texel[:, contract.FIELD_WAVE2_TEXEL, 3])
    np.testing.assert_array_equal(fields.compression2,
                                  texel[:, contract.FIELD_DIRECTION2_TEXEL, 3])
    np.testing.assert_array_equal(fields.phase, phases[:, 0])       # system 1: x
    np.testing.assert_array_equal(fields.phase2, phases[:, 1])      # system 2: y
    np.testing.assert_array_equal(fields.anchor_phase2, phases[:, 1] + 100)
    assert list(fields.arrays()) == ["points", "normals", "usable", "wave_vector", "amplitude",
                                     "drawn", "direction", "compression", "phase", "anchor_phase",
                                     "wave_vector2", "amplitude2", "direction2",
                                     "compression2", "phase2", "anchor_phase2", "wavenumber",
                                     "offset", "offset_gradient", "length_scale", "weight",
                                     "weight2"]
    np.testing.assert_array_equal(fields.offset, texel[:, contract.FIELD_DEEPEN_TEXEL, 0])
    np.testing.assert_array_equal(fields.length_scale, texel[:, contract.FIELD_LENGTH_TEXEL, 0])
    np.testing.assert_array_equal(fields.weight, texel[:, contract.FIELD_LENGTH_TEXEL, 1])
    np.testing.assert_array_equal(fields.weight2, texel[:, contract.FIELD_LENGTH_TEXEL, 2])
    np.testing.assert_array_equal(fields.offset_gradient,
                                  texel[:, contract.FIELD_DEEPEN_TEXEL, 1:])
    np.testing.assert_array_equal(fields.wavenumber, 0.0)  # no damped table given
    # the normal texel's w: 0 where the ring is not usable (all drawn), else 1 + the share
    # drawn (in [0, 1])
    table[0::FIELD_TEXELS, 3] = [0.0, 1.0, 1.25, 2.0, 7.0]
    drawn = WrinkleFields.from_tables(posed, table, phases, phases)
    np.testing.assert_array_equal(drawn.usable, [False, True, True, True, True])
    np.testing.assert_array_equal(drawn.drawn, [1.0, 0.0, 0.25, 1.0, 1.0])
    # the drawn amplitudes carry the share and the length pass's scale
    np.testing.assert_array_equal(drawn.drawn_amplitude,
                                  drawn.amplitude * drawn.drawn * drawn.length_scale)
    np.testing.assert_array_equal(drawn.drawn_amplitude2, drawn.amplitude2 * drawn.length_scale)
    damped = np.arange(n * 4, dtype=np.float32).reshape(n, 4)
    np.testing.assert_array_equal(
        WrinkleFields.from_tables(posed, table, phases, phases, damped).wavenumber, damped[:, 3])


def test_the_wave_blend_is_written_once():
    """Draw, the wrinkle maps, the geometry and the length pass evaluate the waves through
    include/wave.glsl's blend (wave_blend, or blend_corner_waves of corners gathered by
    corner_waves): no other shader samples the profiles or sums the corner waves itself."""
    users = []
    for path in shader_files():
        text = strip_comments(path.read_text())
        if path.name == "wave.glsl":
            assert "Wave wave_blend(" in text and "Wave blend_corner_waves(" in text
            continue
        assert "u_height_profile" not in text and "u_gradient_profile" not in text, path.name
        if '#include "include/wave.glsl"' in text:
            # the corners come from corner_waves (the length pass reads and scales each
            # vertex's own wave, beside the blends it samples)
            assert "FIELD_WAVE" not in text or path.name == "length.glsl", path.name
            assert "wave_blend(" in text or ("corner_waves(" in text and
                                             "blend_corner_waves(" in text), path.name
            users.append(path.name)
    assert {"draw.glsl", "maps.glsl", "geometry.glsl", "length.glsl"} <= set(users)


def test_each_on_disk_contract_is_written_once():
    """Issue 25: the baked primvar names, the AOV and EXR channel names, the half-float
    mask and the UDIM sentinel stand in one module each (usd/schema.py, images/aovs.py,
    method/contract.py); a writer, reader or shader that types one again fails here."""
    from pathlib import Path

    source = Path(__file__).resolve().parents[1] / "src" / "usdwrinkle"
    owners = {
        '"primvars:wrinkle:waveVector': "usd/schema.py",
        '"primvars:wrinkle:phase': "usd/schema.py",
        '"primvars:wrinkle:compression"': "usd/schema.py",
        '"wrinkle.height"': "images/aovs.py",
        '"wrinkle.amplitude"': "images/aovs.py",
        '"N.X"': "images/aovs.py",
    }
    for text, owner in owners.items():
        places = sorted(str(p.relative_to(source)) for p in source.rglob("*.py")
                        if "__pycache__" not in p.parts and text in p.read_text())
        assert places == [owner], (text, places)
    for path in SHADERS.rglob("*.glsl"):
        code = strip_comments(path.read_text())
        assert "!= -2" not in code and "== -2" not in code, path.name  # UDIM_REPEAT
        assert "[10]" not in code and "< 10;" not in code, path.name     # OFFSET_SLOTS
