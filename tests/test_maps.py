"""bake --maps: wrinkle maps against the analytic sheet, tangent space under rigid motion,
UDIM tiles, the material that binds them, and our renderer reading them back (the oracle:
the baked layer drawn with --no-wrinkles looks like the shot drawn with wrinkles)."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Gf, Sdf, Usd, UsdGeom, UsdLux, UsdShade, Vt

from usdwrinkle.cli.main import main
from usdwrinkle.method.contract import COARSENING_MAX
from usdwrinkle.scene.material import load_texture

from conftest import grid_sheet
from helpers import MAPS_SIZE as SIZE
from helpers import MAPS_WIDTH as WIDTH
from helpers import bake_maps, bind_purpose_looks, fold_law, point_cache_stage, rotation_matrix
from helpers import maps_sheet_stage as sheet_stage
from helpers import read_pixels as read

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT = str(SAMPLES / "shirt.usda")
def sheet_maps(tmp_path, ratio, rotation=None):
    source = sheet_stage(tmp_path, ratio, rotation)
    layer = tmp_path / "maps.usda"
    assert bake_maps(source, layer) == 0
    folder = tmp_path / "maps_maps"
    normal = read(folder / "Sheet.normal.0001.png") * 2.0 - 1.0
    height = read(folder / "Sheet.height.0001.exr")[..., 0]
    amplitude = read(folder / "Sheet.amplitude.0001.png")[..., 0]
    inner = slice(SIZE // 8, SIZE - SIZE // 8)  # away from the sheet's free border
    return normal[inner, inner], height[inner, inner], amplitude[inner, inner]


@pytest.mark.parametrize("ratio", [0.6, 0.85])
def test_maps_of_the_analytic_sheet(gl_context, tmp_path, ratio):
    normal, height, amplitude = sheet_maps(tmp_path, ratio)
    a, k = fold_law(ratio, WIDTH)   # the fold law (docs/method.md)
    a, k = float(a), float(k)
    tilt = np.arccos(np.clip(normal[..., 2] / np.linalg.norm(normal, axis=2), -1, 1))
    # the largest tilt, on the flanks: atan of the fold profile's steepest slope
    from usdwrinkle.method.folds import gradient_of
    from usdwrinkle.method.profiles import default_profile

    steepest = float(np.abs(gradient_of(default_profile())).max())
    np.testing.assert_allclose(tilt.max(), np.arctan(a * k * steepest), rtol=0.03)
    np.testing.assert_allclose(np.abs(height).max(), a, rtol=0.02)
    np.testing.assert_allclose(amplitude, a / (COARSENING_MAX * WIDTH / 4), rtol=0.02)
    # the wave runs along x (s): no tilt along t
    assert np.abs(normal[..., 1]).max() < 1e-3
    # the map holds the wave itself: its slope along s matches the height map's
    texel = 2.0 * ratio / SIZE  # posed length of one texel along s
    slope = np.gradient(height, texel, axis=1)
    flank = np.abs(slope) > 0.5 * np.abs(slope).max()
    np.testing.assert_allclose((-normal[..., 0] / normal[..., 2])[flank], slope[flank],
                               atol=0.05 * a * k)


def test_maps_are_in_tangent_space(gl_context, tmp_path):
    """A rigid rotation (and shift) of the posed sheet leaves every map unchanged."""
    for name in ("plain", "moved"):
        (tmp_path / name).mkdir()
    plain = sheet_maps(tmp_path / "plain", 0.7)
    moved = sheet_maps(tmp_path / "moved", 0.7, rotation_matrix([0.3, -0.5, 0.8], 1.1))
    a = float(fold_law(0.7, WIDTH)[0])
    assert np.abs(moved[0] - plain[0]).max() < 0.01        # unit normals
    assert np.abs(moved[1] - plain[1]).max() < 0.01 * a    # heights
    assert np.abs(moved[2] - plain[2]).max() < 0.01        # normalised amplitude


def file_samples(stage, material_path, name):
    attr = UsdShade.Material(stage.GetPrimAtPath(material_path)).GetInput(name).GetAttr()
    values = [attr.Get()] + [attr.Get(t) for t in attr.GetTimeSamples()]
    return attr, values


def test_udim_tiles_are_written_and_read_back(gl_context, tmp_path):
    """UVs over two tiles: one file per tile (1001, 1002) named through <UDIM>, each with
    its half of the sheet; our renderer reads the set back."""
    rest, _, _ = grid_sheet(31, 31, 2.0)
    st = np.stack([rest[:, 0] + 1.0, (rest[:, 1] + 1.0) / 2.0], 1)  # u in [0, 2]
    source = sheet_stage(tmp_path, 0.7, st=st)
    lit = Usd.Stage.Open(str(source))  # an oblique key: the camera light shows no relief
    key = UsdLux.DistantLight.Define(lit, "/Key")
    key.AddRotateXYZOp().Set(Gf.Vec3f(-30.0, 60.0, 0.0))
    lit.Save()
    layer = tmp_path / "udim.usda"
    assert bake_maps(source, layer) == 0
    folder = tmp_path / "udim_maps"
    assert sorted(os.listdir(folder)) == sorted(
        f"Sheet.{kind}.{tile}.0001.{ext}" for kind, ext in
        (("normal", "png"), ("height", "exr"), ("amplitude", "png")) for tile in (1001, 1002))
    for tile in (1001, 1002):
        amplitude = read(folder / f"Sheet.amplitude.{tile}.0001.png")[..., 0]
        inner = amplitude[SIZE // 8:-SIZE // 8, SIZE // 8:-SIZE // 8]
        np.testing.assert_allclose(inner, float(fold_law(0.7, WIDTH)[0])
                                   / (COARSENING_MAX * WIDTH / 4), rtol=0.02)
    stage = Usd.Stage.Open(str(layer))
    _, values = file_samples(stage, "/WrinkleMaterials/Sheet", "wrinkleNormalFile")
    assert all("<UDIM>" in value.path for value in values)
    wrinkled, from_maps, plain = (tmp_path / f"{n}.exr" for n in ("w", "m", "p"))
    for stage_path, out, extra in ((source, wrinkled, []), (layer, from_maps, ["--no-wrinkles"]),
                                   (source, plain, ["--no-wrinkles"])):
        assert main(["render", str(stage_path), str(out), "--frames", "1", "--width", "200",
                     "--quiet", *extra]) == 0
    w, m, p = (read(path)[..., :3] for path in (wrinkled, from_maps, plain))
    assert np.abs(m - w).mean() < 0.3 * np.abs(p - w).mean()


@pytest.fixture(scope="module")
def shirt_maps(tmp_path_factory):
    folder = tmp_path_factory.mktemp("shirt")
    layer = folder / "shirt_maps.usda"
    assert bake_maps(SHIRT, layer, "--frames", "21:24", kinds="normal,height",
                     size=512) == 0
    return layer


def test_shirt_maps_render_like_the_wrinkles(gl_context, tmp_path, shirt_maps):
    """The oracle: the baked layer drawn with --no-wrinkles (our renderer reading the
    UsdPreviewSurface normal maps) against the shot drawn with wrinkles, on the sleeve's
    pixels. What is left is the texture-coordinate parallax, which maps cannot carry, and
    the maps' filtering."""
    images = {}
    for name, stage, extra in (("wrinkled", SHIRT, []), ("maps", shirt_maps, ["--no-wrinkles"]),
                               ("plain", SHIRT, ["--no-wrinkles"])):
        out = tmp_path / f"{name}.png"
        assert main(["render", str(stage), str(out), "--frames", "24", "--width", "480",
                     "--quiet", *extra]) == 0
        images[name] = read(out)
    sleeve = images["wrinkled"][..., 3] > 0.99
    maps = np.abs(images["maps"] - images["wrinkled"])[..., :3][sleeve].mean()
    plain = np.abs(images["plain"] - images["wrinkled"])[..., :3][sleeve].mean()
    print(f"sleeve pixels: maps vs wrinkles {maps:.4f}, plain vs wrinkles {plain:.4f}")
    assert maps < 0.75 * plain


