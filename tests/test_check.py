"""usdwrinkle check: USD's validators plus our WrinkleAPI rules, each broken case caught."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdGeom, UsdValidation, Vt

from usdwrinkle.cli.main import main
from usdwrinkle.usd import schema
from usdwrinkle.usd.validation import VALIDATOR_NAME, register_validators

from conftest import grid_sheet
from helpers import fold_law

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


def sheet_stage(path: Path):
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.z)
    world = UsdGeom.Xform.Define(stage, "/World")
    stage.SetDefaultPrim(world.GetPrim())
    points, counts, indices = grid_sheet(4, 4, 1.0)
    mesh = UsdGeom.Mesh.Define(stage, "/World/Cloth")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    mesh.CreateExtentAttr(Vt.Vec3fArray([(-0.5, -0.5, 0), (0.5, 0.5, 0)]))
    mesh.GetPrim().ApplyAPI(schema.API_NAME)
    return stage, mesh


def _q(mesh, values, interpolation=UsdGeom.Tokens.vertex):
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "wrinkle:q", Sdf.ValueTypeNames.Vector3fArray, interpolation).Set(
        Vt.Vec3fArray.FromNumpy(np.asarray(values, np.float32)))


def _width(mesh, values, interpolation=UsdGeom.Tokens.constant):
    arr = np.atleast_1d(np.asarray(values, np.float32))
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "wrinkle:width", Sdf.ValueTypeNames.FloatArray, interpolation).Set(
        Vt.FloatArray.FromNumpy(arr))


def _float(mesh, name, value):
    mesh.GetPrim().CreateAttribute(name, Sdf.ValueTypeNames.Float).Set(value)


def _floats(mesh, name, values):
    mesh.GetPrim().CreateAttribute(name, Sdf.ValueTypeNames.FloatArray).Set(
        Vt.FloatArray(list(values)))


def _rest(mesh, count):
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "rest", Sdf.ValueTypeNames.Point3fArray, UsdGeom.Tokens.vertex).Set(
        Vt.Vec3fArray.FromNumpy(np.zeros((count, 3), np.float32)))


def _not_a_mesh(stage, mesh):
    xform = stage.DefinePrim("/World/Group", "Xform")
    xform.SetMetadata("apiSchemas", Sdf.TokenListOp.Create(prependedItems=[schema.API_NAME]))


BROKEN = [
    ("q length", lambda s, m: _q(m, np.zeros((5, 3))), "/World/Cloth", schema.Q, "5 values"),
    ("q interpolation", lambda s, m: _q(m, np.zeros((16, 3)), UsdGeom.Tokens.faceVarying),
     "/World/Cloth", schema.Q, "vertex interpolation"),
    ("q not finite", lambda s, m: _q(m, np.full((16, 3), np.nan)), "/World/Cloth", schema.Q,
     "not finite"),
    ("q too long", lambda s, m: _q(m, np.tile([0.0, 1.5, 0.0], (16, 1))), "/World/Cloth",
     schema.Q, "|q| > 1"),
    ("width zero", lambda s, m: _width(m, 0.0), "/World/Cloth", schema.WIDTH, "> 0"),
    ("width nan", lambda s, m: _width(m, np.nan), "/World/Cloth", schema.WIDTH, "finite"),
    ("width length", lambda s, m: _width(m, np.ones(7), UsdGeom.Tokens.vertex), "/World/Cloth",
     schema.WIDTH, "one value per point"),
    ("height profile short", lambda s, m: _floats(m, schema.HEIGHT_PROFILE, [1.0]),
     "/World/Cloth", schema.HEIGHT_PROFILE, "at least 2 finite"),
    ("gradient profile nan", lambda s, m: _floats(m, schema.GRADIENT_PROFILE, [0, np.nan, 1]),
     "/World/Cloth", schema.GRADIENT_PROFILE, "at least 2 finite"),
    ("rest length", lambda s, m: _rest(m, 3), "/World/Cloth", "primvars:rest", "3 values"),
    ("negative amplitude scale", lambda s, m: _float(m, schema.AMPLITUDE_SCALE, -1.0),
     "/World/Cloth", schema.AMPLITUDE_SCALE, ">= 0"),
    ("not a mesh", _not_a_mesh, "/World/Group", None, "not a Mesh"),
]


@pytest.mark.parametrize("label,breaker,prim,attribute,fragment", BROKEN,
                         ids=[b[0] for b in BROKEN])
def test_check_catches(tmp_path, capsys, label, breaker, prim, attribute, fragment):
    path = tmp_path / "shot.usda"
    stage, mesh = sheet_stage(path)
    breaker(stage, mesh)
    stage.Save()
    assert main(["check", str(path), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    ours = [f for f in report["findings"] if f["validator"] == VALIDATOR_NAME]
    assert len(ours) >= 1, report
    assert any(f["prim"] == prim and f["attribute"] == attribute and fragment in f["message"]
               for f in ours), ours


def test_clean_stage_exits_zero(tmp_path, capsys):
    path = tmp_path / "shot.usda"
    stage, mesh = sheet_stage(path)
    _q(mesh, np.tile([0.0, 0.5, 0.0], (16, 1)))
    _width(mesh, 0.1)
    stage.Save()
    assert main(["check", str(path)]) == 0
    assert "is clean" in capsys.readouterr().out
    for sample in ("shirt", "zeppelin", "curtain"):
        assert main(["check", str(SAMPLES / f"{sample}.usda")]) == 0


def test_usd_validators_run_too(corpus, capsys):
    # lbs.usda has no metersPerUnit: UsdGeom's own StageMetadataChecker says so
    assert main(["check", str(corpus / "openusd-usdskel" / "lbs.usda"), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert any(f["validator"] == "usdGeomValidators:StageMetadataChecker"
               for f in report["findings"])


def test_usage_errors_exit_two(tmp_path, capsys):
    assert main(["check", str(tmp_path / "missing.usda")]) == 2
    (tmp_path / "junk.usda").write_text("this is not usd")
    assert main(["check", str(tmp_path / "junk.usda")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert all(line.startswith("usdwrinkle: error: ") for line in err) and len(err) == 2


def test_our_validator_is_registered_with_usd():
    register_validators()
    registry = UsdValidation.ValidationRegistry()
    assert registry.HasValidator(VALIDATOR_NAME)
    names = [str(m.name) for m in registry.GetValidatorMetadataForKeyword("UsdWrinkleValidators")]
    assert VALIDATOR_NAME in names


def test_a_scalar_width_is_read_but_flagged(gl_context, tmp_path, capsys):
    """An asset that authors the width as a plain float (as the width's table in the first
    design said) still renders and bakes; check points at the schema's float[] type."""
    path = Path(__file__).resolve().parent / "data" / "scalar_width.usda"
    assert main(["bake", str(path), str(tmp_path / "baked.usda"), "--quiet"]) == 0
    stage = Usd.Stage.Open(str(tmp_path / "baked.usda"))
    amplitude = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Cloth")).GetPrimvar(
        "wrinkle:amplitude").Get(2)
    # uniform compression by 0.6 with W = 0.3 and the fallback slack: the fold law
    # (compressed beyond SLACK_RAMP x the slack: the whole length restored)
    expected, _ = fold_law(0.6, 0.3, slack=schema.DEFAULT_SLACK)
    np.testing.assert_allclose(amplitude, expected, rtol=1e-4)
    capsys.readouterr()
    assert main(["check", str(path), "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert any(f["validator"] == "usdValidation:AttributeTypeMismatch"
               and "primvars:wrinkle:width" in f["message"] for f in report["findings"])


def test_wrinkles_only_gates_on_the_wrinkle_attributes(corpus, tmp_path, capsys):
    """Issue 27: check exited 1 on CesiumMan for USD's own ShaderSdrCompliance finding and
    on a minimal shot for its stage metadata, so it could not gate a pipeline on the
    wrinkles alone. --wrinkles-only runs only our checker: those stages pass, a broken
    wrinkle attribute still fails."""
    cesium = str(corpus / "usd-wg" / "CesiumMan.usdz")
    assert main(["check", cesium]) == 1
    assert main(["check", cesium, "--wrinkles-only"]) == 0
    lbs = str(corpus / "openusd-usdskel" / "lbs.usda")
    assert main(["check", lbs]) == 1 and main(["check", lbs, "--wrinkles-only"]) == 0
    path = tmp_path / "shot.usda"
    stage, mesh = sheet_stage(path)
    _width(mesh, np.nan)
    stage.Save()
    capsys.readouterr()
    assert main(["check", str(path), "--wrinkles-only", "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    assert {f["validator"] for f in report["findings"]} == {VALIDATOR_NAME}
