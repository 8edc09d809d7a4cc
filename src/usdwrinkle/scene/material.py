"""Materials: UsdPreviewSurface diffuseColor, constant or through UsdUVTexture, and
inputs:normal through a UsdUVTexture (a tangent-space normal map, one file or a UDIM set,
its file name possibly time-sampled: per-frame wrinkle maps).

Textures are opened through Ar, so a texture inside a .usdz package works; the
bytes are decoded by OpenImageIO. Texture coordinates become one value per
triangle corner, whatever the primvar's interpolation.
"""
from __future__ import annotations

import logging
import os
import tempfile
from functools import lru_cache

import numpy as np
from pxr import Ar, Usd, UsdGeom, UsdShade

from ..images.colour import srgb_decode
from ..method.contract import UDIM_TILES
from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_TEXTURE_SIZE
from ..usd.schema import MAP_INPUTS, PREVIEW_SURFACE_TYPES
from ..usd.values import frame_of, static_flattened, static_value
from .inputs import package_file, require_regular_file
from .records import MaterialRecord, NormalMapRecord, SurfaceParams, TextureImage
from .topology import Topology

_log = logging.getLogger(__name__)

DEFAULT_COLOR = np.array([0.6, 0.6, 0.6], np.float32)
#: Storm's displayColor where a mesh authors none (measured: 0.5 grey)
FALLBACK_DISPLAY_COLOR = np.array([0.5, 0.5, 0.5], np.float32)
#: UsdPreviewSurface's inputs:diffuseColor fallback
PREVIEW_DIFFUSE_FALLBACK = np.array([0.18, 0.18, 0.18], np.float32)


def load_texture(resolved_path: str, color_space: str = "auto") -> TextureImage:
    """Decode an image asset into RGBA, row 0 at the bottom (cached while the file, or
    the package that holds it, keeps its size and modification time: an artist who
    repaints a texture in a live usdview session sees the new one).

    ``color_space``: UsdUVTexture's sourceColorSpace. ``sRGB`` decodes to linear, ``raw``
    keeps the values (normal maps), ``auto`` decodes 8-bit images only, as the
    UsdPreviewSurface specification says. An 8-bit file keeps its codes (uint8; the GPU
    decodes sRGB as it samples): a quarter of the memory and upload of float pixels, and
    no decode on the CPU (CesiumMan's 2048² texture: 0.29 s of start-up before). Raises
    OSError when the asset cannot be read or decoded.
    """
    package = package_file(resolved_path)
    require_regular_file(package, "texture")
    try:
        status = os.stat(package)
        identity = (status.st_mtime_ns, status.st_size, status.st_ino)
    except OSError:
        identity = None  # not a local file: Ar reads it; cached by name
    return _decode_texture(resolved_path, color_space, identity)


@lru_cache(maxsize=32)
def _decode_texture(resolved_path: str, color_space: str, identity) -> TextureImage:
    """load_texture's decode, cached by the file's identity too."""
    from ..images.imagefiles import read_float_image

    asset = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(resolved_path))
    if asset is None:
        raise OSError(f"cannot open texture '{resolved_path}'")
    buffer = asset.GetBuffer() if asset.GetSize() else None
    if buffer is None:
        raise OSError(f"cannot decode texture '{resolved_path}': the file is empty")
    data = bytes(buffer)
    inner = resolved_path.rsplit("[", 1)[-1].rstrip("]")
    suffix = os.path.splitext(inner)[1] or ".png"
    # OIIO's Python bindings decode from files; a temporary file keeps Ar in charge of IO.
    with tempfile.NamedTemporaryFile(suffix=suffix, delete=False) as handle:
        handle.write(data)
        tmp = handle.name
    try:
        pixels, eight_bit = read_float_image(tmp, MAX_TEXTURE_SIZE, keep_8bit=True)
    except OSError as exc:
        # the decoder's words name the temporary copy: name the texture instead
        detail = str(exc).split(": ", 1)[-1].replace(tmp, resolved_path).replace(
            os.path.basename(tmp), os.path.basename(inner))
        raise OSError(f"cannot decode texture '{resolved_path}': {detail}") from None
    finally:
        os.unlink(tmp)
    encoded_srgb = color_space == "sRGB" or (color_space != "raw" and eight_bit)
    opaque = 255 if pixels.dtype == np.uint8 else 1.0
    rgba = np.full((pixels.shape[0], pixels.shape[1], 4), opaque, pixels.dtype)
    channels = pixels.shape[2]
    if channels >= 3:
        rgba[..., :3] = pixels[..., :3]
    else:
        rgba[..., :3] = pixels[..., :1]
    if channels in (2, 4):
        rgba[..., 3] = pixels[..., -1]
    rgba = np.ascontiguousarray(rgba[::-1])
    if eight_bit:
        return TextureImage(rgba, encoded_srgb)
    with np.errstate(invalid="ignore"):
        bad = int(np.count_nonzero(~(np.abs(rgba) <= 1e15)))
    if bad:  # NaN, Inf or beyond what scale and bias keep finite
        raise OSError(f"texture '{resolved_path}' has {bad:,} pixel value(s) that are NaN, "
                      "Inf or beyond +-1e15")
    if encoded_srgb:
        rgba[..., :3] = srgb_decode(rgba[..., :3])
    return TextureImage(rgba)


