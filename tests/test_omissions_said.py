"""What a render leaves out is said, in one line (issue 42, trust round 4)."""
from __future__ import annotations

import pytest
from pxr import Usd, UsdGeom

from usdwrinkle.cli.main import main


def test_gprims_that_are_not_meshes_are_named(tmp_path, capsys):
    """Finding 8: a Sphere and BasisCurves vanished without a word, and a stage with no
    Mesh told the user to pass the --all-meshes they had passed."""
    path = tmp_path / "props.usda"
    stage = Usd.Stage.CreateNew(str(path))
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(2)
    UsdGeom.Sphere.Define(stage, "/World/Ball")
    UsdGeom.Cube.Define(stage, "/World/Box")
    curves = UsdGeom.BasisCurves.Define(stage, "/World/Hair")
    curves.CreateCurveVertexCountsAttr([2])
    curves.CreatePointsAttr([(0, 0, 0), (0, 1, 0)])
    guide = UsdGeom.Cube.Define(stage, "/World/Guide")
    guide.CreatePurposeAttr(UsdGeom.Tokens.guide)  # not drawn by renders anyway: not named
    stage.Save()
    assert main(["render", str(path), str(tmp_path / "x.png"), "--frames", "1", "--width",
                 "32", "--all-meshes"]) == 0
    err = capsys.readouterr().err
    assert ("3 gprim(s) are not drawn: usdwrinkle draws Mesh prims only (/World/Ball "
            "(Sphere), /World/Box (Cube), /World/Hair (BasisCurves))") in err
    assert "Guide" not in err
    assert "the stage has no Mesh to wrinkle" in err and "use --all-meshes" not in err


def test_held_from_a_primvar_authored_as_time_samples(tmp_path):
    """Finding 18: --held-from-primvar on a primvar whose only value is a time sample of
    0.5 was refused as 'must be in [0, 1]' (its default time read nothing)."""
    import numpy as np
    from pxr import Sdf

    from usdwrinkle.authoring import WrinkleAPI
    from usdwrinkle.authoring.builders import grid_sheet, point_cache_stage

    points, counts, indices = grid_sheet(3, 3)
    stage = point_cache_stage(points, {1.0: points}, counts, indices, width=0.2)
    primvar = UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/Sheet")).CreatePrimvar(
        "pin", Sdf.ValueTypeNames.FloatArray, UsdGeom.Tokens.constant)
    primvar.Set([0.5], 1.0)
    path = tmp_path / "sheet.usda"
    stage.GetRootLayer().Export(str(path))
    assert main(["apply", str(path), "/Sheet", "--held-from-primvar", "pin"]) == 0
    applied = Usd.Stage.Open(str(path))
    held = WrinkleAPI(applied.GetPrimAtPath("/Sheet")).GetHeldPrimvar()
    np.testing.assert_allclose(np.asarray(held.ComputeFlattened()), 0.5)


def test_a_cloth_preset_under_an_authored_width_is_said(tmp_path, capsys):
    """Finding 19: apply --cloth denim on a mesh that authors its width changed nothing,
    silently (the authored width wins)."""
    from pathlib import Path

    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    out = tmp_path / "over.usda"
    assert main(["apply", str(shirt), "/World/Arm/Sleeve", "-o", str(out), "--cloth",
                 "denim"]) == 0
    err = capsys.readouterr().err
    assert "--cloth denim sets no width on /World/Arm/Sleeve" in err


