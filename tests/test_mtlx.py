"""bake --maps parallax: the parallax maps against the analytic sheet, the MaterialX network
evaluated against draw.glsl's texture deformation (numpy), validated by MaterialX's own
library, its generated GLSL compiled on our GL context, and the UsdPreviewSurface
binding a reader without MaterialX takes, unchanged."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Sdf, Usd, UsdShade

from usdwrinkle.maps.mtlx import MIN_FACING, PREFIX, SURFACE_OUTPUT
from usdwrinkle.method.contract import HORIZON_COSINE

from helpers import MAPS_SIZE as SIZE
from helpers import MAPS_WIDTH as WIDTH
from helpers import bake_maps, fold_law, rotation_matrix
from helpers import maps_sheet_stage as sheet_stage
from helpers import read_pixels as read

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
SHIRT = str(SAMPLES / "shirt.usda")
PARALLAX = ("parallaxN", "parallaxS", "parallaxT")


def parallax_maps(tmp_path, ratio, rotation=None):
    source = sheet_stage(tmp_path, ratio, rotation)
    layer = tmp_path / "maps.usda"
    assert bake_maps(source, layer, kinds="normal,height,parallax") == 0
    folder = tmp_path / "maps_maps"
    maps = {kind: read(folder / f"Sheet.{kind}.0001.exr")[..., :3] for kind in PARALLAX}
    maps["height"] = read(folder / "Sheet.height.0001.exr")[..., 0]
    maps["normal"] = read(folder / "Sheet.normal.0001.png") * 2.0 - 1.0
    inner = slice(SIZE // 8, SIZE - SIZE // 8)
    return {kind: image[inner, inner] for kind, image in maps.items()}, layer


@pytest.mark.parametrize("ratio", [0.6, 0.85])
def test_parallax_maps_of_the_analytic_sheet(gl_context, tmp_path, ratio):
    """The sheet's st = (x + 1, y + 1) / 2 at rest, x compressed by ``ratio``: dP/ds =
    (2 ratio, 0, 0), dP/dt = (0, 2, 0), so S = (1 / (2 ratio), 0, 0), T = (0, 1/2, 0), and
    the maps hold h S, h T and the bent normal, which is the normal map's (the triangle
    frame of a flat sheet is the axes)."""
    maps, _ = parallax_maps(tmp_path, ratio)
    h = maps["height"]
    a = float(fold_law(ratio, WIDTH)[0])
    assert np.abs(h).max() > 0.5 * a  # there are folds
    np.testing.assert_allclose(maps["parallaxS"][..., 0], h / (2 * ratio), atol=1e-6)
    np.testing.assert_allclose(maps["parallaxT"][..., 1], h / 2, atol=1e-6)
    assert np.abs(maps["parallaxS"][..., 1:]).max() < 1e-6
    assert np.abs(maps["parallaxT"][..., [0, 2]]).max() < 1e-6
    normal = maps["normal"] / np.linalg.norm(maps["normal"], axis=-1, keepdims=True)
    np.testing.assert_allclose(maps["parallaxN"], normal, atol=2e-4)  # 16-bit PNG
    np.testing.assert_allclose(np.linalg.norm(maps["parallaxN"], axis=-1), 1.0, atol=1e-5)


def test_parallax_maps_are_in_world_space(gl_context, tmp_path):
    """A rigid motion of the posed sheet turns the maps with it: they are world space (the
    view direction a renderer's network has), and the products with a turned view equal
    the unturned ones."""
    for name in ("plain", "moved"):
        (tmp_path / name).mkdir()
    rotation = rotation_matrix([0.3, -0.5, 0.8], 1.1)
    plain, _ = parallax_maps(tmp_path / "plain", 0.7)
    moved, _ = parallax_maps(tmp_path / "moved", 0.7, rotation)
    a = float(fold_law(0.7, WIDTH)[0])
    for kind, tolerance in (("parallaxN", 0.01), ("parallaxS", 0.01 * a),
                            ("parallaxT", 0.01 * a)):
        turned = plain[kind] @ rotation.T
        assert np.abs(moved[kind] - turned).max() < tolerance, kind


# -- the network, evaluated node by node -------------------------------------------------


def network(stage, material_path):
    """{node name: (info:id, {input: value or source node name})} of the MaterialX
    network, and the name of the node the material's mtlx surface output reads."""
    material = UsdShade.Material(stage.GetPrimAtPath(material_path))
    nodes = {}
    for child in material.GetPrim().GetChildren():
        shader = UsdShade.Shader(child)
        if not child.GetName().startswith(PREFIX):
            continue
        inputs = {}
        for inp in shader.GetInputs():
            sources = inp.GetConnectedSources()[0]
            if sources:
                source = sources[0].source.GetPrim()
                inputs[inp.GetBaseName()] = ("node", source.GetName()) \
                    if source != material.GetPrim() else ("material", sources[0].sourceName)
            else:
                inputs[inp.GetBaseName()] = ("value", inp.Get())
        nodes[child.GetName()] = (shader.GetIdAttr().Get(), inputs)
    surface = material.GetPrim().GetAttribute(SURFACE_OUTPUT).GetConnections()[0]
    return nodes, surface.GetPrimPath().name


def evaluate(nodes, name, context, cache=None):
    """The value of node ``name`` for ``context``: geomprop / file name -> value, and
    "view", "tangent", "bitangent", "normal" (numpy vectors)."""
    cache = {} if cache is None else cache
    if name in cache:
        return cache[name]
    node_id, inputs = nodes[name]

    def arg(key):
        how, value = inputs[key]
        if how == "node":
            return evaluate(nodes, value, context, cache)
        if how == "material":
            return context[value]
        return np.asarray(value, np.float64) if not isinstance(value, str) else value

    kind = node_id[3:]
    if kind.startswith("geompropvalue"):
        out = context[arg("geomprop")]
    elif kind.startswith("image"):  # the maps from the context; the look's own a grey
        how, value = inputs["file"]
        out = context[("image", value, tuple(arg("texcoord")))] if how == "material" \
            else np.full(3, 0.5)
    elif kind.startswith("viewdirection"):
        assert arg("space") == "world"
        out = context["view"]
    elif kind.split("_")[0] in ("tangent", "bitangent", "normal"):
        out = context[kind.split("_")[0]]
    elif kind.startswith("dotproduct"):
        out = float(np.dot(arg("in1"), arg("in2")))
    elif kind.startswith("absval"):
        out = abs(arg("in"))
    elif kind.startswith("max"):
        out = max(arg("in1"), arg("in2"))
    elif kind.startswith("min"):
        out = min(arg("in1"), arg("in2"))
    elif kind.startswith("normalize"):
        out = arg("in") / np.linalg.norm(arg("in"))
    elif kind.startswith("divide"):
        out = arg("in1") / arg("in2")
    elif kind.startswith("add"):
        out = arg("in1") + arg("in2")
    elif kind.startswith("subtract"):
        out = arg("in1") - arg("in2")
    elif kind.startswith("multiply"):
        out = arg("in1") * arg("in2")
    elif kind.startswith("combine"):
        out = np.array([arg(f"in{i}") for i in range(1, 4) if f"in{i}" in inputs], float)
    elif kind.startswith("ifgreatereq"):
        out = arg("in1") if arg("value1") >= arg("value2") else arg("in2")
    elif kind.startswith("creatematrix"):
        out = np.column_stack([arg("in1"), arg("in2"), arg("in3")])  # GLSL mat3 columns
    elif kind.startswith("invertmatrix"):
        out = np.linalg.inv(arg("in"))
    elif kind.startswith("transformmatrix"):
        out = arg("mat") @ arg("in")    # mx_matrix_mul(mat, in)
    elif kind.startswith("UsdPreviewSurface"):
        out = {key: arg(key) for key in inputs}
    else:
        raise AssertionError(f"no evaluator for {node_id}")
    cache[name] = out
    return out


@pytest.fixture(scope="module")
def shirt_parallax(tmp_path_factory):
    folder = tmp_path_factory.mktemp("shirt_parallax")
    layer = folder / "maps.usda"
    from usdwrinkle.cli.main import main

    assert main(["bake", SHIRT, str(layer), "--quiet", "--frames", "24", "--maps",
                 "normal,parallax", "--map-size", "128"]) == 0
    return layer


def test_the_network_computes_the_draw_passes_offset(shirt_parallax):
    """For random texel values, views and (non-orthonormal) renderer frames, the network's
    st is draw.glsl's st + (S.dx, T.dx), dx = (v/max(|v.n'|, 1/4) - n') h with v toward
    the eye, and its normal input decodes (normalmap: T x + B y + N z) to n' turned to the
    horizon as the draw pass shades it (draw.glsl's bend: where its cosine with v is under
    c = min(HORIZON_COSINE, the renderer's normal's), n' + (c - v.n') v normalised) where
    the renderer's normal faces the eye and agrees with the map's, else to the renderer's
    own normal (seen from behind)."""
    stage = Usd.Stage.Open(str(shirt_parallax))
    nodes, surface = network(stage, "/World/WrinkleMaterials/Sleeve")
    _, surface_inputs = nodes[surface]
    texture = surface_inputs["diffuseColor"][1]
    rng = np.random.default_rng(7)
    checked = turned = 0
    for _ in range(400):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        h = rng.normal() * 0.1
        hs, ht = rng.normal(size=3) * h, rng.normal(size=3) * h
        view = rng.normal(size=3)
        view /= np.linalg.norm(view)          # MaterialX's: from the eye to the surface
        frame = rng.normal(size=(3, 3))
        st = rng.random(2)
        context = {"st": st, "view": view, "tangent": frame[0], "bitangent": frame[1],
                   "normal": frame[2]}
        for kind, value in (("wrinkleParallaxNormalFile", n), ("wrinkleParallaxSFile", hs),
                            ("wrinkleParallaxTFile", ht)):
            context[("image", kind, tuple(st))] = value
        cache = {}
        moved = evaluate(nodes, nodes[texture][1]["texcoord"][1], context, cache)
        v = -view
        coarse = frame[2] / np.linalg.norm(frame[2])
        least = min(HORIZON_COSINE, v @ coarse)
        seen = n if v @ n >= least else \
            (n + (least - v @ n) * v) / np.linalg.norm(n + (least - v @ n) * v)
        turned += v @ n < least
        dx = v / max(abs(v @ n), MIN_FACING) - n  # times h: the maps hold h S and h T
        np.testing.assert_allclose(moved, st + np.array([hs @ dx, ht @ dx]), atol=1e-12)
        coefficients = evaluate(nodes, surface, context, cache)["normal"]
        decoded = frame.T @ coefficients
        if v @ coarse >= 0 and coarse @ n >= 0:  # seen from the front
            np.testing.assert_allclose(decoded / np.linalg.norm(decoded), seen, atol=1e-9)
            assert v @ decoded / np.linalg.norm(decoded) >= least - 1e-3  # |n'+..| < 1.005
            checked += 1
        else:
            np.testing.assert_allclose(coefficients, (0, 0, 1))
    assert checked > 30 and turned > 30, (checked, turned)


def test_a_reader_without_materialx_keeps_the_usd_preview_surface(gl_context, tmp_path,
                                                                   shirt_parallax):
    """The universal surface and everything it reads are the same as in a bake without
    parallax; the mtlx context is the network's."""
    plain = tmp_path / "plain.usda"
    from usdwrinkle.cli.main import main

    assert main(["bake", SHIRT, str(plain), "--quiet", "--frames", "24", "--maps", "normal",
                 "--map-size", "128"]) == 0
    stages = [Usd.Stage.Open(str(layer)) for layer in (shirt_parallax, plain)]
    for name in ("Sleeve", "Sleeve_preview"):
        path = f"/World/WrinkleMaterials/{name}"
        shaded, reference = (UsdShade.Material(stage.GetPrimAtPath(path)) for stage in stages)

        def universal(material):
            surface = material.ComputeSurfaceSource("")[0]
            network = {}
            for prim in Usd.PrimRange(material.GetPrim()):
                if prim.GetName().startswith(PREFIX):
                    continue
                for attr in prim.GetAttributes():
                    value = attr.Get()
                    if isinstance(value, Sdf.AssetPath):  # the two bakes' map folders
                        value = Path(value.path).name
                    network[(prim.GetName(), attr.GetName())] = (
                        str(value), [str(c) for c in attr.GetConnections()])
            return surface.GetPath().name, {k: v for k, v in network.items()
                                            if "Parallax" not in k[1] and "mtlx" not in k[1]}

        assert universal(shaded) == universal(reference)
        assert shaded.ComputeSurfaceSource("mtlx")[0].GetPath().name == f"{PREFIX}Surface"
        assert reference.ComputeSurfaceSource("mtlx")[0].GetPath() == \
            reference.ComputeSurfaceSource("")[0].GetPath()


# -- MaterialX's own checks --------------------------------------------------------------


def materialx_document(stage, material_path):
    """The network as a MaterialX document (a nodegraph with the surface's inputs, and a
    surfacematerial), built from the UsdShade network node by node."""
    import MaterialX as mx

    nodes, surface = network(stage, material_path)
    material = UsdShade.Material(stage.GetPrimAtPath(material_path))
    library = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(),
                     library)
    doc = mx.createDocument()
    doc.importLibrary(library)
    made = {}
    for name, (node_id, _) in nodes.items():
        nodedef = library.getNodeDef(node_id)
        assert nodedef is not None, f"{node_id} is not in MaterialX's library"
        made[name] = doc.addNodeInstance(nodedef, name)
    for name, (node_id, inputs) in nodes.items():
        node = made[name]
        nodedef = library.getNodeDef(node_id)
        for key, (how, value) in inputs.items():
            definition = nodedef.getActiveInput(key)
            assert definition is not None, f"{node_id} has no input {key}"
            inp = node.addInput(key, definition.getType())
            if how == "node":
                inp.setConnectedNode(made[value])
            elif how == "material":
                asset = material.GetInput(value).Get()
                inp.setValueString(asset.resolvedPath or asset.path)
            elif isinstance(value, Sdf.AssetPath):
                inp.setValueString(value.path)
            elif isinstance(value, str):
                inp.setValueString(value)
            else:
                flat = np.ravel(np.asarray(value, np.float64))
                text = ", ".join(f"{v:g}" for v in flat)
                inp.setValueString(str(int(flat[0])) if definition.getType() == "integer"
                                   else text)
    out = doc.addMaterialNode("WrinkleMaterial", made[surface])
    return doc, out


