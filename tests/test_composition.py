"""Composition options (issue 44): --sublayer, --variant and --mask open a shot as a
pipeline composes it, without a shot file; a bake records them."""
from __future__ import annotations

import hashlib
import json
from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Usd

from usdwrinkle.cli.main import main
from usdwrinkle.process.errors import UsdWrinkleError
from usdwrinkle.scene.composition import Composition, parse_variant
from usdwrinkle.scene.stage import open_stage

from helpers import read_exr

SHIRT = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
SLEEVE = "/World/Arm/Sleeve"


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_an_override_layer_over_a_usdz_without_a_shot_file(gl_context, corpus, tmp_path,
                                                           capsys):
    """The README's CesiumMan recipe without its shot file: apply writes WrinkleAPI into an
    override layer, and render and check read it with --sublayer. The package is not
    changed, and without --sublayer nothing is wrinkled."""
    usdz = corpus / "usd-wg" / "CesiumMan.usdz"
    before = digest(usdz)
    overrides = tmp_path / "overrides.usda"
    assert main(["apply", str(usdz), "/CesiumMan/**/Cesium_Man_2", "-o", str(overrides),
                 "--width", "0.05"]) == 0
    assert main(["render", str(usdz), str(tmp_path / "c.####.exr"), "--sublayer",
                 str(overrides), "--frames", "12", "--width", "160"]) == 0
    wrinkled = read_exr(tmp_path / "c.0012.exr")["wrinkle.height"]
    assert np.abs(wrinkled).max() > 1e-3
    capsys.readouterr()
    assert main(["render", str(usdz), str(tmp_path / "n.####.exr"), "--frames", "12",
                 "--width", "160"]) == 0
    assert "no mesh has WrinkleAPI applied" in capsys.readouterr().err
    assert np.abs(read_exr(tmp_path / "n.0012.exr")["wrinkle.height"]).max() == 0
    assert main(["check", str(usdz), "--sublayer", str(overrides), "--wrinkles-only",
                 "--json"]) == 0
    widths = json.loads(capsys.readouterr().out)["widths"]
    assert [w["prim"].rsplit("/", 1)[-1] for w in widths] == ["Cesium_Man_2"]
    assert digest(usdz) == before
    # an output may not be the override layer the stage is composed with
    assert main(["bake", str(usdz), str(overrides), "--sublayer", str(overrides)]) == 2
    assert digest(usdz) == before


def _variant_shot(tmp_path) -> Path:
    """The shirt, referenced, under a variant set 'fold' whose variants author other widths
    (a variant's opinion is stronger than the reference's, LIVRPS)."""
    path = tmp_path / "shot.usda"
    path.write_text(f"""#usda 1.0
(
    metersPerUnit = 1
    startTimeCode = 1
    endTimeCode = 24
)

def Xform "World" (
    prepend references = @{SHIRT}@</World>
    variants = {{ string fold = "fine" }}
    prepend variantSets = "fold"
)
{{
    variantSet "fold" = {{
        "coarse" {{
            over "Arm"
            {{
                over "Sleeve"
                {{
                    float[] primvars:wrinkle:width = [0.4]
                }}
            }}
        }}
        "fine" {{
            over "Arm"
            {{
                over "Sleeve"
                {{
                    float[] primvars:wrinkle:width = [0.2]
                }}
            }}
        }}
    }}
}}
""")
    return path


def test_a_variant_selection_without_a_shot_file(gl_context, tmp_path, capsys):
    shot = _variant_shot(tmp_path)
    for argv, width in (([], 0.2), (["--variant", "/World{fold=coarse}"], 0.4)):
        assert main(["check", str(shot), "--wrinkles-only", "--json", *argv]) == 0
        widths = json.loads(capsys.readouterr().out)["widths"]
        assert widths[0]["width"] == pytest.approx([width, width]), argv
    # a bake records the selection: its layer renders as the composed stage did
    layer = tmp_path / "bake.usda"
    assert main(["bake", str(shot), str(layer), "--variant", "/World{fold=coarse}",
                 "--frames", "3"]) == 0
    baked = Usd.Stage.Open(str(layer))
    assert baked.GetPrimAtPath("/World").GetVariantSets().GetVariantSet(
        "fold").GetVariantSelection() == "coarse"
    width = baked.GetPrimAtPath(SLEEVE).GetAttribute("primvars:wrinkle:width").Get()
    assert list(width) == [pytest.approx(0.4)]
    assert main(["render", str(shot), str(tmp_path / "d.####.exr"), "--variant",
                 "/World{fold=coarse}", "--frames", "3", "--width", "160"]) == 0
    assert main(["render", str(layer), str(tmp_path / "b.####.exr"), "--frames", "3",
                 "--width", "160"]) == 0
    direct = read_exr(tmp_path / "d.0003.exr")["wrinkle.height"]
    from_bake = read_exr(tmp_path / "b.0003.exr")["wrinkle.height"]
    assert np.abs(direct).max() > 1e-3
    np.testing.assert_allclose(from_bake, direct, atol=1e-5)