def test_skip_existing_renders_damaged_frames_again(tmp_path):
    """Finding 6: --skip-existing kept an EXR without its AOV channels and PNG data named
    .exr as if they were frames."""
    import os
    import shutil
    from pathlib import Path

    import OpenImageIO as oiio

    from usdwrinkle.images.imagefiles import is_complete_image

    shirt = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")
    args = ["--width", "32", "--height", "20", "--samples", "1", "--quiet"]
    pattern = str(tmp_path / "f.####.exr")
    assert main(["render", shirt, pattern, "--frames", "1:3", *args]) == 0
    assert main(["render", shirt, str(tmp_path / "p.png"), "--frames", "1", *args]) == 0
    oiio.ImageBuf(oiio.ImageSpec(32, 20, 4, oiio.HALF)).write(str(tmp_path / "f.0001.exr"))
    shutil.copy(tmp_path / "p.png", tmp_path / "f.0002.exr")
    kept = os.stat(tmp_path / "f.0003.exr").st_mtime_ns
    assert not is_complete_image(str(tmp_path / "f.0001.exr"), 32, 20)
    assert not is_complete_image(str(tmp_path / "f.0002.exr"), 32, 20)
    assert main(["render", shirt, pattern, "--frames", "1:3", "--skip-existing", *args]) == 0
    for frame in (1, 2, 3):
        assert is_complete_image(str(tmp_path / f"f.{frame:04d}.exr"), 32, 20), frame
    assert os.stat(tmp_path / "f.0003.exr").st_mtime_ns == kept


def _two_sheets(tmp_path, first: str, second: str) -> str:
    """Two still sheets with WrinkleAPI and painted q at ``first`` and ``second``."""
    import numpy as np
    from pxr import Sdf, Vt

    from usdwrinkle.authoring.builders import grid_sheet, point_cache_stage

    points, counts, indices = grid_sheet(5, 5)
    q = np.tile([0.6, 0.0, 0.0], (len(points), 1))
    stage = point_cache_stage(points, {1.0: points}, counts, indices, q=q, width=0.5,
                              path=first)
    other = point_cache_stage(points + [0, 0, 0.5], {1.0: points + [0, 0, 0.5]}, counts,
                              indices, q=q, width=0.5, path=second)
    UsdGeom.Xform.Define(stage, Sdf.Path(second).GetParentPath())
    Sdf.CopySpec(other.GetRootLayer(), second, stage.GetRootLayer(), second)
    for path in (first, second):
        UsdGeom.Mesh(stage.GetPrimAtPath(path)).CreateExtentAttr(
            Vt.Vec3fArray([(-1, -1, 0), (1, 1, 0.5)]))
    path = tmp_path / "two.usda"
    stage.GetRootLayer().Export(str(path))
    return str(path)


@pytest.mark.parametrize("first,second,extra", [
    # a mesh's preview set is another's full set
    ("/World/Cloth", "/World/Cloth_preview", []),
    ("/World/A_B/C", "/World/Z/A/B/C", []),                      # joined names
    ("/World/Ärmel", "/World/Örmel", []),                        # file-safe characters
    # the display-colour ramp's material
    ("/World/DisplayColor", "/World/Other", ["--display-color", "amplitude"]),
])
def test_every_mesh_binds_its_own_maps(gl_context, tmp_path, first, second, extra):
    """Finding 3: meshes whose names met after joining, sanitising or a set's suffix
    were bound to each other's maps, or failed with a misleading 'cannot write'."""
    from pxr import UsdShade

    stage_path = _two_sheets(tmp_path, first, second)
    layer = tmp_path / "baked.usda"
    assert main(["bake", stage_path, str(layer), "--quiet", "--maps", "normal", "--map-size",
                 "32", *extra]) == 0
    baked = Usd.Stage.Open(str(layer))
    seen = {}
    for mesh in (first, second):
        for purpose in (UsdShade.Tokens.full, UsdShade.Tokens.preview):
            material, _ = UsdShade.MaterialBindingAPI(baked.GetPrimAtPath(mesh)) \
                .ComputeBoundMaterial(purpose)
            seen[(mesh, purpose)] = str(material.GetPath())
    bound = list(seen.values())
    # each mesh its own maps material for final renderers, never the ramp's (which the
    # preview purpose shares by design)
    full = [seen[(mesh, UsdShade.Tokens.full)] for mesh in (first, second)]
    assert len(set(full)) == 2 and not any(p.endswith("WrinkleMaterials/DisplayColor")
                                           for p in full), seen
    maps = [path for path in bound if not path.endswith("WrinkleMaterials/DisplayColor")]
    assert len(set(maps)) == len(maps) and "" not in bound, seen
    files = [p.name for p in (tmp_path / "baked_maps").iterdir()]
    assert len(files) == (2 if extra else 4), files