def corner_values(primvar: UsdGeom.Primvar, topology: Topology, time) -> np.ndarray | None:
    """A primvar as one value per triangle corner, (m, 3, c); None if unusable."""
    values = static_flattened(primvar, time)
    if values is None or len(values) == 0:
        return None
    arr = np.asarray(values, dtype=np.float32)
    arr = arr.reshape(len(arr), -1)
    interp = primvar.GetInterpolation()
    tri = topology.triangles
    if interp in ("vertex", "varying") and len(arr) == topology.num_points:
        return arr[tri]
    if interp == "faceVarying" and len(arr) > topology.corner_face_vertex.max(initial=-1):
        return arr[topology.corner_face_vertex]
    if interp == "uniform" and len(arr) > topology.triangle_face.max(initial=-1):
        return np.repeat(arr[topology.triangle_face][:, None, :], 3, axis=1)
    if interp == "constant":
        return np.broadcast_to(arr[0], (len(tri), 3, arr.shape[1])).copy()
    return None


def _resolve(shader: UsdShade.Shader, name: str, time):
    """An input's value, or the shader whose output feeds it: (value, source shader).

    UsdShade.Input.GetValueProducingAttributes follows connections through node-graph
    and material interface inputs to what really produces the value."""
    inp = shader.GetInput(name)
    if not inp:
        return None, None
    for attr in inp.GetValueProducingAttributes():
        if UsdShade.Output.IsOutput(attr):
            return None, UsdShade.Shader(attr.GetPrim())
        return static_value(attr, time), None
    return None, None


def _coordinates(prim: Usd.Prim, tex: UsdShade.Shader, topology: Topology, time):
    """(primvar name, corner values or None) of the texture coordinates a UsdUVTexture
    reads through its inputs:st (a UsdPrimvarReader_float2; ``st`` when unconnected)."""
    varname = "st"
    _, reader = _resolve(tex, "st", time)
    if reader is not None:
        name, _ = _resolve(reader, "varname", time)
        varname = str(name) if name else varname
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar(varname)
    st = corner_values(primvar, topology, time) if primvar else None
    if st is None or st.shape[-1] < 2:
        return varname, None
    return varname, np.ascontiguousarray(st[..., :2])


def _scale_bias(tex: UsdShade.Shader, time) -> tuple[np.ndarray, np.ndarray]:
    scale, _ = _resolve(tex, "scale", time)
    bias, _ = _resolve(tex, "bias", time)
    scale = np.ones(4, np.float32) if scale is None else np.asarray(scale, np.float64)
    bias = np.zeros(4, np.float32) if bias is None else np.asarray(bias, np.float64)
    for name, value in (("scale", scale), ("bias", bias)):
        # a texel (at most 1e15 by load_texture) times scale, plus bias, stays finite in
        # float32, and an input that breaks it is named here, not as a frame's
        # "non-finite values"
        if not (np.all(np.isfinite(value)) and np.all(np.abs(value) <= 1e15)):
            raise UsdWrinkleError(f"UsdUVTexture inputs:{name} {tuple(value.tolist())} must "
                                  "be finite and within +-1e15", str(tex.GetPath()),
                                  f"inputs:{name}", frame_of(time))
    return scale.astype(np.float32), bias.astype(np.float32)


def _color_space(tex: UsdShade.Shader, time) -> str:
    value, _ = _resolve(tex, "sourceColorSpace", time)
    return str(value) if value in ("raw", "sRGB") else "auto"