def test_the_network_validates_in_materialx(shirt_parallax):
    mx = pytest.importorskip("MaterialX", reason="MaterialX (pip install MaterialX) checks the "
                             "network: the test extra installs it")
    doc, _ = materialx_document(Usd.Stage.Open(str(shirt_parallax)),
                                "/World/WrinkleMaterials/Sleeve_preview")
    valid, message = doc.validate()
    assert valid, message
    assert mx.getVersionIntegers() >= (1, 39, 0)


def test_the_networks_glsl_compiles_on_our_context(gl_context, shirt_parallax):
    """MaterialX's GLSL generator's vertex and pixel stages compile and link in our GL
    4.5 context."""
    pytest.importorskip("MaterialX", reason="the test extra installs MaterialX")
    import MaterialX as mx
    import MaterialX.PyMaterialXGenGlsl as mx_glsl
    import MaterialX.PyMaterialXGenShader as mx_gen

    doc, material = materialx_document(Usd.Stage.Open(str(shirt_parallax)),
                                       "/World/WrinkleMaterials/Sleeve")
    generator = mx_glsl.GlslShaderGenerator.create()
    context = mx_gen.GenContext(generator)
    context.registerSourceCodeSearchPath(mx.getDefaultDataSearchPath())
    shader = generator.generate("WrinkleMaterial", material, context)
    vertex = shader.getSourceCode(mx_gen.VERTEX_STAGE)
    pixel = shader.getSourceCode(mx_gen.PIXEL_STAGE)
    assert "texcoord" in pixel or "geomprop" in pixel or "i_geomprop" in pixel
    program = gl_context.program(vertex_shader=vertex, fragment_shader=pixel)
    assert program.glo > 0
    program.release()



