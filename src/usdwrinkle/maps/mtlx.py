"""The texture deformation as a MaterialX network (render context ``mtlx``), written
into a wrinkle material beside its UsdPreviewSurface (maps/material.py).

usdwrinkle's draw pass moves the texture with the folds (draw.glsl): the point seen
through a wrinkle is ``x' = (v/(v.n') - n') h`` away, v toward the eye, n' the bent normal,
h the height, all in the mesh's local space, and its texture coordinates move by
``(S.x', T.x')``, S and T the gradients of the texture's s and t. That depends on the
view, which UsdPreviewSurface cannot express. The parallax maps (bake --maps parallax)
hold what does not: n', hS and hT per texel, taken to world space per frame (for a
similarity transform the products equal the local ones; Storm's MaterialX offers no
object space: its object-space normal measured constant). They are laid out in the
texture coordinates the look's textures read (``uv``). This network reads them, takes
the view direction per pixel (``viewdirection``, world space), and reads each of the
look's textures at the moved coordinates. So a camera the bake never saw gets its own
offset.

Its shading normal is n' too, expressed in the renderer's own tangent frame
(``tangent``, ``bitangent``, ``normal``, world space), which UsdPreviewSurface's
``normalmap`` turns back into n': no tangent frame has to agree with the bake's.

Where n' faces away from the eye (or nearly), the network shades it turned back to the
horizon as the draw pass does (contract.HORIZON_COSINE; docs/method.md, "The horizon"),
which the normal map, the same for every view, cannot; the offset keeps n' as it is.

Storm (usdview) takes ``outputs:mtlx:surface`` over the universal ``outputs:surface``;
a renderer without MaterialX keeps the UsdPreviewSurface, unchanged. Node ids are
MaterialX's standard library's (MaterialX 1.38+), as UsdShade ``info:id``.
"""
from __future__ import annotations

import os

from pxr import Sdf

from ..method.contract import HORIZON_COSINE
from ..outputs.layers import attribute_spec, define_prim
from ..usd.schema import MAP_INPUTS, PREVIEW_SURFACE_TYPES
from .files import relative_asset

VALUE_TYPES = Sdf.ValueTypeNames
#: the render context's surface output on the material
SURFACE_OUTPUT = "outputs:mtlx:surface"
#: |v.n'| is held at least this (draw.glsl): grazing views shift by at most 4 h
MIN_FACING = 0.25
#: UsdUVTexture wrap -> MaterialX address mode
ADDRESS = {"repeat": "periodic", "clamp": "clamp", "mirror": "mirror", "black": "constant",
           "useMetadata": "periodic"}
#: MaterialX type -> (Sdf value type, image node id)
TYPES = {"color3": (VALUE_TYPES.Color3f, "ND_image_color3"),
         "float": (VALUE_TYPES.Float, "ND_image_float"),
         "vector3": (VALUE_TYPES.Float3, "ND_image_vector3"),
         "vector2": (VALUE_TYPES.Float2, None),
         "matrix33": (VALUE_TYPES.Matrix3d, None),
         "integer": (VALUE_TYPES.Int, None)}
#: the prefix of every node this module writes (the material may reference another's)
PREFIX = "Mtlx"


class _Graph:
    """Shader specs under a material, each with typed inputs and one output."""

    def __init__(self, layer: Sdf.Layer, material: Sdf.Path):
        self.layer = layer
        self.material = material

    def node(self, name: str, shader_id: str, output: str = "vector3", **inputs) -> Sdf.Path:
        """A node ``name`` of ``shader_id``; each input is (mtlx type, value or the path
        of a node's output or of a material input). Returns its ``outputs:out``."""
        path = self.material.AppendChild(PREFIX + name)
        spec = define_prim(self.layer, path, "Shader")
        attribute_spec(spec, "info:id", VALUE_TYPES.Token, shader_id, uniform=True)
        for input_name, (kind, value) in inputs.items():
            type_name = {"string": VALUE_TYPES.String, "filename": VALUE_TYPES.Asset}.get(
                kind) or TYPES[kind][0]
            if isinstance(value, Sdf.Path):
                attribute_spec(spec, f"inputs:{input_name}", type_name, connect=value)
            else:
                attribute_spec(spec, f"inputs:{input_name}", type_name, value)
        out_type = VALUE_TYPES.Token if output == "surfaceshader" else TYPES[output][0]
        attribute_spec(spec, "outputs:out", out_type)
        return path.AppendProperty("outputs:out")