def test_shirt_layer_is_clean_and_complete(gl_context, shirt_maps, capsys):
    assert main(["check", str(shirt_maps)]) == 0
    stage = Usd.Stage.Open(str(shirt_maps))
    sleeve = stage.GetPrimAtPath("/World/Arm/Sleeve")
    material, _ = UsdShade.MaterialBindingAPI(sleeve).ComputeBoundMaterial()
    assert str(material.GetPath()) == "/World/WrinkleMaterials/Sleeve"
    surface = material.ComputeSurfaceSource()[0]
    assert surface.GetIdAttr().Get() == "UsdPreviewSurface"
    # the rest of the look is the original material's (its plaid and roughness)
    diffuse = surface.GetInput("diffuseColor").GetConnectedSources()[0][0].source
    assert "plaid.png" in UsdShade.Shader(diffuse.GetPrim()).GetInput("file").Get().path
    assert surface.GetInput("roughness").Get() == pytest.approx(0.6)
    normal = UsdShade.Shader(surface.GetInput("normal").GetConnectedSources()[0][0]
                             .source.GetPrim())
    assert normal.GetInput("sourceColorSpace").Get() == "raw"
    assert tuple(normal.GetInput("scale").Get()) == (2, 2, 2, 1)
    assert tuple(normal.GetInput("bias").Get()) == (-1, -1, -1, 0)
    assert normal.GetInput("wrapS").Get() == "repeat" == normal.GetInput("wrapT").Get()
    # the height map is named, not bound: Storm displaces the coarse corners (streaks)
    assert not surface.GetInput("displacement")
    folder = os.path.dirname(str(shirt_maps))
    for name in ("wrinkleNormalFile", "wrinkleHeightFile"):
        attr, values = file_samples(stage, material.GetPath(), name)
        assert attr.GetTimeSamples() == [21.0, 22.0, 23.0, 24.0]
        assert values[0].path == values[1].path  # the default is the first frame's file
        for value in values:
            assert not os.path.isabs(value.path)  # relative: layer and maps move together
            assert os.path.isfile(os.path.join(folder, value.path)), value.path
            assert value.resolvedPath


