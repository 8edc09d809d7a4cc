"""Authoring: the WrinkleAPI class, presets, and `usdwrinkle apply` with painted textures."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Sdf, Usd, UsdGeom, Vt

from usdwrinkle import WrinkleAPI, profile_from_curve, profile_preset
from usdwrinkle.cli.main import main
from usdwrinkle.process.errors import UsdWrinkleError

from conftest import grid_sheet


def write_image(path: Path, pixels: np.ndarray) -> str:
    pixels = np.ascontiguousarray(pixels, np.float32)
    spec = oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], "float")
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(pixels)
    out.close()
    return str(path)


def sheet_file(tmp_path: Path, st_swap: bool = False, face_varying: bool = False) -> Path:
    """A 2x2 sheet in XY with st = (x, y) + 0.5 (or swapped), saved to disk."""
    path = tmp_path / "sheet.usda"
    stage = Usd.Stage.CreateNew(str(path))
    points, counts, indices = grid_sheet(9, 9, 2.0)
    mesh = UsdGeom.Mesh.Define(stage, "/World/Sheet")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray.FromNumpy(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray.FromNumpy(indices))
    st = points[:, :2] / 2.0 + 0.5
    if st_swap:
        st = st[:, ::-1]
    if face_varying:
        values = st[indices]
        UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
            "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying).Set(
            Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(values)))
    else:
        UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
            "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex).Set(
            Vt.Vec2fArray.FromNumpy(np.ascontiguousarray(st)))
    stage.GetRootLayer().Save()
    return path


def cylinder_file(tmp_path: Path) -> Path:
    """A cylinder along z, st = (angle / 2pi, z), with a faceVarying seam."""
    path = tmp_path / "cylinder.usda"
    stage = Usd.Stage.CreateNew(str(path))
    around, rows = 16, 6
    theta = np.arange(around) * 2 * np.pi / around
    z = np.linspace(0, 1, rows)
    gz, gt = np.meshgrid(z, theta, indexing="ij")
    points = np.stack([np.cos(gt).ravel(), np.sin(gt).ravel(), gz.ravel()], 1).astype(np.float32)
    faces, corner_st = [], []
    for r in range(rows - 1):
        for c in range(around):
            a, b = r * around + c, r * around + (c + 1) % around
            faces.append([a, b, b + around, a + around])
            u0, u1 = c / around, (c + 1) / around  # the seam gets u = 1, not 0
            corner_st += [[u0, z[r]], [u1, z[r]], [u1, z[r + 1]], [u0, z[r + 1]]]
    mesh = UsdGeom.Mesh.Define(stage, "/Cylinder")
    mesh.CreatePointsAttr(Vt.Vec3fArray.FromNumpy(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray([4] * len(faces)))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(np.asarray(faces).ravel().tolist()))
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar(
        "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying).Set(
        Vt.Vec2fArray.FromNumpy(np.asarray(corner_st, np.float32)))
    stage.GetRootLayer().Save()
    return path


def flow_map(tmp_path, direction_uv, amount=None, size=8, name="flow.exr"):
    rgba = np.zeros((size, size, 4), np.float32)
    rgba[..., 0] = 0.5 + 0.5 * direction_uv[0]
    rgba[..., 1] = 0.5 + 0.5 * direction_uv[1]
    rgba[..., 2] = 1.0 if amount is None else amount
    rgba[..., 3] = 1.0
    return write_image(tmp_path / name, rgba)


def read_q(path, prim="/World/Sheet"):
    stage = Usd.Stage.Open(str(path))
    return WrinkleAPI.Get(stage, prim).get_q(), stage


def test_api_round_trip(tmp_path):
    path = sheet_file(tmp_path)
    stage = Usd.Stage.Open(str(path))
    prim = stage.GetPrimAtPath("/World/Sheet")
    assert WrinkleAPI.CanApply(prim)
    assert not WrinkleAPI.CanApply(stage.GetPrimAtPath("/World"))
    api = WrinkleAPI.Apply(prim)
    q = np.zeros((81, 3), np.float32)
    q[:, 0] = np.linspace(0, 0.9, 81)
    api.set_q(q)
    api.CreateWidthPrimvar(np.full(81, 0.25, np.float32))
    api.CreateAmplitudeScaleAttr(0.6)
    api.set_profile(profile_preset("sharp"))
    api.CreateRelaxIterationsAttr(5)
    stage.Save()
    again = Usd.Stage.Open(str(path))
    back = WrinkleAPI.Get(again, "/World/Sheet")
    assert back and "WrinkleAPI" in back.GetPrim().GetAppliedSchemas()
    np.testing.assert_allclose(back.get_q(), q)
    assert back.GetQPrimvar().GetInterpolation() == "vertex"
    width = back.GetWidthPrimvar()
    assert width.GetInterpolation() == "vertex"
    np.testing.assert_allclose(width.Get(), 0.25)
    assert back.GetAmplitudeScaleAttr().Get() == pytest.approx(0.6)
    np.testing.assert_allclose(back.GetHeightProfileAttr().Get(), profile_preset("sharp"))
    assert len(back.GetGradientProfileAttr().Get()) == 256
    assert back.GetRelaxIterationsAttr().Get() == 5
    assert set(WrinkleAPI.GetSchemaAttributeNames()) >= {
        "primvars:wrinkle:q", "primvars:wrinkle:width", "wrinkle:amplitudeScale"}


def test_api_refuses_bad_values_before_writing(tmp_path):
    stage = Usd.Stage.Open(str(sheet_file(tmp_path)))
    api = WrinkleAPI.Apply(stage.GetPrimAtPath("/World/Sheet"))
    with pytest.raises(UsdWrinkleError, match="values for 81 points"):
        api.set_q(np.zeros((5, 3)))
    with pytest.raises(UsdWrinkleError, match=r"\|q\| > 1"):
        api.set_q(np.tile([0.0, 2.0, 0.0], (81, 1)))
    with pytest.raises(UsdWrinkleError, match="finite and > 0"):
        api.CreateWidthPrimvar([-1.0])
    with pytest.raises(UsdWrinkleError, match="at least 2"):
        api.CreateHeightProfileAttr([1.0])
    with pytest.raises(UsdWrinkleError, match="Mesh"):
        WrinkleAPI.Apply(stage.GetPrimAtPath("/World"))
    # the reader's bound, not only >= 0 (issue 25: the API wrote what render refused)
    from usdwrinkle.process.limits import MAX_RELAX_ITERATIONS

    for bad in (-1, MAX_RELAX_ITERATIONS + 1):
        with pytest.raises(UsdWrinkleError, match="relax iterations must be in 0.."):
            api.CreateRelaxIterationsAttr(bad)
    assert not api.GetRelaxIterationsAttr().HasAuthoredValue()
    assert not api.GetQPrimvar().HasAuthoredValue()


def test_presets_and_curves():
    for name in ("cosine", "sharp", "rounded", "box"):
        profile = profile_preset(name)
        assert profile.shape == (256,) and profile.max() == pytest.approx(1.0)
        assert profile.min() == pytest.approx(-1.0) and profile[0] == pytest.approx(1.0)
    sharp = profile_preset("sharp")
    assert (sharp > 0).mean() < 0.4  # narrow ridges, broad valleys
    assert (profile_preset("rounded") > 0).mean() > 0.6
    theta = np.linspace(0, 1, 9)[:-1]
    resampled = profile_from_curve(np.cos(2 * np.pi * theta))
    np.testing.assert_allclose(resampled, profile_preset("cosine"), atol=0.08)
    pairs = np.stack([theta * 360, np.cos(2 * np.pi * theta)], 1)
    np.testing.assert_allclose(profile_from_curve(pairs), resampled, atol=1e-6)


@pytest.mark.parametrize("swap,face_varying", [(False, False), (True, False), (False, True)])
def test_flow_map_direction_on_a_sheet(tmp_path, swap, face_varying):
    path = sheet_file(tmp_path, st_swap=swap, face_varying=face_varying)
    image = flow_map(tmp_path, (1.0, 0.0), amount=0.5)
    assert main(["apply", str(path), "/World/Sheet", "--q-from-texture", image,
                 "--amount-channel", "B"]) == 0
    q, _ = read_q(path)
    expected = np.array([0.0, 1.0, 0.0]) if swap else np.array([1.0, 0.0, 0.0])  # dP/du
    np.testing.assert_allclose(q, np.tile(expected * 0.5, (81, 1)), atol=2e-3)


def test_flow_map_direction_on_a_cylinder(tmp_path):
    path = cylinder_file(tmp_path)
    for direction, check in (((1.0, 0.0), "around"), ((0.0, 1.0), "along")):
        image = flow_map(tmp_path, direction, name=f"{check}.exr")
        assert main(["apply", str(path), "/Cylinder", "--q-from-texture", image]) == 0
        q, stage = read_q(path, "/Cylinder")
        points = np.asarray(UsdGeom.Mesh(stage.GetPrimAtPath("/Cylinder")).GetPointsAttr().Get())
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-3)
        if check == "around":  # d/du of (cos 2pi u, sin 2pi u, z): the circumference
            tangent = np.stack([-points[:, 1], points[:, 0], np.zeros(len(points))], 1)
            assert np.all(np.sum(q * tangent, 1) > 0.99)
        else:
            assert np.all(q[:, 2] > 0.99)


def test_checker_amount_map(tmp_path):
    path = sheet_file(tmp_path)
    size = 64
    yy, xx = np.mgrid[0:size, 0:size]
    checker = np.where(((xx // 16) + (yy // 16)) % 2 == 0, 0.2, 0.8)
    rgba = np.ones((size, size, 4), np.float32)
    rgba[..., 0] = 1.0  # direction +u
    rgba[..., 1] = 0.5
    rgba[..., 3] = checker
    image = write_image(tmp_path / "checker.exr", rgba)
    assert main(["apply", str(path), "/World/Sheet", "--q-from-texture", image,
                 "--amount-channel", "A"]) == 0
    q, stage = read_q(path)
    st = np.asarray(UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Sheet"))
                    .GetPrimvar("st").Get())
    # the cell of each vertex (away from cell borders, where bilinear filtering blends)
    px, py = st[:, 0] * size, (1 - st[:, 1]) * size
    inside = (np.abs(px % 16 - 8) < 6) & (np.abs(py % 16 - 8) < 6)
    cell = ((np.floor(px) // 16) + (np.floor(py) // 16)) % 2
    expected = np.where(cell == 0, 0.2, 0.8)
    assert inside.sum() > 10
    np.testing.assert_allclose(np.linalg.norm(q, axis=1)[inside], expected[inside], atol=1e-3)


def test_uniform_q_width_map_profile_and_override_layer(tmp_path):
    path = sheet_file(tmp_path)
    before = path.read_text()
    grey = np.full((4, 4, 4), 0.5, np.float32)
    grey[..., 3] = 1
    image = write_image(tmp_path / "grey.exr", grey)
    override = tmp_path / "wrinkles.usda"
    assert main(["apply", str(path), "/World/**/Sh*", "-o", str(override), "--q", "1,1,5:0.3",
                 "--width", "0.4", "--width-from-texture", image, "--profile", "box",
                 "--amplitude-scale", "0.5"]) == 0
    assert path.read_text() == before  # -o leaves the stage alone
    layer = Sdf.Layer.FindOrOpen(str(override))
    assert len(layer.subLayerPaths) == 0
    assert layer.GetPrimAtPath("/World/Sheet").specifier == Sdf.SpecifierOver
    stage = Usd.Stage.Open(str(path))
    stage.GetRootLayer().subLayerPaths.append(str(override))
    api = WrinkleAPI.Get(stage, "/World/Sheet")
    q = api.get_q()
    np.testing.assert_allclose(q, np.tile([0.3 / np.sqrt(2), 0.3 / np.sqrt(2), 0], (81, 1)),
                               atol=1e-5)  # projected onto the sheet's plane
    np.testing.assert_allclose(api.GetWidthPrimvar().Get(), 0.2, atol=1e-5)
    assert api.GetWidthPrimvar().GetInterpolation() == "vertex"
    np.testing.assert_allclose(api.GetHeightProfileAttr().Get(), profile_preset("box"))


def test_q_from_colour_primvar(tmp_path):
    path = sheet_file(tmp_path)
    stage = Usd.Stage.Open(str(path))
    colours = np.tile([1.0, 0.5, 0.5], (81, 1)).astype(np.float32)  # +x as a colour
    UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/World/Sheet")).CreatePrimvar(
        "paint", Sdf.ValueTypeNames.Color3fArray, UsdGeom.Tokens.vertex).Set(
        Vt.Vec3fArray.FromNumpy(colours))
    stage.Save()
    assert main(["apply", str(path), "/World/Sheet", "--q-from-primvar", "paint"]) == 0
    q, _ = read_q(path)
    np.testing.assert_allclose(q, np.tile([1.0, 0.0, 0.0], (81, 1)), atol=1e-6)
    assert main(["apply", str(path), "/World/Sheet", "--clear-q"]) == 0
    q, _ = read_q(path)
    assert np.all(q == 0)


@pytest.mark.parametrize("args,fragment", [
    (["--width", "0"], "width must be finite and > 0"),
    (["--amplitude-scale", "-1"], "amplitude scale"),
    (["--q", "1,0,0:1.5"], "outside [0, 1]"),
    (["--q", "garbage"], "bad --q"),
    (["--profile", "wobbly"], "neither a preset"),
    (["--q-from-texture", "missing.exr"], "cannot read image"),
])
def test_bad_values_are_refused_and_nothing_is_written(tmp_path, capsys, args, fragment):
    path = sheet_file(tmp_path)
    before = path.read_text()
    assert main(["apply", str(path), "/World/Sheet", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and fragment in err[0]
    assert path.read_text() == before


def test_patterns_that_match_nothing(tmp_path, capsys):
    path = sheet_file(tmp_path)
    assert main(["apply", str(path), "/Nope/**", "--width", "1"]) == 2
    assert "no prim matches" in capsys.readouterr().err


def test_apply_updates_the_override_layer_the_shot_already_sublayers(corpus, tmp_path, capsys):
    """Issue 27: the usual assembly is a shot layer that sublayers an override layer over a
    read-only package. apply -o refused that override layer (an input of the stage) and
    advised editing the shot file; it edits the override layer where it is, keeping what
    an earlier apply wrote, and still refuses a package or a texture."""
    from pxr import Sdf

    Sdf.Layer.CreateNew(str(tmp_path / "overrides.usda")).Save()
    shot = Sdf.Layer.CreateNew(str(tmp_path / "shot.usda"))
    shot.subLayerPaths = ["overrides.usda", str(corpus / "usd-wg" / "CesiumMan.usdz")]
    shot.Save()
    before = (tmp_path / "shot.usda").read_text()
    mesh = "/CesiumMan/**/Cesium_Man_2"
    for extra in (["--width", "0.05"], ["--amplitude-scale", "0.7"]):
        assert main(["apply", str(tmp_path / "shot.usda"), mesh, "-o",
                     str(tmp_path / "overrides.usda"), *extra]) == 0
    stage = Usd.Stage.Open(str(tmp_path / "shot.usda"))
    prim = next(p for p in stage.Traverse() if p.GetName() == "Cesium_Man_2")
    assert "WrinkleAPI" in prim.GetAppliedSchemas()
    assert list(prim.GetAttribute("primvars:wrinkle:width").Get()) == [pytest.approx(0.05)]
    assert prim.GetAttribute("wrinkle:amplitudeScale").Get() == pytest.approx(0.7)
    assert (tmp_path / "shot.usda").read_text() == before   # the shot file is untouched
    capsys.readouterr()
    assert main(["apply", str(tmp_path / "shot.usda"), mesh, "-o",
                 str(corpus / "usd-wg" / "CesiumMan.usdz"), "--width", "0.05"]) == 2
    assert "cannot be edited in place" in capsys.readouterr().err


def test_apply_o_naming_the_stage_by_any_spelling_is_refused(tmp_path, monkeypatch, capsys):
    """Issue 54, finding 11: ``apply -o`` naming the stage as ./stage.usda, ../in/,
    '//', a symlink or a symlinked folder edited the stage in place, and a hard link was
    refused with a misleading message. ``-o`` means "leave my stage alone"."""
    import os
    import shutil

    from usdwrinkle.cli.main import main

    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    folder = tmp_path / "in"
    folder.mkdir()
    stage = folder / "stage.usda"
    shutil.copy(shirt, stage)
    shutil.copytree(shirt.parent / "textures", folder / "textures")
    (tmp_path / "link.usda").symlink_to(stage)
    (tmp_path / "linkdir").symlink_to(folder)
    os.link(stage, tmp_path / "hard.usda")
    (tmp_path / "other").mkdir()
    before = stage.read_bytes()
    monkeypatch.chdir(folder)
    for spelling in ("stage.usda", "./stage.usda", "../in/stage.usda", f"{folder}//stage.usda",
                     str(tmp_path / "link.usda"), str(tmp_path / "linkdir" / "stage.usda"),
                     str(tmp_path / "hard.usda"), "../other/../in/stage.usda"):
        assert main(["apply", str(stage), "/World/Arm/Sleeve", "-o", spelling, "--width",
                     "0.3"]) == 2, spelling
        assert "is the stage itself; leave --output out to edit the stage in place" in \
            capsys.readouterr().err, spelling
        assert stage.read_bytes() == before, spelling