def _image(graph: _Graph, name: str, kind: str, file, texcoord: Sdf.Path, wrap=("periodic",
           "periodic"), colorspace: str | None = None) -> Sdf.Path:
    path = graph.node(name, TYPES[kind][1], kind,
                      file=("filename", file), texcoord=("vector2", texcoord),
                      uaddressmode=("string", wrap[0]), vaddressmode=("string", wrap[1]))
    if colorspace:
        spec = graph.layer.GetAttributeAtPath(path.GetPrimPath().AppendProperty("inputs:file"))
        spec.SetInfo("colorSpace", colorspace)
    return path


def _colorspace(file: str, source_space: str) -> str | None:
    """A colour texture's MaterialX colour space: sRGB unless it is raw or a float image."""
    if source_space == "raw":
        return None
    if source_space == "auto" and os.path.splitext(file)[1].lower() in (".exr", ".hdr"):
        return None
    return "srgb_texture"


def author_network(layer: Sdf.Layer, material: Sdf.Path, inputs: tuple, map_st: str,
                   wrap: str, layer_path: str) -> None:
    """The MaterialX network on ``material`` (already holding the parallax maps' file
    inputs, MAP_INPUTS): ``inputs`` are its look's surface inputs
    (as scene/material.look_inputs reads them), ``map_st`` the primvar the maps are laid out in,
    ``wrap`` their address mode ("periodic", or "clamp" for UDIM sets), ``layer_path``
    the bake layer's (texture paths are written relative to it)."""
    graph = _Graph(layer, material)
    maps_st = graph.node("MapST", "ND_geompropvalue_vector2", "vector2",
                         geomprop=("string", map_st))
    read = {}
    for kind, name in (("parallaxN", "Bent"), ("parallaxS", "SlopeS"),
                       ("parallaxT", "SlopeT")):
        file_input = material.AppendProperty(f"inputs:{MAP_INPUTS[kind]}")
        read[kind] = _image(graph, name, "vector3", file_input, maps_st, (wrap, wrap))
    read_bent = read["parallaxN"]
    # x' = v/(v.n') - n' with v toward the eye; MaterialX's view direction d points away
    # from it (d/|d.n'| + n' = -x' where the surface faces the eye)
    view = graph.node("View", "ND_viewdirection_vector3", space=("string", "world"))
    # the renderer's own frame, world space (its normal is the coarse surface's)
    frame = [graph.node(axis, f"ND_{axis.lower()}_vector3", space=("string", "world"))
             for axis in ("Tangent", "Bitangent", "Normal")]
    coarse = graph.node("NormalUnit", "ND_normalize_vector3", **{"in": ("vector3", frame[2])})
    coarse_side = graph.node("CoarseSide", "ND_dotproduct_vector3", "float",
                             in1=("vector3", view), in2=("vector3", coarse))
    # the horizon (draw.glsl's bend, contract.HORIZON_COSINE): n' turned back towards the
    # eye, n' - (c' + d.n') d normalised, where its cosine with the eye's direction is
    # under c' = min(HORIZON_COSINE, the coarse normal's)
    coarse_facing = graph.node("CoarseFacing", "ND_multiply_float", "float",
                               in1=("float", coarse_side), in2=("float", -1.0))
    least = graph.node("HorizonLeast", "ND_min_float", "float",
                       in1=("float", HORIZON_COSINE), in2=("float", coarse_facing))
    bent_side = graph.node("BentSide", "ND_dotproduct_vector3", "float",
                           in1=("vector3", view), in2=("vector3", read_bent))
    deficit = graph.node("HorizonDeficit", "ND_add_float", "float", in1=("float", least),
                         in2=("float", bent_side))
    push = graph.node("HorizonPush", "ND_multiply_vector3FA", in1=("vector3", view),
                      in2=("float", deficit))
    turned = graph.node("HorizonTurned", "ND_subtract_vector3", in1=("vector3", read_bent),
                        in2=("vector3", push))
    turned = graph.node("HorizonUnit", "ND_normalize_vector3", **{"in": ("vector3", turned)})
    bent = graph.node("Horizon", "ND_ifgreatereq_vector3", value1=("float", 0.0),
                      value2=("float", deficit), in1=("vector3", read_bent),
                      in2=("vector3", turned))
    facing = graph.node("ViewFacingAbs", "ND_absval_float", "float",
                        **{"in": ("float", bent_side)})
    facing = graph.node("ViewFacingMin", "ND_max_float", "float", in1=("float", facing),
                        in2=("float", MIN_FACING))
    steep = graph.node("Steep", "ND_divide_vector3FA", in1=("vector3", view),
                       in2=("float", facing))
    seen = graph.node("Seen", "ND_add_vector3", in1=("vector3", steep),
                      in2=("vector3", read_bent))
    ds = graph.node("OffsetS", "ND_dotproduct_vector3", "float",
                    in1=("vector3", read["parallaxS"]), in2=("vector3", seen))
    dt = graph.node("OffsetT", "ND_dotproduct_vector3", "float",
                    in1=("vector3", read["parallaxT"]), in2=("vector3", seen))
    offset = graph.node("Offset", "ND_combine2_vector2", "vector2", in1=("float", ds),
                        in2=("float", dt))
    # the bent normal in the renderer's tangent frame, which normalmap decodes back. Seen
    # from behind (a sleeve's inside: the renderer's normal faces away from the eye, or,
    # where the renderer turns it to the eye on a back face, away from the bent one) the
    # renderer's own normal: Storm shades the bent one there unlit (measured: black, where
    # its own is lit)
    # c with T c.x + B c.y + N c.z = n' (the frame need not be orthonormal: Storm's
    # bitangent measured a constant (0, 1, 0))
    basis = graph.node("Frame", "ND_creatematrix_vector3_matrix33", "matrix33",
                       **{f"in{i + 1}": ("vector3", axis) for i, axis in enumerate(frame)})
    inverse = graph.node("FrameInverse", "ND_invertmatrix_matrix33", "matrix33",
                         **{"in": ("matrix33", basis)})
    bent_tangent = graph.node("NormalTangent", "ND_transformmatrix_vector3",
                              **{"in": ("vector3", bent), "mat": ("matrix33", inverse)})
    front = graph.node("CoarseFront", "ND_ifgreatereq_vector3", value1=("float", 0.0),
                       value2=("float", coarse_side), in1=("vector3", bent_tangent),
                       in2=("vector3", (0.0, 0.0, 1.0)))
    agree = graph.node("BentAgrees", "ND_dotproduct_vector3", "float",
                       in1=("vector3", coarse), in2=("vector3", read_bent))
    normal = graph.node("NormalFront", "ND_ifgreatereq_vector3", value1=("float", agree),
                        value2=("float", 0.0), in1=("vector3", front),
                        in2=("vector3", (0.0, 0.0, 1.0)))
    surface_inputs = {"normal": ("vector3", normal)}
    deformed = {}
    for name, how, payload in inputs:
        kind = PREVIEW_SURFACE_TYPES[name]
        if how == "value":
            value = payload[0] if kind in ("float", "integer") else tuple(payload[:3])
            surface_inputs[name] = (kind, int(value) if kind == "integer" else value)
            continue
        if kind not in ("color3", "float"):
            continue
        file, wrap_s, wrap_t, space, varname, output, scale, bias = payload
        if varname not in deformed:
            st = graph.node(f"ST_{varname}", "ND_geompropvalue_vector2", "vector2",
                            geomprop=("string", varname))
            deformed[varname] = graph.node(f"DeformedST_{varname}", "ND_subtract_vector2",
                                           "vector2", in1=("vector2", st),
                                           in2=("vector2", offset))
        channel = {"rgb": None, "r": 0, "g": 1, "b": 2, "a": 3}.get(output)
        image_kind = "color3" if kind == "color3" else "float"
        if kind == "float" and channel not in (None, 0):
            continue  # a channel other than the first: kept at the fallback
        texel = _image(graph, f"Texture_{name}", image_kind,
                       Sdf.AssetPath(relative_asset(file, layer_path)), deformed[varname],
                       (ADDRESS.get(wrap_s, "periodic"), ADDRESS.get(wrap_t, "periodic")),
                       _colorspace(file, space) if kind == "color3" else None)
        if tuple(scale[:3]) != (1.0, 1.0, 1.0) or tuple(bias[:3]) != (0.0, 0.0, 0.0):
            if kind == "color3":
                texel = graph.node(f"Scale_{name}", "ND_multiply_color3", "color3",
                                   in1=("color3", texel), in2=("color3", tuple(scale[:3])))
                texel = graph.node(f"Bias_{name}", "ND_add_color3", "color3",
                                   in1=("color3", texel), in2=("color3", tuple(bias[:3])))
            else:
                texel = graph.node(f"Scale_{name}", "ND_multiply_float", "float",
                                   in1=("float", texel), in2=("float", scale[0]))
                texel = graph.node(f"Bias_{name}", "ND_add_float", "float",
                                   in1=("float", texel), in2=("float", bias[0]))
        surface_inputs[name] = (kind, texel)
    surface = graph.node("Surface", "ND_UsdPreviewSurface_surfaceshader", "surfaceshader",
                         **surface_inputs)
    spec = layer.GetPrimAtPath(material)
    attribute_spec(spec, SURFACE_OUTPUT, VALUE_TYPES.Token, connect=surface)