def _dilated(mask, steps):
    for _ in range(steps):
        grown = mask.copy()
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                shifted = np.zeros_like(mask)
                shifted[max(dy, 0):mask.shape[0] + min(dy, 0),
                        max(dx, 0):mask.shape[1] + min(dx, 0)] = \
                    mask[max(-dy, 0):mask.shape[0] + min(-dy, 0),
                         max(-dx, 0):mask.shape[1] + min(-dx, 0)]
                grown |= shifted
        mask = grown
    return mask


def test_parallax_maps_are_dilated_past_their_borders(gl_context, tmp_path):
    """The sheet's st cover the middle of the map: with --map-padding 8, every texel within
    8 steps (8-connected) of a covered one holds a covered neighbour's values (a unit
    normal, the same h S), so a renderer's filter reading across the border finds no zero,
    and none beyond."""
    rest = (np.mgrid[-1:1:31j, -1:1:31j][::-1].reshape(2, -1).T + 1.0) / 4.0 + 0.25
    source = sheet_stage(tmp_path, 0.7, st=rest)
    images = {}
    for padding in (0, 8):
        layer = tmp_path / f"pad{padding}.usda"
        assert bake_maps(source, layer, "--map-padding", str(padding),
                         "--map-dir", str(tmp_path / f"pad{padding}"),
                         kinds="parallax") == 0
        images[padding] = {kind: read(tmp_path / f"pad{padding}" / f"Sheet.{kind}.0001.exr")
                           [..., :3] for kind in PARALLAX}
    covered = np.linalg.norm(images[0]["parallaxN"], axis=-1) > 0.5
    padded = np.linalg.norm(images[8]["parallaxN"], axis=-1) > 0.5
    assert 0.15 < covered.mean() < 0.4
    np.testing.assert_array_equal(padded, _dilated(covered, 8))
    np.testing.assert_allclose(np.linalg.norm(images[8]["parallaxN"][padded], axis=-1), 1.0,
                               atol=1e-5)
    for kind in PARALLAX:  # the islands themselves are the same
        np.testing.assert_array_equal(images[8][kind][covered], images[0][kind][covered])
    ring = padded & ~covered
    assert np.abs(images[8]["parallaxS"][ring]).max() > 0.0  # copied, not zero