def _texture(prim: Usd.Prim, tex: UsdShade.Shader, topology: Topology, time):
    """(texture pixels, corner st, scale, bias) of a UsdUVTexture, or Nones when it cannot
    be used (with a warning: the mesh then renders untextured)."""
    scale, bias = _scale_bias(tex, time)
    file_value, _ = _resolve(tex, "file", time)
    if file_value is None:
        return None, None, scale, bias
    if not file_value.resolvedPath:
        _log.warning(f"texture '{file_value.path}' not found; rendering untextured "
                     f"({prim.GetPath()})")
        return None, None, scale, bias
    try:
        texture = load_texture(file_value.resolvedPath, _color_space(tex, time))
    except OSError as exc:
        _log.warning(f"{exc}; rendering untextured ({prim.GetPath()})")
        return None, None, scale, bias
    varname, st = _coordinates(prim, tex, topology, time)
    if st is None:
        _log.warning(f"texture coordinates '{varname}' missing; rendering untextured "
                     f"({prim.GetPath()})")
        return None, None, scale, bias
    return texture, st, scale, bias


def _file_attribute(tex: UsdShade.Shader):
    """The attribute that produces a UsdUVTexture's inputs:file (through material
    interface inputs), or None."""
    inp = tex.GetInput("file")
    if not inp:
        return None
    for attr in inp.GetValueProducingAttributes():
        return None if UsdShade.Output.IsOutput(attr) else attr
    return None


def _anchor_layer(attr: Usd.Attribute, time):
    """The layer whose opinion gives ``attr`` its value at ``time`` (relative asset
    paths, and UDIM patterns, are anchored there)."""
    for spec in attr.GetPropertyStack(time):
        if spec.HasDefaultValue() or spec.layer.ListTimeSamplesForPath(spec.path):
            return spec.layer
    return None


def _tiles(file_value, attr, time) -> list[tuple[int, str]]:
    """[(tile, resolved path)] of a texture file: one (tile -1) or a UDIM set's tiles."""
    if not UsdShade.UdimUtils.IsUdimIdentifier(file_value.path):
        return [(-1, file_value.resolvedPath)] if file_value.resolvedPath else []
    layer = _anchor_layer(attr, time)
    if layer is None:
        return []
    tiles = []
    for resolved, number in UsdShade.UdimUtils.ResolveUdimTilePaths(file_value.path, layer):
        tiles.append((int(number) - 1001, str(resolved)))
    return tiles


def read_normal_map(prim: Usd.Prim, topology: Topology, time,
                    shader: UsdShade.Shader | None = None) -> tuple:
    """(NormalMapRecord or None, whether its file is time-sampled) of a mesh's bound
    UsdPreviewSurface inputs:normal, when a UsdUVTexture feeds it."""
    if shader is None:
        shader = bound_surface(prim)[1]
    if not shader:
        return None, False
    _, tex = _resolve(shader, "normal", time)
    if tex is None:
        return None, False
    where = prim.GetPath()
    if tex.GetIdAttr().Get() != "UsdUVTexture":
        _log.warning(f"inputs:normal comes from a {tex.GetIdAttr().Get()} shader, not a "
                     f"UsdUVTexture; the normal map is ignored ({where})")
        return None, False
    attr = _file_attribute(tex)
    file_value = static_value(attr, time) if attr else None
    if file_value is None or not file_value.path:
        return None, False
    varies = attr.ValueMightBeTimeVarying()
    tiles = _tiles(file_value, attr, time)
    if not tiles:
        _log.warning(f"normal map '{file_value.path}' not found; rendered without it ({where})")
        return None, varies
    outside = [tile for tile, _ in tiles if not -1 <= tile < UDIM_TILES]
    if outside:
        _log.warning(f"normal map '{file_value.path}': UDIM tiles beyond "
                     f"{1000 + UDIM_TILES} are not drawn ({where})")
    color_space = _color_space(tex, time)
    loaded = []
    try:
        for tile, resolved in tiles:
            if -1 <= tile < UDIM_TILES:
                loaded.append((tile, load_texture(resolved, color_space)))
    except OSError as exc:
        _log.warning(f"{exc}; rendered without the normal map ({where})")
        return None, varies
    if len({pixels.shape for _, pixels in loaded}) > 1:
        _log.warning(f"normal map '{file_value.path}': its UDIM tiles differ in size; rendered "
                     f"without it ({where})")
        return None, varies
    varname, st = _coordinates(prim, tex, topology, time)
    if st is None:
        _log.warning(f"texture coordinates '{varname}' of the normal map missing; rendered without "
                     f"it ({where})")
        return None, varies
    scale, bias = _scale_bias(tex, time)
    key = "|".join(resolved for _, resolved in tiles) + f"|{color_space}"
    return NormalMapRecord(tuple(loaded), st, scale, bias, key), varies