def test_a_bake_of_a_bake_makes_no_reference_cycle(gl_context, tmp_path):
    """Finding 3: baking maps from a maps bake wrote WrinkleMaterials/Cloth referencing
    itself."""
    stage_path = _two_sheets(tmp_path, "/World/Cloth", "/World/Other")
    first, second = tmp_path / "first.usda", tmp_path / "second.usda"
    assert main(["bake", stage_path, str(first), "--quiet", "--maps", "normal",
                 "--map-size", "32", "--tangent-space", "triangle"]) == 0
    assert main(["bake", str(first), str(second), "--quiet", "--maps", "normal",
                 "--map-size", "32", "--tangent-space", "triangle",
                 "--map-dir", str(tmp_path / "second_maps")]) == 0
    layer = Sdf_layer(second)
    for prim in layer.rootPrims:
        for spec in _walk(prim):
            for ref in spec.referenceList.GetAddedOrExplicitItems():
                assert ref.primPath != spec.path, spec.path


def Sdf_layer(path):  # noqa: N802
    from pxr import Sdf

    return Sdf.Layer.FindOrOpen(str(path))


def _walk(spec):
    yield spec
    for child in spec.nameChildren:
        yield from _walk(child)


def _held_shot(tmp_path):
    """The curtain under a root layer with metersPerUnit 1 and no authored W (its cloth
    preset's width goes through the units), opened as usdview holds it."""
    from pathlib import Path

    curtain = Path(__file__).resolve().parents[1] / "sample_stages" / "curtain.usda"
    path = tmp_path / "shot.usda"
    stage = Usd.Stage.CreateNew(str(path))
    stage.GetRootLayer().subLayerPaths.append(str(curtain))
    stage.GetRootLayer().pseudoRoot.SetInfo("metersPerUnit", 1.0)
    stage.GetRootLayer().pseudoRoot.SetInfo("upAxis", "Y")
    stage.SetStartTimeCode(1)
    stage.SetEndTimeCode(24)
    cloth = next(p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh))
    cloth.GetAttribute("primvars:wrinkle:width").Block()
    stage.Save()
    return Usd.Stage.Open(str(path)), str(cloth.GetPath())


def _stand_in(stage, frame):
    from types import SimpleNamespace

    status: list[str] = []
    return SimpleNamespace(stage=stage, frame=Usd.TimeCode(frame), selectedPrims=[],
                           cameraPrim=None, PrintStatus=status.append), status


def test_usdview_out_of_process_keeps_units_and_unsaved_edits(gl_context, tmp_path,
                                                              monkeypatch):
    """Finding 4: the out-of-process bake dropped metersPerUnit (amplitudes 100x) and
    baked the file on disk, not usdview's unsaved edits."""
    import sys

    import numpy as np

    from usdwrinkle import usdview

    inside, path = _held_shot(tmp_path)
    inside.GetPrimAtPath(path).GetAttribute("wrinkle:amplitudeScale").Set(2.0)  # unsaved
    assert inside.GetRootLayer().dirty
    api, _ = _stand_in(inside, 12)
    assert usdview.bake_current_frame(api, ctx=gl_context) == [path]
    expected = np.asarray(UsdGeom.PrimvarsAPI(inside.GetPrimAtPath(path))
                          .GetPrimvar("wrinkle:amplitude").Get(12))
    (tmp_path / "again").mkdir()
    outside, _ = _held_shot(tmp_path / "again")
    outside.GetPrimAtPath(path).GetAttribute("wrinkle:amplitudeScale").Set(2.0)
    monkeypatch.setattr(usdview, "_in_process", lambda: False)
    monkeypatch.setenv("USDWRINKLE_PYTHON", sys.executable)
    api, status = _stand_in(outside, 12)
    assert usdview.bake_current_frame(api) == [path], status
    got = np.asarray(UsdGeom.PrimvarsAPI(outside.GetPrimAtPath(path))
                     .GetPrimvar("wrinkle:amplitude").Get(12))
    assert expected.max() > 0
    np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-7)


