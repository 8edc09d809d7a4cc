"""The schema's fallbacks and documentation are the renderer's (issue 42, finding 1): both
schema files against the code's constants, and USD's own answer on an unauthored mesh."""
from __future__ import annotations

import math
from pathlib import Path

import pytest
from pxr import Sdf, Usd, UsdGeom

from usdwrinkle.render.passes.crush import DAMPING_DEADBAND
from usdwrinkle.usd import schema

SCHEMAS = Path(__file__).resolve().parents[1] / "schemas"

#: attribute -> the code's fallback
FALLBACKS = {
    schema.SLACK: schema.DEFAULT_SLACK,
    schema.CREST_DAMPING: schema.DEFAULT_CREST_DAMPING,
    schema.IRREGULARITY: schema.DEFAULT_IRREGULARITY,
    schema.CLOTH: schema.DEFAULT_CLOTH,
    schema.BIAXIAL: schema.DEFAULT_BIAXIAL,
    schema.TENSION: schema.DEFAULT_TENSION,
    schema.TENSION_THRESHOLD: schema.DEFAULT_TENSION_THRESHOLD,
    schema.RELAX_ITERATIONS: schema.DEFAULT_RELAX_ITERATIONS,
    schema.AMPLITUDE_SCALE: 1.0,
}


@pytest.mark.parametrize("name", ["schema.usda", "generatedSchema.usda"])
def test_the_schema_files_hold_the_code_s_fallbacks(name):
    layer = Sdf.Layer.FindOrOpen(str(SCHEMAS / name))
    api = layer.GetPrimAtPath("/WrinkleAPI")
    assert api, name
    for attribute, fallback in FALLBACKS.items():
        spec = api.properties[attribute]
        value = spec.default
        if isinstance(fallback, float):
            assert value == pytest.approx(fallback, rel=1e-6), (name, attribute, value)
        else:
            assert value == fallback, (name, attribute, value)
    cloth = api.properties[schema.CLOTH]
    assert list(cloth.allowedTokens) == list(schema.CLOTH_TOKENS)
    doc = " ".join((cloth.documentation or cloth.customData.get("userDocBrief", "")).split())
    for preset, metres in schema.CLOTH_WIDTHS_M.items():
        assert f"{preset} {100 * metres:.1f} cm" in doc, (name, preset, doc)
    assert f"{100 * schema.CURVED_WIDTH_M:g} cm" in doc
    assert f"{100 * schema.CURVED_RADIUS_M:g} cm" in doc
    damping = api.properties[schema.CREST_DAMPING]
    text = " ".join((damping.documentation or
                     damping.customData.get("userDocBrief", "")).split())
    # crush.glsl's rule: slow under the deadband, at once from twice it
    assert f"{math.degrees(DAMPING_DEADBAND):.0f} degrees" in text
    assert f"{2 * math.degrees(DAMPING_DEADBAND):.0f} degrees" in text


def test_usd_answers_the_renderer_s_fallback_on_an_unauthored_mesh():
    stage = Usd.Stage.Open(str(Path(__file__).resolve().parents[1] / "sample_stages" /
                               "shirt.usda"))
    sleeve = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    assert sleeve.HasAPI(schema.API_NAME) or schema.has_wrinkle_api(sleeve)
    attr = sleeve.GetAttribute(schema.SLACK)
    assert not attr.HasAuthoredValue()
    assert attr.Get() == pytest.approx(schema.DEFAULT_SLACK)
    assert sleeve.GetAttribute(schema.CREST_DAMPING).Get() == schema.DEFAULT_CREST_DAMPING