def test_a_mesh_without_material_gets_a_plain_preview_surface(gl_context, tmp_path):
    """No bound material: the wrinkle material is a plain UsdPreviewSurface with the mesh's
    displayColor, and the normal map on it."""
    source = sheet_stage(tmp_path, 0.7)
    stage = Usd.Stage.Open(str(source))
    UsdGeom.Gprim(stage.GetPrimAtPath("/Sheet")).CreateDisplayColorAttr([(0.2, 0.4, 0.6)])
    stage.Save()
    layer = tmp_path / "plain.usda"
    assert bake_maps(source, layer, kinds="normal") == 0
    baked = Usd.Stage.Open(str(layer))
    material, _ = UsdShade.MaterialBindingAPI(baked.GetPrimAtPath("/Sheet")) \
        .ComputeBoundMaterial()
    surface = material.ComputeSurfaceSource()[0]
    assert surface.GetIdAttr().Get() == "UsdPreviewSurface"
    assert tuple(surface.GetInput("diffuseColor").Get()) == pytest.approx((0.2, 0.4, 0.6))
    assert surface.GetInput("normal").HasConnectedSource()
    assert not surface.GetInput("displacement")  # no height map asked for


def test_mesh_without_uvs_is_named_and_maps_of_none_are_refused(gl_context, tmp_path, capsys):
    """The only wrinkled mesh has no st: the bake is refused in one line naming it (a
    maps bake without maps is not what was asked for); next to a mesh that has them, it
    is skipped with a warning naming it."""
    source = sheet_stage(tmp_path, 0.7, st=False)
    layer = tmp_path / "out.usda"
    assert main(["bake", str(source), str(layer), "--maps", "normal", "--map-size", "64",
                 "--map-layout", "asset"]) == 2
    err = capsys.readouterr().err
    assert "no wrinkled mesh has the texture coordinates 'st'" in err and "/Sheet" in err
    assert "--uv" in err and not layer.exists()
    with_uvs = sheet_stage(tmp_path, 0.7, name="with_uvs.usda")
    both = Usd.Stage.Open(str(source))
    both.DefinePrim("/WithUVs").GetReferences().AddReference(str(with_uvs), "/Sheet")
    both.Save()
    assert main(["bake", str(source), str(layer), "--maps", "normal", "--map-size", "64",
                 "--all-meshes", "--map-layout", "asset"]) == 0
    err = capsys.readouterr().err
    assert "no texture coordinates 'st'" in err and "/Sheet" in err
    baked = Usd.Stage.Open(str(layer))
    assert baked.GetPrimAtPath("/WrinkleMaterials/WithUVs")
    assert not baked.GetPrimAtPath("/WrinkleMaterials/Sheet")


def test_overlapping_uvs_warn_and_the_bake_goes_on(gl_context, tmp_path, capsys):
    rest, _, _ = grid_sheet(31, 31, 2.0)
    st = np.stack([np.abs(rest[:, 0]), (rest[:, 1] + 1) / 2], 1)  # mirrored halves
    source = sheet_stage(tmp_path, 0.7, st=st)
    layer = tmp_path / "out.usda"
    assert main(["bake", str(source), str(layer), "--maps", "normal", "--map-size", "64",
                 "--map-layout", "asset"]) == 0
    err = capsys.readouterr().err
    assert "overlap" in err and "/Sheet" in err
    assert (tmp_path / "out_maps" / "Sheet.normal.0001.png").is_file()