def display_color(prim: Usd.Prim, time) -> np.ndarray:
    """The mesh's first displayColor (linear), or the neutral clay DEFAULT_COLOR."""
    display = UsdGeom.PrimvarsAPI(prim).GetPrimvar("displayColor")
    value = static_flattened(display, time) if display and display.HasValue() else None
    return np.asarray(value[0], np.float32) if value is not None and len(value) else \
        DEFAULT_COLOR


def display_opacity(prim: Usd.Prim, time) -> float:
    """The mesh's first displayOpacity, else 1."""
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar("displayOpacity")
    value = static_flattened(primvar, time) if primvar and primvar.HasValue() else None
    return float(value[0]) if value is not None and len(value) else 1.0


#: UsdPreviewSurface inputs read as constants -> SurfaceParams field
SURFACE_INPUTS = {"emissiveColor": "emissive_color",
                  "useSpecularWorkflow": "use_specular_workflow",
                  "specularColor": "specular_color", "metallic": "metallic",
                  "roughness": "roughness", "clearcoat": "clearcoat",
                  "clearcoatRoughness": "clearcoat_roughness", "opacity": "opacity",
                  "opacityThreshold": "opacity_threshold", "ior": "ior",
                  "occlusion": "occlusion"}


def surface_params(shader: UsdShade.Shader, prim: Usd.Prim, time) -> SurfaceParams:
    """A UsdPreviewSurface's constant inputs; one that a texture (or another shader)
    drives keeps its fallback, with a warning naming it."""
    values = {}
    for name, field in SURFACE_INPUTS.items():
        value, source = _resolve(shader, name, time)
        if source is not None:
            _log.warning(f"inputs:{name} comes from a {source.GetIdAttr().Get() or 'shader'}; "
                         f"usdwrinkle reads it as the constant {getattr(SurfaceParams, field)} "
                         f"({prim.GetPath()})")
            continue
        if value is None:
            continue
        if isinstance(getattr(SurfaceParams, field), tuple):
            values[field] = tuple(float(v) for v in value)
        elif field == "use_specular_workflow":
            values[field] = bool(int(value))
        else:
            values[field] = float(value)
    return SurfaceParams(**values)


def look_inputs(shader: UsdShade.Shader) -> tuple:
    """A UsdPreviewSurface's inputs as a network of another render context needs them:
    ((name, "value", value) for an authored constant, (name, "texture", (resolved file,
    wrapS, wrapT, sourceColorSpace, texture coordinates' primvar, output name, scale,
    bias)) for one a UsdUVTexture feeds), in PREVIEW_SURFACE_TYPES order; other sources are left
    out (the network keeps their fallback). Read at the default time."""
    time = Usd.TimeCode.Default()
    found = []
    for name in PREVIEW_SURFACE_TYPES:
        inp = shader.GetInput(name)
        if not inp:
            continue
        value, source = _resolve(shader, name, time)
        if source is None:
            if value is not None:
                found.append((name, "value", tuple(np.ravel(np.asarray(value, np.float64))
                                                   .tolist())))
            continue
        if source.GetIdAttr().Get() != "UsdUVTexture":
            continue
        file_value, _ = _resolve(source, "file", time)
        if file_value is None or not file_value.resolvedPath:
            continue
        output = next((attr.GetBaseName() for attr in inp.GetValueProducingAttributes()
                       if UsdShade.Output.IsOutput(attr)), "rgb")
        wrap = [str(_resolve(source, f"wrap{axis}", time)[0] or "useMetadata") for axis in "ST"]
        varname = "st"
        _, reader = _resolve(source, "st", time)
        if reader is not None:
            reader_name, _ = _resolve(reader, "varname", time)
            varname = str(reader_name) if reader_name else varname
        scale, bias = _scale_bias(source, time)
        found.append((name, "texture", (str(file_value.resolvedPath), wrap[0], wrap[1],
                                        _color_space(source, time), varname, output,
                                        tuple(float(v) for v in scale),
                                        tuple(float(v) for v in bias))))
    return tuple(found)


def bound_surface(prim: Usd.Prim, purpose: str = UsdShade.Tokens.allPurpose):
    """(the mesh's bound Material or None, its UsdPreviewSurface or None), for the material
    ``purpose`` (a purpose's own binding, else the all-purpose one)."""
    from ..usd.diagnostics import usd_diagnostics

    with usd_diagnostics(forward=True):  # e.g. bindings without MaterialBindingAPI
        material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial(purpose)
    if not material:
        return None, None
    shader = material.ComputeSurfaceSource()[0]
    if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
        return material, None
    return material, shader