def test_usdview_out_of_process_says_when_nothing_was_written(tmp_path, monkeypatch):
    """Finding 4: with a USDWRINKLE_PYTHON that writes nothing, Render reported success
    and opened a missing PNG, Bake raised AttributeError, and a folder was left behind."""
    import tempfile

    from usdwrinkle import usdview

    scratch = tmp_path / "tmp"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    monkeypatch.setattr(usdview, "_in_process", lambda: False)
    monkeypatch.setenv("USDWRINKLE_PYTHON", "/bin/true")
    stage, _ = _held_shot(tmp_path)
    api, status = _stand_in(stage, 12)
    assert usdview.bake_current_frame(api) == []
    assert "wrote no layer" in status[-1]
    opened = []
    assert usdview.render_current_frame(api, outdir=str(tmp_path), opener=opened.append) == []
    assert "wrote no frame" in status[-1] and opened == []
    assert not list(scratch.iterdir())  # nothing left in TMPDIR


def test_a_map_size_no_gl_target_holds_is_refused(tmp_path, capsys):
    """Finding 12: bake --maps --map-size 11600 passed both checks and exited 3 on an
    incomplete framebuffer (llvmpipe refuses targets of 2 GiB and more)."""
    from pathlib import Path

    shirt = str(Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda")
    assert main(["bake", shirt, str(tmp_path / "b.usda"), "--maps", "normal", "--map-size",
                 "11600", "--frames", "1"]) == 2
    assert "--map-size 11600 needs render targets of 2.01 GiB each; at most 11585" in \
        capsys.readouterr().err
    assert not list(tmp_path.iterdir())


def _shirt_copy(tmp_path, edit=None):
    """The sample shirt copied (with its texture) into tmp_path, its text edited."""
    import shutil
    from pathlib import Path

    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    shutil.copytree(shirt.parent / "textures", tmp_path / "textures")
    text = shirt.read_text()
    if edit is not None:
        edited = edit(text)
        assert edited != text
        text = edited
    copy = tmp_path / "shirt.usda"
    copy.write_text(text)
    return copy


def test_wrinkle_api_listed_twice_is_named(tmp_path, capfd):
    """Finding 17: WrinkleAPI prepended twice made USD drop the whole apiSchemas list, and
    the render said only 'no mesh has WrinkleAPI applied'."""
    stage = _shirt_copy(tmp_path, lambda text: text.replace(
        '"SkelBindingAPI", "WrinkleAPI"]', '"SkelBindingAPI", "WrinkleAPI", "WrinkleAPI"]'))
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--frames", "3",
                 "--width", "64"]) == 0
    err = capfd.readouterr().err
    assert ("usdwrinkle: warning: /World/Arm/Sleeve authors wrinkle controls but WrinkleAPI "
            "is not applied: USD discards an apiSchemas list that names an item twice") in err
    assert "no mesh has WrinkleAPI applied" not in err
    # no raw USD line (the binding without MaterialBindingAPI is one usdwrinkle warning)
    assert not [line for line in err.splitlines() if not line.startswith("usdwrinkle: ")]
    assert main(["check", str(stage), "--wrinkles-only"]) == 1
    out = capfd.readouterr().out
    assert "error: /World/Arm/Sleeve.apiSchemas: authors wrinkle controls but WrinkleAPI " \
           "is not applied" in out
    assert main(["bake", str(stage), str(tmp_path / "bake.usda"), "--frames", "3"]) == 2
    err = capfd.readouterr().err
    last = err.splitlines()[-1]
    assert last.startswith("usdwrinkle: error: ") and "authors wrinkle controls" in last
    assert not [line for line in err.splitlines() if not line.startswith("usdwrinkle: ")]
    assert not (tmp_path / "bake.usda").exists()


