"""Saving a paint session (app/paint_session.py): Save As never replaces a file the stage reads,
by any spelling, and a saved copy names the same files from its new folder (issue 54:
findings 1, 2, 6, 11 and the paint layer's defaultPrim)."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from pxr import Ar, Sdf, Usd, UsdShade

from usdwrinkle.app.paint_session import PaintSession, open_paint_stage
from usdwrinkle.process.errors import UsdWrinkleError

from helpers import sheet_stage


def spellings(path: Path, tmp_path: Path) -> list[str]:
    """The same file by other names: as given, './', '..', '//', a symlink, a symlinked
    folder and a hard link."""
    folder = path.parent
    link = tmp_path / "link.usda"
    if not link.exists():
        link.symlink_to(path)
    linkdir = tmp_path / "linkdir"
    if not linkdir.exists():
        linkdir.symlink_to(folder)
    hard = tmp_path / "hard.usda"
    if not hard.exists():
        os.link(path, hard)
    return [str(path), os.path.relpath(path), str(folder / ".." / folder.name / path.name),
            str(folder) + "//" + path.name, str(link), str(linkdir / path.name), str(hard)]


def shot(tmp_path: Path) -> tuple[Path, Path]:
    """asset/sheet.usda (the geometry) and shot/shot.usda, which sublayers it."""
    (tmp_path / "asset").mkdir()
    (tmp_path / "shot").mkdir()
    asset = Path(sheet_stage(tmp_path / "asset" / "sheet.usda", nx=5))
    asset_layer = Sdf.Layer.FindOrOpen(str(asset))
    asset_layer.defaultPrim = "Sheet"
    asset_layer.Save()
    layer = Sdf.Layer.CreateNew(str(tmp_path / "shot" / "shot.usda"))
    layer.subLayerPaths.append("../asset/sheet.usda")
    layer.defaultPrim = "Sheet"
    layer.startTimeCode, layer.endTimeCode = 1, 2
    layer.Save()
    return asset, Path(layer.realPath)


@pytest.fixture
def painted(gl_context, tmp_path):
    """A session painting shot.usda into a new layer, one flood done."""
    asset, shot_path = shot(tmp_path)
    stage, layer, save = open_paint_stage(str(shot_path), str(tmp_path / "shot" / "p.usda"))
    session = PaintSession(stage, layer, save, ctx=gl_context)
    session.flood()
    yield session, asset, shot_path
    session.release()


def test_save_as_never_replaces_the_stage_or_its_sublayers(painted, tmp_path, monkeypatch):
    """Findings 1 and 2: Save As over the stage replaced it with the paint layer (which
    then sublayered itself), and over a sublayer replaced the asset."""
    session, asset, shot_path = painted
    monkeypatch.chdir(tmp_path)
    before = {p: p.read_bytes() for p in (asset, shot_path)}
    for target in (*spellings(shot_path, tmp_path / "a"), *spellings(asset, tmp_path / "b")):
        with pytest.raises(UsdWrinkleError, match="is a file the stage reads"):
            session.save(target)
    assert {p: p.read_bytes() for p in before} == before
    assert session.dirty  # nothing was saved
    assert session.save() == str(tmp_path / "shot" / "p.usda")
    assert not session.dirty


@pytest.fixture(autouse=True)
def _spelling_folders(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()


def test_paint_o_naming_the_stage_or_an_input_is_refused(tmp_path, monkeypatch):
    """Finding 11 for paint: ``-o`` means "leave my stage alone"."""
    asset, shot_path = shot(tmp_path)
    monkeypatch.chdir(tmp_path)
    for target in (*spellings(shot_path, tmp_path / "a"), *spellings(asset, tmp_path / "b")):
        with pytest.raises(UsdWrinkleError, match="is a file the stage reads"):
            open_paint_stage(str(shot_path), target)


def test_paint_o_in_a_missing_or_read_only_folder_is_refused(tmp_path):
    """Finding 16: refused before the window, not on the first save."""
    _, shot_path = shot(tmp_path)
    with pytest.raises(UsdWrinkleError, match="does not exist"):
        open_paint_stage(str(shot_path), str(tmp_path / "nope" / "p.usda"))
    # /sys refuses new files even to root (a read-only folder that no chmod could give a
    # test running as root)
    with pytest.raises(UsdWrinkleError, match="is not writable"):
        open_paint_stage(str(shot_path), "/sys/p.usda")


def _resolves_to(layer_path: str, asset: str) -> str:
    layer = Sdf.Layer.FindOrOpen(layer_path)
    return str(Ar.GetResolver().Resolve(layer.ComputeAbsolutePath(asset)))


def test_a_reopened_paint_layer_saved_elsewhere_still_names_the_stage(painted, tmp_path,
                                                                      gl_context):
    """Finding 6: a reopened layer saved into another folder kept '../asset/...'."""
    session, asset, shot_path = painted
    first = session.save()
    stage, layer, save = open_paint_stage(str(shot_path), first)
    again = PaintSession(stage, layer, save, ctx=gl_context)
    try:
        (tmp_path / "elsewhere" / "deeper").mkdir(parents=True)
        target = str(tmp_path / "elsewhere" / "deeper" / "copy.usda")
        again.save(target)
    finally:
        again.release()
    saved = Sdf.Layer.FindOrOpen(target)
    sublayer = saved.subLayerPaths[0]
    assert not os.path.isabs(sublayer)
    assert os.path.samefile(_resolves_to(target, sublayer), shot_path)
    copy = Usd.Stage.Open(target)
    np.testing.assert_array_equal(
        np.asarray(copy.GetPrimAtPath(session.active).GetAttribute(
            "primvars:wrinkle:q").Get()), session.mesh.q)


def test_a_symlinked_folder_is_anchored_as_named(gl_context, tmp_path):
    """Finding 6: ``-o LINKDIR/p.usda`` made the sublayer relative to the real folder,
    while USD resolves it from the folder as named."""
    _, shot_path = shot(tmp_path)
    real = tmp_path / "deep" / "real"
    real.mkdir(parents=True)
    (tmp_path / "linkdir").symlink_to(real)
    target = str(tmp_path / "linkdir" / "p.usda")
    stage, layer, save = open_paint_stage(str(shot_path), target)
    session = PaintSession(stage, layer, save, ctx=gl_context)
    try:
        session.flood()
        session.save()
    finally:
        session.release()
    saved = Sdf.Layer.FindOrOpen(target)
    sublayer = saved.subLayerPaths[0]
    assert sublayer == "../shot/shot.usda"
    assert Usd.Stage.Open(target).GetPrimAtPath(session.active).IsValid()


def _textured_sheet(folder: Path) -> Path:
    """The sheet with a material whose texture is './tex/c.png'."""
    import OpenImageIO as oiio

    path = Path(sheet_stage(folder / "sheet.usda", nx=5))
    (folder / "tex").mkdir()
    buf = oiio.ImageBuf(oiio.ImageSpec(4, 4, 3, oiio.UINT8))
    oiio.ImageBufAlgo.fill(buf, (0.8, 0.2, 0.1))
    buf.write(str(folder / "tex" / "c.png"))
    stage = Usd.Stage.Open(str(path))
    material = UsdShade.Material.Define(stage, "/Looks/M")
    texture = UsdShade.Shader.Define(stage, "/Looks/M/Tex")
    texture.CreateIdAttr("UsdUVTexture")
    texture.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./tex/c.png")
    surface = UsdShade.Shader.Define(stage, "/Looks/M/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(
        texture.ConnectableAPI(), "rgb")
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    stage.Save()
    return path


def test_save_as_of_a_stage_edited_in_place_keeps_its_textures(gl_context, tmp_path):
    """Finding 6: without ``-o``, the copy lost './tex/c.png'."""
    (tmp_path / "in").mkdir()
    path = _textured_sheet(tmp_path / "in")
    stage, layer, save = open_paint_stage(str(path), None)
    session = PaintSession(stage, layer, save, ctx=gl_context)
    try:
        session.flood()
        (tmp_path / "out").mkdir()
        target = str(tmp_path / "out" / "copy.usda")
        session.save(target)
    finally:
        session.release()
    copy = Sdf.Layer.FindOrOpen(target)
    value = copy.GetAttributeAtPath("/Looks/M/Tex.inputs:file").default.path
    assert value == "../in/tex/c.png"
    assert os.path.samefile(_resolves_to(target, value), tmp_path / "in" / "tex" / "c.png")


def test_save_as_of_a_usdz_keeps_the_package_textures(gl_context, tmp_path, corpus):
    """Finding 6: CesiumMan painted from its .usdz (the README's path) and saved as a new
    layer rendered grey: the copy named its textures inside the package relatively."""
    package = tmp_path / "CesiumMan.usdz"
    shutil.copy(corpus / "usd-wg" / "CesiumMan.usdz", package)
    stage, layer, save = open_paint_stage(str(package), None)
    assert save is None
    session = PaintSession(stage, layer, save, ctx=gl_context, all_meshes=True)
    try:
        session.flood()
        with pytest.raises(UsdWrinkleError, match="no layer file to save to"):
            session.save()
        (tmp_path / "out").mkdir()
        target = str(tmp_path / "out" / "painted.usda")
        session.save(target)
    finally:
        session.release()
    found = []
    copy = Sdf.Layer.FindOrOpen(target)

    def visit(path):
        spec = copy.GetObjectAtPath(path)
        if isinstance(spec, Sdf.AttributeSpec) and spec.typeName == Sdf.ValueTypeNames.Asset \
                and spec.default is not None:
            found.append(spec.default.path)

    copy.Traverse(Sdf.Path.absoluteRootPath, visit)
    assert found and all(p.startswith("../CesiumMan.usdz[") for p in found)
    for value in found:
        resolved = _resolves_to(target, value)
        assert resolved.startswith(str(package) + "[")
        assert Ar.GetResolver().OpenAsset(Ar.ResolvedPath(resolved)) is not None


def test_a_new_paint_layer_names_the_default_prim(painted):
    """A new paint layer had no defaultPrim, so ``usdwrinkle check`` of it exited 1."""
    session, asset, _ = painted
    target = session.save()
    expected = Sdf.Layer.FindOrOpen(str(asset)).defaultPrim
    assert expected and Sdf.Layer.FindOrOpen(target).defaultPrim == expected