def corner_colors(prim: Usd.Prim, name: str, topology: Topology, time):
    """(colours per triangle corner (m, 3, 3) float32, time-sampled) of the colour
    primvar ``name``, or None where it has no usable value."""
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar(name)
    if not primvar or not primvar.HasValue():
        return None
    values = corner_values(primvar, topology, time)
    if values is None or values.shape[-1] < 3 or not np.all(np.isfinite(values[..., :3])):
        return None
    return (np.ascontiguousarray(values[..., :3], np.float32),
            primvar.ValueMightBeTimeVarying())


def _primvar_reader(source: UsdShade.Shader):
    """(primvar name, fallback colour or None) of a UsdPrimvarReader_float3 (or _float4)
    node that feeds diffuseColor, or None for any other source (a texture)."""
    shader_id = source.GetIdAttr().Get() if source.GetIdAttr() else None
    if shader_id not in ("UsdPrimvarReader_float3", "UsdPrimvarReader_float4"):
        return None
    varname = source.GetInput("varname")
    name = varname.Get() if varname else None
    if not name:
        return None
    fallback = source.GetInput("fallback")
    value = fallback.Get() if fallback else None
    return str(name), (None if value is None else np.asarray(value, np.float32)[:3])


def _per_corner(colors) -> dict:
    """MaterialRecord fields of a per-corner colour (a non-constant one only)."""
    if colors is None:
        return {}
    values, varies = colors
    flat = values.reshape(-1, 3)
    if not varies and (len(flat) == 0 or np.all(flat == flat[0])):
        return {}  # one colour: the constant diffuse colour does it
    return {"corner_colors": values, "color_varies": varies}


def read_material(prim: Usd.Prim, topology: Topology, time) -> MaterialRecord:
    """Resolve the bound material of a mesh into a MaterialRecord: UsdPreviewSurface's
    diffuseColor, constant or from a UsdUVTexture, its normal map and its other inputs;
    without a UsdPreviewSurface, displayColor and displayOpacity for Storm's fallback
    surface (an empty displayColor is Storm's 0.5 grey). The binding is the preview
    purpose's where there is one, as usdview's Storm resolves it."""
    material, shader = bound_surface(prim, UsdShade.Tokens.preview)
    if shader is None:
        per_corner = _per_corner(corner_colors(prim, "displayColor", topology, time))
        if per_corner:  # Storm shades each corner's displayColor
            return MaterialRecord(np.ones(3, np.float32), color_primvar="displayColor",
                                  opacity=display_opacity(prim, time), **per_corner)
        color = display_color(prim, time)
        if color is DEFAULT_COLOR:
            color = FALLBACK_DISPLAY_COLOR
        return MaterialRecord(np.asarray(color, np.float32)[:3],
                              opacity=display_opacity(prim, time))
    surface = surface_params(shader, prim, time)
    normal_map, varies = read_normal_map(prim, topology, time, shader)
    maps = bool(material.GetInput(MAP_INPUTS["normal"]))
    value, source = _resolve(shader, "diffuseColor", time)
    if source is None:
        color = PREVIEW_DIFFUSE_FALLBACK if value is None else value
        return MaterialRecord(np.asarray(color, np.float32)[:3], normal_map=normal_map,
                              normal_map_varies=varies, wrinkle_maps=maps, surface=surface)
    reader = _primvar_reader(source)
    if reader is not None:  # diffuseColor from a primvar (UsdPrimvarReader_float3)
        name, fallback = reader
        colors = corner_colors(prim, name, topology, time)
        if colors is not None:
            values, colors_vary = colors
            return MaterialRecord(np.ones(3, np.float32), normal_map=normal_map,
                                  normal_map_varies=varies, wrinkle_maps=maps,
                                  surface=surface, corner_colors=values,
                                  color_primvar=name, color_varies=colors_vary)
        color = PREVIEW_DIFFUSE_FALLBACK if fallback is None else fallback
        return MaterialRecord(np.asarray(color, np.float32)[:3], normal_map=normal_map,
                              normal_map_varies=varies, wrinkle_maps=maps, surface=surface)
    texture, st, scale, bias = _texture(prim, source, topology, time)
    # untextured means a neutral clay, not the (often black) texture fallback
    color = DEFAULT_COLOR if texture is None else np.ones(3, np.float32)
    return MaterialRecord(np.asarray(color, np.float32)[:3], texture, st, scale, bias,
                          normal_map, varies, maps, surface)