def test_a_failed_bake_leaves_neither_maps_nor_layer(gl_context, tmp_path, capsys):
    """A frame that fails in the middle: exit 2, one line, no map, no staging folder and
    no layer (nothing half written that names missing maps)."""
    rest, counts, indices = grid_sheet(11, 11, 2.0)
    posed = rest * np.array([0.7, 1, 1], np.float32)
    bad = posed.copy()
    bad[3] = np.nan
    stage = point_cache_stage(rest, {1: posed, 2: posed, 3: bad}, counts, indices,
                              width=WIDTH)
    UsdGeom.PrimvarsAPI(stage.GetPrimAtPath("/Sheet")).CreatePrimvar(
        "st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.vertex).Set(
        Vt.Vec2fArray.FromNumpy(((rest[:, :2] + 1) / 2).astype(np.float32)))
    source = tmp_path / "bad.usda"
    stage.GetRootLayer().Export(str(source))
    out = tmp_path / "out" / "layer.usda"
    assert main(["bake", str(source), str(out), "--quiet", "--maps", "normal",
                 "--map-size", "32", "--map-layout", "asset"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "frame 3" in err[0]
    assert not out.exists()
    leftovers = os.listdir(tmp_path / "out") if (tmp_path / "out").exists() else []
    assert leftovers == []


@pytest.mark.parametrize("args,fragment", [
    (["--maps", "normal,wrinkles"], "--maps takes"),
    (["--maps", "normal", "--map-size", "8"], "--map-size must be in"),
    (["--maps", "normal", "--map-padding", "-1"], "--map-padding must be in"),
    (["--maps", "normal", "--map-layout", "islands", "--uv", "st"],
     "--uv names the texture coordinates of --map-layout asset"),
    (["--map-dir", "x"], "--map-dir need --maps"),
])
def test_map_options_are_checked(tmp_path, capsys, args, fragment):
    source = sheet_stage(tmp_path, 0.7)
    assert main(["bake", str(source), str(tmp_path / "o.usda"), "--quiet", *args]) == 2
    assert fragment in capsys.readouterr().err


def test_source_color_space_follows_usd_preview_surface(tmp_path):
    """auto decodes 8-bit images from sRGB and keeps 16-bit ones (a normal map) as they
    are; raw never decodes; sRGB always does."""
    for bits, value in (("uint8", 128), ("uint16", 32768)):
        path = str(tmp_path / f"grey{bits}.png")
        spec = oiio.ImageSpec(4, 4, 3, bits)
        out = oiio.ImageOutput.create(path)
        out.open(path, spec)
        out.write_image(np.full((4, 4, 3), value, np.uint8 if bits == "uint8" else np.uint16))
        out.close()
        stored = value / (255.0 if bits == "uint8" else 65535.0)
        decoded = ((stored + 0.055) / 1.055) ** 2.4
        expected_auto = decoded if bits == "uint8" else stored
        for space, expected, rtol in (("auto", expected_auto, 1e-3), ("raw", stored, 1e-4),
                                      ("sRGB", decoded, 1e-3)):
            image = load_texture(path, space)
            np.testing.assert_allclose(image.linear()[..., 0], expected, rtol=rtol)
            # 8-bit files keep their codes; the sampler decodes sRGB (GL_SRGB8_ALPHA8)
            assert image.pixels.dtype == (np.uint8 if bits == "uint8" else np.float32)


def test_a_static_normal_map_tilts_the_rendered_normal(gl_context, tmp_path):
    """Any mesh's UsdPreviewSurface normal map: a constant map of the tangent-space normal
    (sin a, 0, cos a) on a flat sheet with st along (x, y) gives the world normal
    (sin a, 0, cos a) in the normal AOV (tangent = dP/ds = x, bitangent = y, n = z)."""
    angle = 0.4
    path = str(tmp_path / "tilt.png")
    encoded = 0.5 * np.array([np.sin(angle), 0.0, np.cos(angle)]) + 0.5
    spec = oiio.ImageSpec(8, 8, 3, "uint16")
    out = oiio.ImageOutput.create(path)
    out.open(path, spec)
    out.write_image(np.full((8, 8, 3), np.round(encoded * 65535), np.uint16))
    out.close()
    source = sheet_stage(tmp_path, 1.0, apply_api=False)
    stage = Usd.Stage.Open(str(source))
    material = UsdShade.Material.Define(stage, "/Looks/Tilt")
    surface = UsdShade.Shader.Define(stage, "/Looks/Tilt/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    texture = UsdShade.Shader.Define(stage, "/Looks/Tilt/Normal")
    texture.CreateIdAttr("UsdUVTexture")
    texture.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./tilt.png")
    texture.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set((2, 2, 2, 1))
    texture.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set((-1, -1, -1, 0))
    surface.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(
        texture.ConnectableAPI().CreateOutput("rgb", Sdf.ValueTypeNames.Float3))
    UsdShade.MaterialBindingAPI.Apply(stage.GetPrimAtPath("/Sheet")).Bind(material)
    stage.Save()
    out_path = tmp_path / "tilt.exr"
    assert main(["render", str(source), str(out_path), "--frames", "1", "--width", "64",
                 "--quiet"]) == 0
    spec_in = oiio.ImageInput.open(str(out_path)).spec()
    names = list(spec_in.channelnames)
    pixels = read(out_path)
    centre = pixels[pixels.shape[0] // 2, pixels.shape[1] // 2]
    assert centre[names.index("A")] == 1.0
    normal = centre[[names.index(f"N.{c}") for c in "XYZ"]]
    np.testing.assert_allclose(normal, [np.sin(angle), 0.0, np.cos(angle)], atol=2e-3)


def test_drawing_wrinkles_over_baked_maps_warns(gl_context, tmp_path, shirt_maps, capsys):
    """The maps layer drawn with wrinkles would show them twice: a warning says so."""
    out = tmp_path / "twice.png"
    assert main(["render", str(shirt_maps), str(out), "--frames", "24", "--width", "64"]) == 0
    err = capsys.readouterr().err
    assert "baked wrinkle maps" in err and "--no-wrinkles" in err and "/World/Arm/Sleeve" in err
    assert main(["render", str(shirt_maps), str(out), "--frames", "24", "--width", "64",
                 "--no-wrinkles"]) == 0
    assert "baked wrinkle maps" not in capsys.readouterr().err


# --- MikkTSpace (bake --tangent-space mikktspace) ---------------------------------------


def test_mikktspace_on_a_flat_sheet_is_the_triangle_frame():
    """On a plane with affine texture coordinates every triangle's dP/ds is the same, so
    MikkTSpace's averaged tangent is dP/ds exactly, sign +1; a mirrored island gets the
    mirrored tangent and sign -1 (mikktspace.c: ORIENT_PRESERVING)."""
    from usdwrinkle.maps.tangents import mikktspace

    rest, counts, indices = grid_sheet(5, 4, 2.0)
    quads = np.asarray(indices).reshape(-1, 4)
    triangles = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    uv = (rest[:, :2] + 1.0) / 2.0 * np.array([0.5, 2.0])   # s along x, t along y
    corner_uv = uv[triangles].reshape(-1, 2)
    normals = np.tile([0.0, 0.0, 1.0], (3 * len(triangles), 1))
    tangents = mikktspace(rest, triangles, normals, corner_uv)
    np.testing.assert_allclose(tangents[:, :3], np.tile([1.0, 0.0, 0.0], (len(tangents), 1)),
                               atol=1e-6)
    assert (tangents[:, 3] == 1.0).all()
    mirrored = mikktspace(rest, triangles, normals, corner_uv * np.array([-1.0, 1.0]))
    np.testing.assert_allclose(mirrored[:, :3], -tangents[:, :3], atol=1e-6)
    assert (mirrored[:, 3] == -1.0).all()


def test_mikktspace_maps_of_the_analytic_sheet_equal_the_triangle_maps(gl_context, tmp_path):
    """On the flat analytic sheet the two frames agree, so the two maps do (8-bit); the
    layer records the frame it was baked in."""
    source = sheet_stage(tmp_path, 0.7)
    maps = {}
    for frame in ("triangle", "mikktspace"):
        layer = tmp_path / f"{frame}.usda"
        assert bake_maps(source, layer, "--tangent-space", frame, kinds="normal") == 0
        maps[frame] = read(tmp_path / f"{frame}_maps" / "Sheet.normal.0001.png")
        data = Sdf.Layer.FindOrOpen(str(layer)).customLayerData["usdwrinkle"]["maps"]
        assert data["tangentSpace"] == frame
    assert np.abs(maps["mikktspace"] - maps["triangle"]).max() <= 1.5 / 255


def test_default_maps_are_a_set_per_material_purpose(gl_context, tmp_path):
    """Without --tangent-space and --map-layout the bake writes two map sets: for final
    renderers (the all-purpose binding, which Blender's importer reads) the MikkTSpace
    maps in the asset's UVs, and for usdview's Storm (material:binding:preview, which
    Storm resolves first) the per-triangle maps in islands. Each is, to the byte, what
    the one-set bake in that frame and layout writes, which the real-client tier
    measures in Cycles and Storm (tests/test_realclients.py)."""
    def bake(name, *args):
        layer = tmp_path / f"{name}.usda"
        assert main(["bake", SHIRT, str(layer), "--quiet", "--frames", "24", "--maps",
                     "normal", "--map-size", "256", *args]) == 0
        return layer, tmp_path / f"{name}_maps"

    layer, folder = bake("default")
    assert sorted(os.listdir(folder)) == ["Sleeve.normal.0024.png",
                                          "Sleeve.preview.normal.0024.png"]
    _, full = bake("full", "--tangent-space", "mikktspace", "--map-layout", "asset")
    _, preview = bake("preview", "--tangent-space", "triangle", "--map-layout", "islands")
    assert sorted(os.listdir(full)) == sorted(os.listdir(preview)) == ["Sleeve.normal.0024.png"]
    default_full = read(folder / "Sleeve.normal.0024.png")
    default_preview = read(folder / "Sleeve.preview.normal.0024.png")
    assert np.array_equal(default_full, read(full / "Sleeve.normal.0024.png"))
    assert np.array_equal(default_preview, read(preview / "Sleeve.normal.0024.png"))
    assert not np.array_equal(default_full, default_preview)

    stage = Usd.Stage.Open(str(layer))
    binding = UsdShade.MaterialBindingAPI(stage.GetPrimAtPath("/World/Arm/Sleeve"))
    readers = {}
    for purpose in (UsdShade.Tokens.preview, UsdShade.Tokens.full, UsdShade.Tokens.allPurpose):
        material, _ = binding.ComputeBoundMaterial(purpose)
        reader = UsdShade.Shader(material.GetPrim().GetChild("WrinkleUV"))
        _, files = file_samples(stage, material.GetPath(), "wrinkleNormalFile")
        readers[purpose] = (str(material.GetPath()), reader.GetInput("varname").Get(),
                            os.path.basename(files[-1].path))
    assert readers[UsdShade.Tokens.preview] == (
        "/World/WrinkleMaterials/Sleeve_preview", "wrinkleMapST", "Sleeve.preview.normal.0024.png")
    assert readers[UsdShade.Tokens.full] == readers[UsdShade.Tokens.allPurpose] == (
        "/World/WrinkleMaterials/Sleeve", "st", "Sleeve.normal.0024.png")
    data = Sdf.Layer.FindOrOpen(str(layer)).customLayerData["usdwrinkle"]["maps"]
    assert (data["purpose"], data["tangentSpace"], data["islands"]) == ("full", "mikktspace", "")
    assert dict(data["preview"]) == {"meshes": "/World/Arm/Sleeve", "islands": "/World/Arm/Sleeve",
                                     "tangentSpace": "triangle"}


def test_display_color_keeps_the_preview_purpose_from_the_maps(gl_context, tmp_path):
    """With --display-color, usdview is to show the ramp (bound for the preview purpose):
    the default bake then writes no preview map set, and final renderers still get the
    MikkTSpace maps."""
    layer = tmp_path / "both.usda"
    assert main(["bake", SHIRT, str(layer), "--quiet", "--frames", "24", "--maps", "normal",
                 "--map-size", "256", "--display-color", "amplitude"]) == 0
    assert os.listdir(tmp_path / "both_maps") == ["Sleeve.normal.0024.png"]
    stage = Usd.Stage.Open(str(layer))
    binding = UsdShade.MaterialBindingAPI(stage.GetPrimAtPath("/World/Arm/Sleeve"))
    bound = {purpose: str(binding.ComputeBoundMaterial(purpose)[0].GetPath())
             for purpose in (UsdShade.Tokens.preview, UsdShade.Tokens.full)}
    assert bound == {UsdShade.Tokens.preview: "/World/WrinkleMaterials/DisplayColor",
                     UsdShade.Tokens.full: "/World/WrinkleMaterials/Sleeve"}
    data = Sdf.Layer.FindOrOpen(str(layer)).customLayerData["usdwrinkle"]["maps"]
    assert data["tangentSpace"] == "mikktspace" and "preview" not in data


def test_preview_maps_fall_back_to_the_asset_uvs_where_islands_do_not_fit(gl_context,
                                                                           tmp_path, capfd):
    """900 faces on a 64-texel map leave islands too small to hold a wave: the default
    bake does not fail for the preview set (it did not before it had one), but lays that
    set out in the mesh's UVs, per triangle, and says so; the full set is as ever."""
    source = sheet_stage(tmp_path, 0.7)
    layers = {name: tmp_path / f"{name}.usda" for name in ("default", "triangle")}
    assert main(["bake", str(source), str(layers["default"]), "--quiet", "--maps", "normal",
                 "--map-size", "64"]) == 0
    assert "the preview maps are laid out in 'st'" in capfd.readouterr().err
    assert main(["bake", str(source), str(layers["triangle"]), "--quiet", "--maps", "normal",
                 "--map-size", "64", "--tangent-space", "triangle", "--map-layout",
                 "asset"]) == 0
    preview = read(tmp_path / "default_maps" / "Sheet.preview.normal.0001.png")
    assert np.array_equal(preview, read(tmp_path / "triangle_maps" / "Sheet.normal.0001.png"))
    stage = Usd.Stage.Open(str(layers["default"]))
    material = UsdShade.Material(stage.GetPrimAtPath("/WrinkleMaterials/Sheet_preview"))
    reader = UsdShade.Shader(material.GetPrim().GetChild("WrinkleUV"))
    assert reader.GetInput("varname").Get() == "st"
    assert not stage.GetPrimAtPath("/Sheet").HasAttribute("primvars:wrinkleMapST")
    data = Sdf.Layer.FindOrOpen(str(layers["default"])).customLayerData["usdwrinkle"]["maps"]
    assert data["preview"]["islands"] == "" and data["preview"]["meshes"] == "/Sheet"


def test_each_set_keeps_the_look_its_renderers_resolve(gl_context, tmp_path):
    """A mesh that binds a material per purpose (all red, full blue, preview green): the
    full set's material takes the full look and is bound for the full purpose too (Blender
    and final renderers resolve full first, and would otherwise show the blue material
    without wrinkles), the preview set's takes the preview look; the displaced render mesh
    keeps the coarse mesh's full binding."""
    source = sheet_stage(tmp_path, 0.7)
    stage = Usd.Stage.Open(str(source))
    bind_purpose_looks(stage, "/Sheet")
    stage.Save()
    layer = tmp_path / "looks.usda"
    assert main(["bake", str(source), str(layer), "--quiet", "--maps", "normal", "--map-size",
                 "256", "--geometry", "--levels", "1"]) == 0
    baked = Usd.Stage.Open(str(layer))
    mesh = UsdShade.MaterialBindingAPI(baked.GetPrimAtPath("/Sheet"))
    seen = {}
    for purpose in (UsdShade.Tokens.full, UsdShade.Tokens.preview):
        material, _ = mesh.ComputeBoundMaterial(purpose)
        surface = material.ComputeSurfaceSource()[0]
        seen[purpose] = (str(material.GetPath()), tuple(surface.GetInput("diffuseColor").Get()),
                         surface.GetInput("normal").HasConnectedSource())
    assert seen == {UsdShade.Tokens.full: ("/WrinkleMaterials/Sheet", (0, 0, 1), True),
                    UsdShade.Tokens.preview: ("/WrinkleMaterials/Sheet_preview", (0, 1, 0), True)}
    fine = UsdShade.MaterialBindingAPI(baked.GetPrimAtPath("/Sheet_wrinkled"))
    assert str(fine.ComputeBoundMaterial(UsdShade.Tokens.full)[0].GetPath()) == "/Looks/Final"


def _smooth_normals(points, quads):
    """Per point the sum over its quads' corners of cross(next - p, prev - p), as the
    normals pass makes a polygonal mesh's smooth normals (scene/normals.py)."""
    normals = np.zeros_like(points)
    for c in range(4):
        p = points[quads[:, c]]
        cross = np.cross(points[quads[:, (c + 1) % 4]] - p, points[quads[:, (c - 1) % 4]] - p)
        np.add.at(normals, quads[:, c], cross)
    return normals / np.linalg.norm(normals, axis=1, keepdims=True)


def test_mikktspace_maps_decode_to_the_triangle_maps_normals_on_the_shirt(gl_context,
                                                                           tmp_path):
    """The shirt's elbow, where the two frames differ by 10 degrees (median): the
    MikkTSpace map decoded as Cycles decodes it (tangent and normal interpolated, not
    renormalised, B = sign cross(N, T); the normal Blender's own, angle-weighted, since
    this subdivision mesh authors none; the tangents summed over the triangles
    mikktspace.c splits each quad into; numpy, maps/tangents.py) gives the normal that
    the per-triangle map decodes to in its own frame about usdwrinkle's normal, at 2000
    points inside the triangles. Both decodes read the same texel, so what is left is
    the 8-bit quantisation and the normals pass's float rounding (measured: p99 0.72
    degrees)."""
    from usdwrinkle.maps.tangents import (
        blender_vertex_normals,
        mikktspace,
        mikktspace_triangles,
    )

    size = 1024
    maps = {}
    for frame in ("triangle", "mikktspace"):
        layer = tmp_path / f"{frame}.usda"
        assert bake_maps(SHIRT, layer, "--frames", "24", "--with-points", "--tangent-space",
                         frame, kinds="normal", size=size) == 0
        maps[frame] = read(tmp_path / f"{frame}_maps" / "Sleeve.normal.0024.png") * 2 - 1
    root = Sdf.Layer.CreateAnonymous()
    root.subLayerPaths = [str(tmp_path / "triangle.usda"), SHIRT]   # the layer over the shot
    stage = Usd.Stage.Open(root)
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Arm/Sleeve"))
    points = np.asarray(mesh.GetPointsAttr().Get(24), np.float64)
    quads = np.asarray(mesh.GetFaceVertexIndicesAttr().Get()).reshape(-1, 4)
    st = UsdGeom.PrimvarsAPI(mesh).GetPrimvar("st")
    face_uv = np.asarray(st.Get(), np.float64).reshape(-1, 4, 2)   # faceVarying
    assert st.GetInterpolation() == UsdGeom.Tokens.faceVarying
    fan = [[0, 1, 2], [0, 2, 3]]                      # each quad's two triangles, in turn
    triangles = quads[:, fan].reshape(-1, 3)
    corner_uv = face_uv[:, fan].reshape(-1, 2)
    vertex_normals = _smooth_normals(points, quads)
    blender = blender_vertex_normals(points, np.full(len(quads), 4), quads.reshape(-1))
    ids = mikktspace_triangles(points, triangles, np.repeat(np.arange(len(quads)), 2),
                               corner_uv)
    tangents = mikktspace(points, triangles, blender[triangles].reshape(-1, 3), corner_uv,
                          mikk_ids=ids).reshape(-1, 3, 4)

    rng = np.random.default_rng(7)
    t = rng.integers(0, len(triangles), 2000)
    bary = rng.dirichlet([4, 4, 4], 2000)
    bary = np.maximum(bary, 0.15) / np.maximum(bary, 0.15).sum(1, keepdims=True)
    uv = np.einsum("nc,ncd->nd", bary, corner_uv.reshape(-1, 3, 2)[t])
    texel = np.floor(uv * size).astype(int).clip(0, size - 1)
    row = size - 1 - texel[:, 1]                       # image row 0 is t = 1
    n = np.einsum("nc,ncd->nd", bary, vertex_normals[triangles[t]])

    # MikkTSpace, as Cycles' normal-map node decodes it
    tangent = np.einsum("nc,ncd->nd", bary, tangents[t, :, :3])
    blender_n = np.einsum("nc,ncd->nd", bary, blender[triangles[t]])
    bitangent = tangents[t, 0, 3:4] * np.cross(blender_n, tangent)
    c = maps["mikktspace"][row, texel[:, 0]]
    mikk = c[:, :1] * tangent + c[:, 1:2] * bitangent + c[:, 2:3] * blender_n
    mikk /= np.linalg.norm(mikk, axis=1, keepdims=True)

    # the per-triangle frame, as Storm and usdwrinkle decode it (include/wave.glsl)
    p = points[triangles[t]]
    s = corner_uv.reshape(-1, 3, 2)[t]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d1, d2 = s[:, 1] - s[:, 0], s[:, 2] - s[:, 0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    dp_ds = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / det[:, None]
    dp_dt = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / det[:, None]
    unit_n = n / np.linalg.norm(n, axis=1, keepdims=True)
    T = dp_ds - np.sum(dp_ds * unit_n, 1, keepdims=True) * unit_n
    T /= np.linalg.norm(T, axis=1, keepdims=True)
    B = np.cross(unit_n, T)
    B *= np.sign(np.sum(B * dp_dt, 1, keepdims=True))
    c = maps["triangle"][row, texel[:, 0]]
    triangle = c[:, :1] * T + c[:, 1:2] * B + c[:, 2:3] * unit_n
    triangle /= np.linalg.norm(triangle, axis=1, keepdims=True)

    degrees = np.degrees(np.arccos(np.clip(np.sum(mikk * triangle, 1), -1, 1)))
    tilt = np.degrees(np.arccos(np.clip(np.sum(triangle * unit_n, 1), -1, 1)))
    assert np.percentile(tilt, 90) > 10.0            # the samples hold real wrinkles
    median, p99 = np.percentile(degrees, [50, 99])
    print(f"MikkTSpace vs triangle decode: median {median:.2f}, p99 {p99:.2f} degrees")
    assert median < 0.5 and p99 < 2.0, (median, p99)
    # and the two maps differ where the frames do: the option is not a no-op
    frames = np.degrees(np.arccos(np.clip(np.sum(
        maps["mikktspace"][row, texel[:, 0]] * c, 1) / np.linalg.norm(c, axis=1)
        / np.linalg.norm(maps["mikktspace"][row, texel[:, 0]], axis=1), -1, 1)))
    assert np.percentile(frames, 90) > 2.0


def test_a_map_folder_that_is_the_layers_own_path_is_refused_before_any_work(tmp_path,
                                                                             capsys):
    """Issue 54: ``--map-dir`` naming the layer's own path left a partial map set there
    (the maps moved in, then the layer could not replace the folder). All or nothing."""
    from usdwrinkle.cli.main import main

    layer = tmp_path / "x.usda"
    for spelling in (str(layer), str(tmp_path / "." / "x.usda")):
        assert main(["bake", str(SHIRT), str(layer), "--frames", "1:2", "--maps", "normal",
                     "--map-size", "64", "--map-dir", spelling]) == 2
        assert "--map-dir" in capsys.readouterr().err
        assert not list(tmp_path.iterdir())