def test_usd_warnings_about_cameras_are_one_line(tmp_path, capfd):
    """Finding 14: an unknown camera projection and an ill-formed --camera path printed
    USD's raw 'Warning: in ... at line ... of camera.cpp' lines."""
    stage = _shirt_copy(tmp_path, lambda text: text.replace(
        'def Camera "main_cam"\n    {', 'def Camera "main_cam"\n    {\n'
        '        token projection = "fisheye"', 1))
    assert main(["render", str(stage), str(tmp_path / "f.####.png"), "--frames", "3:4",
                 "--width", "64"]) == 0
    err = capfd.readouterr().err
    assert err.count("projection is 'fisheye'") == 1, err
    assert not [line for line in err.splitlines() if not line.startswith("usdwrinkle: ")]
    assert main(["render", str(stage), str(tmp_path / "g.####.png"), "--frames", "3",
                 "--camera", "/World/ bad//x"]) == 2
    err = capfd.readouterr().err
    assert err.startswith("usdwrinkle: error: camera '/World/ bad//x' is not a prim path")
    assert err.count("\n") == 1


def test_indices_outside_a_wrinkle_primvar_are_refused(tmp_path, capfd):
    """Finding 7: out-of-range indices on primvars:wrinkle:held: check was clean, render
    ignored the weights, and USD's raw warnings printed."""
    from pxr import Sdf, Vt

    stage_path = _shirt_copy(tmp_path)
    stage = Usd.Stage.Open(str(stage_path))
    mesh = stage.GetPrimAtPath("/World/Arm/Sleeve")
    count = len(mesh.GetAttribute("points").Get())
    held = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("wrinkle:held", Sdf.ValueTypeNames.FloatArray,
                                                   UsdGeom.Tokens.vertex)
    held.Set(Vt.FloatArray([1.0, 0.5]))
    held.SetIndices(Vt.IntArray([0, 7] * (count // 2) + [0] * (count % 2)))
    stage.Save()
    assert main(["check", str(stage_path), "--wrinkles-only"]) == 1
    out = capfd.readouterr().out
    assert ("error: /World/Arm/Sleeve.primvars:wrinkle:held: primvars:wrinkle:held has "
            f"{count // 2} index(es) outside its 2 value(s) (index 7 at position 1)") in out
    assert main(["render", str(stage_path), str(tmp_path / "f.####.png"), "--frames",
                 "3"]) == 2
    err = capfd.readouterr().err
    assert err.startswith("usdwrinkle: error: primvars:wrinkle:held has") and \
        err.count("\n") == 1, err
    assert not list(tmp_path.glob("f.*.png"))


def test_a_texture_value_out_of_range_is_named(tmp_path, capfd):
    """Finding 15: a NaN or huge UsdUVTexture scale/bias, or a NaN in an EXR texture,
    failed the frame with 'N non-finite values ... a camera, light, transform or wrinkle
    value', naming neither the texture nor the attribute."""
    import numpy as np
    import OpenImageIO as oiio
    from pxr import Gf, Sdf

    stage_path = _shirt_copy(tmp_path)
    stage = Usd.Stage.Open(str(stage_path))
    texture = stage.GetPrimAtPath("/World/Looks/Plaid/diffuse_texture")
    scale = texture.CreateAttribute("inputs:scale", Sdf.ValueTypeNames.Float4)
    scale.Set(Gf.Vec4f(float("nan"), 1, 1, 1))
    stage.Save()
    assert main(["render", str(stage_path), str(tmp_path / "f.####.png"), "--frames",
                 "3"]) == 2
    err = capfd.readouterr().err
    assert err.startswith("usdwrinkle: error: UsdUVTexture inputs:scale (nan, 1.0, 1.0, 1.0) "
                          "must be finite and within +-1e15 (/World/Looks/Plaid/"
                          "diffuse_texture.inputs:scale)"), err
    scale.Set(Gf.Vec4f(1, 1, 1, 1))
    texture.CreateAttribute("inputs:bias", Sdf.ValueTypeNames.Float4).Set(
        Gf.Vec4f(0, 3e38, 0, 0))
    stage.Save()
    assert main(["render", str(stage_path), str(tmp_path / "f.####.png"), "--frames",
                 "3"]) == 2
    assert "inputs:bias (0.0, 3" in capfd.readouterr().err
    texture.GetAttribute("inputs:bias").Clear()
    pixels = np.full((8, 8, 3), 0.5, np.float32)
    pixels[2, 3, 1] = np.nan
    pixels[5, 5, 0] = np.inf
    exr = tmp_path / "textures" / "bad.exr"
    out = oiio.ImageOutput.create(str(exr))
    assert out.open(str(exr), oiio.ImageSpec(8, 8, 3, "float"))
    assert out.write_image(pixels) and out.close()
    texture.GetAttribute("inputs:file").Set(Sdf.AssetPath("textures/bad.exr"))
    stage.Save()
    assert main(["render", str(stage_path), str(tmp_path / "f.####.png"), "--frames",
                 "3"]) == 0
    err = capfd.readouterr().err
    assert "bad.exr' has 2 pixel value(s) that are NaN, Inf or beyond +-1e15; rendering " \
           "untextured (/World/Arm/Sleeve)" in err, err


def test_a_mistyped_uv_set_is_refused(tmp_path, capsys):
    """Finding 19: bake --maps --uv uv2 (a typo) warned and fell back to islands, where
    --map-layout asset refused the same name."""
    from pathlib import Path

    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    out = tmp_path / "out" / "b.usda"
    assert main(["bake", str(shirt), str(out), "--maps", "normal", "--uv", "uv2",
                 "--frames", "1:2"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == ("usdwrinkle: error: --uv uv2: no wrinkled mesh has texture coordinates "
                       "of that name (/World/Arm/Sleeve); name the meshes' own (st by "
                       "default), or use --map-layout islands")
    assert not out.exists() and not list(tmp_path.rglob("*.png"))
    # the mesh's own name still bakes in it (no islands)
    assert main(["bake", str(shirt), str(out), "--maps", "normal", "--uv", "st",
                 "--frames", "1:2"]) == 0
    assert "islands" not in capsys.readouterr().err


def test_a_stronger_ancestor_binding_is_said(tmp_path, capsys):
    """Finding 3: a parent binding with bindMaterialAs = strongerThanDescendants won over
    the maps' material the bake binds on the mesh, with no warning. UsdShade is the
    oracle: the baked mesh resolves the ancestor's material."""
    from pxr import UsdShade

    stage_path = _shirt_copy(tmp_path)
    stage = Usd.Stage.Open(str(stage_path))
    world = stage.GetPrimAtPath("/World")
    UsdShade.MaterialBindingAPI.Apply(world).Bind(
        UsdShade.Material(stage.GetPrimAtPath("/World/Looks/Plaid")),
        UsdShade.Tokens.strongerThanDescendants)
    stage.Save()
    out = tmp_path / "b.usda"
    assert main(["bake", str(stage_path), str(out), "--maps", "normal", "--frames",
                 "1:2"]) == 0
    err = capsys.readouterr().err
    assert ("the wrinkle maps' material bound to /World/Arm/Sleeve never resolves: /World "
            "binds its material with bindMaterialAs = strongerThanDescendants") in err
    baked = Usd.Stage.Open(str(out))
    material, _ = UsdShade.MaterialBindingAPI(
        baked.GetPrimAtPath("/World/Arm/Sleeve")).ComputeBoundMaterial()
    assert material.GetPath() == "/World/Looks/Plaid"  # what the warning says
    # without the stronger binding: no warning, and the maps' material resolves
    stage = Usd.Stage.Open(str(stage_path))
    UsdShade.MaterialBindingAPI(stage.GetPrimAtPath("/World")).UnbindAllBindings()
    stage.Save()
    assert main(["bake", str(stage_path), str(tmp_path / "c.usda"), "--maps", "normal",
                 "--frames", "1:2"]) == 0
    assert "never resolves" not in capsys.readouterr().err
    baked = Usd.Stage.Open(str(tmp_path / "c.usda"))
    material, _ = UsdShade.MaterialBindingAPI(
        baked.GetPrimAtPath("/World/Arm/Sleeve")).ComputeBoundMaterial()
    assert "WrinkleMaterials" in str(material.GetPath())


def test_a_killed_runs_temporary_frame_is_swept_by_the_next_run(tmp_path):
    """Finding 6: a SIGKILLed render left '.f.0003.<random>.tmp.png' beside its frames, and
    later runs of the same frames never removed it. A temporary file now names its
    writer's pid; a run removes those of its frames whose writer is dead, and keeps
    those of a live one (another run writing the same folder now)."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    dead_pid = int(dead.stdout)
    left = tmp_path / f".f.0003.{dead_pid}.k3x_9qzz.tmp.png"
    live = tmp_path / f".f.0003.{os.getpid()}.a1b2c3d4.tmp.png"
    other = tmp_path / f".g.0003.{dead_pid}.k3x_9qzz.tmp.png"  # not a frame of this run
    for path in (left, live, other):
        path.write_bytes(b"half a frame")
    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    assert main(["render", str(shirt), str(tmp_path / "f.####.png"), "--frames", "3",
                 "--width", "32"]) == 0
    assert not left.exists()
    assert live.exists() and other.exists()
    assert (tmp_path / "f.0003.png").exists()


def test_info_puts_a_site_packages_with_pxr_last(tmp_path, monkeypatch, capsys):
    """Finding 4: for a non-editable install, info's PYTHONPATH line put the venv's whole
    site-packages first, so usd-core's pxr (no Usdviewq) shadowed the studio's USD."""
    import os

    import usdwrinkle
    from usdwrinkle.cli.info import environment_lines

    site = tmp_path / "site-packages"
    (site / "pxr").mkdir(parents=True)
    (site / "usdwrinkle").mkdir()
    monkeypatch.setattr(usdwrinkle, "__file__", str(site / "usdwrinkle" / "__init__.py"))
    monkeypatch.setenv("PYTHONPATH", "/studio/usd/lib/python")
    line = [x for x in environment_lines() if "PYTHONPATH=" in x][0]
    assert line.startswith(f"  export PYTHONPATH=/studio/usd/lib/python{os.pathsep}{site}  #")
    # an editable install's src folder has no pxr: first, as before
    src = tmp_path / "src"
    (src / "usdwrinkle").mkdir(parents=True)
    monkeypatch.setattr(usdwrinkle, "__file__", str(src / "usdwrinkle" / "__init__.py"))
    line = [x for x in environment_lines() if "PYTHONPATH=" in x][0]
    assert line == f"  export PYTHONPATH={src}{os.pathsep}/studio/usd/lib/python"


def test_a_refusal_with_stderr_closed_still_exits_2(tmp_path):
    """Finding 13: with stderr closed (2>&-), Python starts with sys.stderr None, and a
    refusal exited 1 (the write of its message raised) instead of 2."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(sys.executable).with_name("usdwrinkle")
    done = subprocess.run(f"'{script}' render '{tmp_path}/nope.usda' '{tmp_path}/x.png' 2>&-",
                          shell=True, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stdout == ""


def test_environment_and_options_no_library_takes_are_one_line(tmp_path, capsys):
    """Findings 12 and 13: USDWRINKLE_EGL_DEVICE=² (str.isdigit accepts superscripts) and
    --dask ucx://... exited 3 with an internal error; a garbage plugInfo.json on
    PXR_PLUGINPATH_NAME printed a traceback at import."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    shirt = Path(__file__).resolve().parents[1] / "sample_stages" / "shirt.usda"
    env = {**os.environ, "USDWRINKLE_EGL_DEVICE": "²"}
    done = subprocess.run([sys.executable, "-m", "usdwrinkle", "info"], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1  # the health check says the node cannot render
    assert "USDWRINKLE_EGL_DEVICE must be a device index (0, 1, ...), not '²'" in done.stdout
    assert "Traceback" not in done.stderr
    plugins = tmp_path / "plugins"
    plugins.mkdir()
    (plugins / "plugInfo.json").write_text("{ garbage")
    env = {**os.environ, "PXR_PLUGINPATH_NAME": str(plugins)}
    done = subprocess.run([sys.executable, "-m", "usdwrinkle", "info", "--no-gl"], env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stderr.startswith("usdwrinkle: warning: USD skipped a plugin (Plugin info "
                                  "file"), done.stderr
    assert done.stderr.count("\n") == 1
    assert main(["render", str(shirt), str(tmp_path / "f.####.png"), "--frames", "1:2",
                 "--dask", "ucx://host:1"]) == 2
    assert "the 'ucx' protocol is not supported" in capsys.readouterr().err