def test_a_bake_records_its_sublayers(gl_context, tmp_path):
    overrides = tmp_path / "overrides.usda"
    layer = Sdf.Layer.CreateNew(str(overrides))
    spec = Sdf.CreatePrimInLayer(layer, SLEEVE)
    spec.specifier = Sdf.SpecifierOver
    Sdf.AttributeSpec(spec, "wrinkle:amplitudeScale", Sdf.ValueTypeNames.Float).default = 2.0
    layer.Save()
    out = tmp_path / "out" / "bake.usda"
    assert main(["bake", str(SHIRT), str(out), "--sublayer", str(overrides), "--frames",
                 "3"]) == 0
    written = Sdf.Layer.FindOrOpen(str(out))
    assert [str((out.parent / p).resolve()) for p in written.subLayerPaths] == \
        [str(overrides.resolve()), str(SHIRT.resolve())]
    assert Usd.Stage.Open(str(out)).GetPrimAtPath(SLEEVE).GetAttribute(
        "wrinkle:amplitudeScale").Get() == 2.0


def test_a_population_mask(tmp_path):
    stage = open_stage(str(SHIRT), Composition(mask=(SLEEVE, "/World/main_cam")))
    assert stage.GetPrimAtPath(SLEEVE) and stage.GetPrimAtPath("/World/main_cam")
    assert not stage.GetPrimAtPath("/World/Lights/key")
    assert open_stage(str(SHIRT)).GetPrimAtPath("/World/Lights/key")


@pytest.mark.parametrize("composition,fragment", [
    (Composition(variants=("/World{fold}",)), "must be a prim path with one selection"),
    (Composition(variants=("/World",)), "must be a prim path with one selection"),
    (Composition(variants=("/World{fold=huge}",)), "has no variant 'huge' (its variants: "
                                                    "coarse, fine)"),
    (Composition(variants=("/World{size=huge}",)), "has no variant set 'size' (its sets: "
                                                    "fold)"),
    (Composition(variants=("/Nope{fold=fine}",)), "no prim /Nope on the stage"),
    (Composition(mask=("/World/Nope",)), "mask '/World/Nope' names no prim"),
    (Composition(mask=("World",)), "is not an absolute prim path"),
    (Composition(sublayers=("missing.usda",)), "sublayer 'missing.usda' does not exist"),
])
def test_compositions_that_select_nothing_are_refused(tmp_path, composition, fragment):
    shot = _variant_shot(tmp_path)
    with pytest.raises(UsdWrinkleError) as caught:
        open_stage(str(shot), composition)
    assert fragment in str(caught.value)


def test_the_stage_itself_is_no_sublayer(tmp_path):
    shot = _variant_shot(tmp_path)
    with pytest.raises(UsdWrinkleError, match="is the stage itself"):
        open_stage(str(shot), Composition(sublayers=(str(shot),)))


@pytest.mark.slow
@pytest.mark.parametrize("wrinkles", [True, False])
def test_a_farm_render_composes_the_stage_as_a_serial_one(gl_context, tmp_path, wrinkles):
    """--dask with --variant and --mask: the client bakes the composed stage (its layer
    carries the selection) and the workers mask as it did; without wrinkles there is no
    bake and the workers open the stage with the whole composition. Frames equal the
    serial render's."""
    shot = _variant_shot(tmp_path)
    extra = ["--variant", "/World{fold=coarse}", "--mask", f"{SLEEVE},/World/main_cam",
             "--frames", "2:3", "--width", "96", "--quiet"]
    if not wrinkles:
        extra.append("--no-wrinkles")
    assert main(["render", str(shot), str(tmp_path / "s" / "f.####.exr"), *extra]) == 0
    assert main(["render", str(shot), str(tmp_path / "d" / "f.####.exr"), *extra,
                 "--dask", "local", "--workers", "1"]) == 0
    for frame in (2, 3):
        serial = read_exr(tmp_path / "s" / f"f.{frame:04d}.exr")
        farm = read_exr(tmp_path / "d" / f"f.{frame:04d}.exr")
        for name in ("R", "G", "B", "A", "wrinkle.height"):
            np.testing.assert_allclose(farm[name], serial[name], atol=1e-5, err_msg=name)
    height = read_exr(tmp_path / "s" / "f.0003.exr")["wrinkle.height"]
    assert (np.abs(height).max() > 1e-3) == wrinkles


def test_parse_variant():
    assert parse_variant("/World/Shirt{look=red}") == ("/World/Shirt", "look", "red")


def test_the_api_takes_the_composition_options(gl_context, tmp_path):
    from usdwrinkle import api

    shot = _variant_shot(tmp_path)
    paths = api.render(str(shot), str(tmp_path / "a.####.exr"), frames=[3], width=96,
                       variant=["/World{fold=coarse}"], mask=f"{SLEEVE},/World/main_cam")
    assert [Path(p).name for p in paths] == ["a.0003.exr"]
    assert np.abs(read_exr(tmp_path / "a.0003.exr")["wrinkle.height"]).max() > 1e-3
