"""usdwrinkle bake: the baked primvars hold the analytic answers, Pixar's baselines hold
with --with-points, and layers are written safely."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdShade, UsdSkel, Vt

from usdwrinkle.cli.main import main
from usdwrinkle.reference.relax import phase_misfit, wrap
from usdwrinkle.scene.topology import build_topology

from conftest import grid_sheet
from helpers import baked, fold_law, interior, point_cache_stage, rotation_matrix

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"


def bake_sheet(tmp_path, rest, posed, counts, indices, *args, **kwargs):
    stage = point_cache_stage(rest, {1: posed}, counts, indices, **kwargs)
    source = tmp_path / "sheet.usda"
    stage.GetRootLayer().Export(str(source))
    out = tmp_path / "sheet_wrinkles.usda"
    assert main(["bake", str(source), str(out), "--quiet", *args]) == 0
    return out


def test_uniform_compression_bakes_the_analytic_wave(gl_context, tmp_path):
    rest, counts, indices = grid_sheet(31, 31, 2.0)
    ratio, width = 0.7, 0.3
    posed = rest * np.array([ratio, 1, 1], np.float32)
    out = bake_sheet(tmp_path, rest, posed, counts, indices, width=width)
    fields, _ = baked(out, "/Sheet", 1)
    inside = interior(rest, 0.1)
    height, k_law = fold_law(ratio, width)
    np.testing.assert_allclose(fields["amplitude"][inside], height, rtol=0.01)
    k = fields["waveVector"][inside]
    np.testing.assert_allclose(np.linalg.norm(k, axis=1), k_law, rtol=0.01)
    assert np.all(np.abs(k[:, 0]) / np.linalg.norm(k, axis=1) > 0.999)
    np.testing.assert_allclose(fields["compression"][inside], ratio, atol=1e-3)
    np.testing.assert_allclose(np.abs(fields["direction"][inside][:, 0]), 1.0, atol=1e-3)
    topology = build_topology(counts, indices, rest)
    misfit = phase_misfit(fields["points"], fields["waveVector"], fields["phase"], topology,
                          inside)
    assert misfit < 0.1


def test_painted_q_bakes_its_compression(gl_context, tmp_path):
    rest, counts, indices = grid_sheet(11, 11, 2.0)
    amount = 0.7
    q = np.tile([0.0, amount, 0.0], (len(rest), 1)).astype(np.float32)
    out = bake_sheet(tmp_path, rest, rest, counts, indices, q=q, width=0.2)
    fields, _ = baked(out, "/Sheet", 1)
    np.testing.assert_allclose(fields["compression"], 1 - amount ** 2, atol=1e-4)


def test_rigid_rotation_changes_no_amplitude_or_wavelength(gl_context, tmp_path):
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([0.75, 1, 1], np.float32)
    rot = rotation_matrix([1.0, 2.0, -0.5], 2.3)
    turned = (posed @ rot.T + [1.0, 5.0, -2.0]).astype(np.float32)
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    base, _ = baked(bake_sheet(tmp_path / "a", rest, posed, counts, indices, width=0.3),
                    "/Sheet", 1)
    moved, _ = baked(bake_sheet(tmp_path / "b", rest, turned, counts, indices, width=0.3),
                     "/Sheet", 1)
    wrinkled = base["amplitude"] > 1e-3
    assert wrinkled.sum() > 100
    rel = np.abs(moved["amplitude"] - base["amplitude"])[wrinkled] / base["amplitude"][wrinkled]
    assert rel.max() < 0.005
    k0 = np.linalg.norm(base["waveVector"], axis=1)[wrinkled]
    k1 = np.linalg.norm(moved["waveVector"], axis=1)[wrinkled]
    assert (np.abs(k1 - k0) / k0).max() < 0.005


@pytest.mark.parametrize("name,frames", [("lbs.usda", "1:30"), ("dqs.usda", "1:30"),
                                         ("blendshapes.usda", "1:131x10"),
                                         ("blendshapesWithNormals.usda", "1:131x10")])
def test_with_points_matches_pixar_baseline(gl_context, corpus, tmp_path, name, frames):
    """Points, and the normals of the meshes that author them (same attribute and
    interpolation, posed), as UsdSkelBakeSkinning bakes them; a mesh without authored
    normals gets none, as there."""
    folder = corpus / "openusd-usdskel"
    out = tmp_path / name.replace(".usda", ".wrinkles.usdc")
    assert main(["bake", str(folder / name), str(out), "--all-meshes", "--with-points",
                 "--frames", frames, "--quiet"]) == 0
    stage = Usd.Stage.Open(str(out))
    baseline = Usd.Stage.Open(str(folder / "baseline" / name.replace(".usda", ".baked.usda")))
    # the composed stage shows the baked points once: no baked mesh is skinned any more,
    # and what was not baked (lbs.usda's curves and implicit shapes) still is
    cache = UsdSkel.Cache()
    skinned = set()
    for prim in stage.Traverse():
        if prim.IsA(UsdSkel.Root):
            cache.Populate(UsdSkel.Root(prim), Usd.PrimDefaultPredicate)
            for binding in cache.ComputeSkelBindings(UsdSkel.Root(prim),
                                                     Usd.PrimDefaultPredicate):
                skinned |= {q.GetPrim() for q in binding.GetSkinningTargets()}
    baked_meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh) and
                    p.GetAttribute("points").GetNumTimeSamples()]
    assert baked_meshes and not any(p in skinned for p in baked_meshes)
    assert all(not p.IsA(UsdGeom.Mesh) for p in skinned)
    checked = normals_checked = 0
    for prim in baseline.Traverse():
        if not prim.IsA(UsdGeom.Mesh) or not prim.HasAPI(UsdSkel.BindingAPI):
            continue
        ours_attr = UsdGeom.Mesh(stage.GetPrimAtPath(prim.GetPath())).GetPointsAttr()
        for tc in ours_attr.GetTimeSamples():
            theirs = np.asarray(UsdGeom.Mesh(prim).GetPointsAttr().Get(tc), np.float64)
            ours = np.asarray(ours_attr.Get(tc), np.float64)
            extent = float(np.max(theirs.max(0) - theirs.min(0)))
            assert np.max(np.abs(ours - theirs)) <= 1e-4 * extent, (prim.GetPath(), tc)
            checked += 1
        ours_prim = stage.GetPrimAtPath(prim.GetPath())
        theirs_normals = prim.GetAttribute("normals")
        if not theirs_normals.HasAuthoredValue():
            assert not ours_prim.GetAttribute("normals").GetTimeSamples()
            continue
        ours_normals = ours_prim.GetAttribute("normals")
        assert ours_normals.GetMetadata("interpolation") == \
            theirs_normals.GetMetadata("interpolation")
        for tc in ours_attr.GetTimeSamples():
            a = np.asarray(ours_normals.Get(tc), np.float64)
            b = np.asarray(theirs_normals.Get(tc), np.float64)
            b /= np.linalg.norm(b, axis=1, keepdims=True)  # UsdSkel leaves them unnormalised
            cos = np.sum(a * b, axis=1)
            assert np.degrees(np.arccos(np.clip(cos.min(), -1, 1))) < 0.05, (prim.GetPath(), tc)
            normals_checked += 1
    assert checked >= 3
    if name in ("lbs.usda", "dqs.usda", "blendshapesWithNormals.usda"):
        assert normals_checked >= 3


def test_frame_alone_equals_frame_in_range(gl_context, tmp_path):
    stage = str(SAMPLES / "zeppelin.usda")
    assert main(["bake", stage, str(tmp_path / "alone.usda"), "--frames", "24", "--quiet"]) == 0
    assert main(["bake", stage, str(tmp_path / "range.usda"), "--frames", "1:24",
                 "--quiet"]) == 0
    alone, _ = baked(tmp_path / "alone.usda", "/World/Zeppelin/Hull", 24)
    within, _ = baked(tmp_path / "range.usda", "/World/Zeppelin/Hull", 24)
    for name in ("amplitude", "compression", "waveVector", "direction"):
        np.testing.assert_allclose(alone[name], within[name], atol=1e-5, err_msg=name)
    assert np.max(np.abs(wrap(alone["phase"] - within["phase"]))) < 1e-5


def test_layer_shape_sublayer_sparse_and_metadata(gl_context, tmp_path):
    stage = SAMPLES / "curtain.usda"
    full = tmp_path / "out" / "curtain.wrinkles.usda"
    sparse = tmp_path / "curtain.sparse.usdc"
    assert main(["bake", str(stage), str(full), "--frames", "20:24", "--display-color",
                 "compression", "--quiet"]) == 0
    assert main(["bake", str(stage), str(sparse), "--frames", "24", "--sparse", "--quiet"]) == 0
    layer_stage = Usd.Stage.Open(str(full))
    root = layer_stage.GetRootLayer()
    assert len(root.subLayerPaths) == 1
    assert (full.parent / root.subLayerPaths[0]).resolve() == stage.resolve()
    info = root.customLayerData["usdwrinkle"]
    assert info["frames"] == "20:24" and info["version"]
    assert (layer_stage.GetStartTimeCode(), layer_stage.GetEndTimeCode()) == (20, 24)
    # the composed stage is the shot: camera, lights and the baked primvars
    assert layer_stage.GetPrimAtPath("/World/main_cam")
    cloth = layer_stage.GetPrimAtPath("/World/Curtain/Cloth")
    colors = UsdGeom.PrimvarsAPI(cloth).GetPrimvar("displayColor")
    assert colors.GetInterpolation() == UsdGeom.Tokens.vertex
    assert len(colors.Get(24)) == 92
    # usdview's Storm resolves the preview purpose first: the ramp's material there, whose
    # surface reads displayColor; renderers of the full purpose keep the cloth's own
    binding = UsdShade.MaterialBindingAPI(cloth)
    preview, _ = binding.ComputeBoundMaterial(UsdShade.Tokens.preview)
    full_material, _ = binding.ComputeBoundMaterial(UsdShade.Tokens.full)
    assert preview.GetPath().name == "DisplayColor" and full_material.GetPath() != \
        preview.GetPath()
    source = preview.ComputeSurfaceSource()[0].GetInput("diffuseColor")
    reader = UsdShade.Shader(source.GetConnectedSources()[0][0].source.GetPrim())
    assert reader.GetInput("varname").Get() == "displayColor"
    assert main(["check", str(full)]) == 0
    sparse_stage = Usd.Stage.Open(str(sparse))
    sparse_layer = sparse_stage.GetRootLayer()
    assert len(sparse_layer.subLayerPaths) == 0
    assert sparse_layer.GetPrimAtPath("/World/Curtain/Cloth").specifier == Sdf.SpecifierOver


def test_bake_refuses_to_overwrite_inputs_and_leaves_nothing_on_error(gl_context, tmp_path,
                                                                     capsys):
    source = tmp_path / "shot.usda"
    source.write_text((SAMPLES / "curtain.usda").read_text())
    before = source.read_text()
    assert main(["bake", str(source), str(source), "--quiet"]) == 2
    assert "is an input of the stage" in capsys.readouterr().err
    assert source.read_text() == before
    # a bad frame spec fails before anything is written
    assert main(["bake", str(source), str(tmp_path / "x.usda"), "--frames", "a:b",
                 "--quiet"]) == 2
    assert sorted(p.name for p in tmp_path.iterdir()) == ["shot.usda"]


def test_the_layer_names_its_source_relative_to_itself(tmp_path, monkeypatch):
    """Issue 27: customLayerData.source was relative to the working directory of the
    bake; it is relative to the layer, as its sublayer path is, wherever the bake ran."""
    from pxr import Sdf

    (tmp_path / "shots").mkdir()
    (tmp_path / "elsewhere" / "deeper").mkdir(parents=True)
    monkeypatch.chdir(tmp_path / "elsewhere" / "deeper")
    rest, counts, indices = grid_sheet(5, 5, 1.0)
    stage = point_cache_stage(rest, {1: rest * [0.8, 1, 1]}, counts, indices)
    stage.GetRootLayer().Export(str(tmp_path / "shots" / "sheet.usda"))
    out = tmp_path / "bakes" / "sheet_wrinkles.usda"
    out.parent.mkdir()
    assert main(["bake", "../../shots/sheet.usda", str(out), "--quiet", "--all-meshes"]) == 0
    layer = Sdf.Layer.FindOrOpen(str(out))
    assert layer.customLayerData["usdwrinkle"]["source"] == "../shots/sheet.usda"
    assert list(layer.subLayerPaths) == ["../shots/sheet.usda"]


def test_with_points_bakes_indexed_primvar_normals_flattened(gl_context, tmp_path):
    """A mesh whose primvars:normals are indexed gets its posed normals flattened in the
    same primvar and interpolation, with the indices blocked; the bake takes both facts
    from the scene's reading of the mesh (NormalPlan), not from the stage per frame."""
    rest, counts, indices = grid_sheet(5, 5, 1.0)
    posed = rest * np.array([0.8, 1, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed, 2: posed}, counts, indices, width=0.3)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/Sheet"))
    mesh.CreateSubdivisionSchemeAttr(UsdGeom.Tokens.none)  # a subdivision surface's are not
    primvar = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "normals", Sdf.ValueTypeNames.Normal3fArray, UsdGeom.Tokens.faceVarying)
    primvar.Set(Vt.Vec3fArray([Gf.Vec3f(0, 0, 1)]))
    primvar.SetIndices(Vt.IntArray([0] * len(indices)))
    source, out = tmp_path / "sheet.usda", tmp_path / "sheet_wrinkles.usda"
    stage.GetRootLayer().Export(str(source))
    assert main(["bake", str(source), str(out), "--with-points", "--frames", "1:2",
                 "--quiet"]) == 0
    layer = Sdf.Layer.FindOrOpen(str(out))
    layer_prim = layer.GetPrimAtPath("/Sheet")
    spec = layer_prim.properties["primvars:normals"]
    assert spec.GetInfo("interpolation") == UsdGeom.Tokens.faceVarying
    assert isinstance(layer_prim.properties["primvars:normals:indices"].default, Sdf.ValueBlock)
    baked_stage = Usd.Stage.Open(str(out))
    composed = UsdGeom.PrimvarsAPI(baked_stage.GetPrimAtPath("/Sheet"))
    normals = np.asarray(composed.GetPrimvar("normals").Get(2.0), np.float64)
    assert normals.shape == (len(indices), 3)
    np.testing.assert_allclose(normals, np.tile([0.0, 0.0, 1.0], (len(indices), 1)), atol=1e-6)
