"""Materials: UsdPreviewSurface diffuseColor, constant or through UsdUVTexture.

Textures are opened through Ar, so a texture inside a .usdz package works; the
bytes are decoded by OpenImageIO. Texture coordinates become one value per
triangle corner, whatever the primvar's interpolation.
"""
from __future__ import annotations

import os
import tempfile
from functools import lru_cache

import numpy as np
from pxr import Ar, Usd, UsdGeom, UsdShade

from ..colour import srgb_decode, srgb_decode_8bit
from ..limits import MAX_TEXTURE_SIZE
from .inputs import package_file, require_regular_file
from .records import MaterialRecord
from .topology import Topology

DEFAULT_COLOR = np.array([0.6, 0.6, 0.6], np.float32)


@lru_cache(maxsize=32)
def load_texture(resolved_path: str) -> np.ndarray:
    """Decode an image asset into (h, w, 4) float32 linear RGBA, row 0 at the bottom.

    Raises OSError when the asset cannot be read or decoded.
    """
    from ..outputs.images import read_float_image

    require_regular_file(package_file(resolved_path), "texture")
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
        pixels, eight_bit = read_float_image(tmp, MAX_TEXTURE_SIZE)
    except OSError as exc:
        raise OSError(f"cannot decode texture '{resolved_path}': "
                      f"{str(exc).split(': ', 1)[-1]}") from None
    finally:
        os.unlink(tmp)
    encoded_srgb = eight_bit or suffix.lower() in (".jpg", ".jpeg", ".png")
    rgba = np.ones((pixels.shape[0], pixels.shape[1], 4), np.float32)
    channels = pixels.shape[2]
    if channels >= 3:
        rgba[..., :3] = pixels[..., :3]
    else:
        rgba[..., :3] = pixels[..., :1]
    if channels in (2, 4):
        rgba[..., 3] = pixels[..., -1]
    if encoded_srgb:  # 8-bit images are sRGB encoded (UsdUVTexture sourceColorSpace auto)
        c = rgba[..., :3]
        rgba[..., :3] = srgb_decode_8bit(c) if eight_bit else srgb_decode(c)
    return np.ascontiguousarray(rgba[::-1])


def corner_values(primvar: UsdGeom.Primvar, topology: Topology, time) -> np.ndarray | None:
    """A primvar as one value per triangle corner, (m, 3, c); None if unusable."""
    values = primvar.ComputeFlattened(time)
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
        return attr.Get(time), None
    return None, None


def _texture(prim: Usd.Prim, tex: UsdShade.Shader, topology: Topology, time, warn):
    """(texture pixels, corner st, scale, bias) of a UsdUVTexture, or Nones when it cannot
    be used (with a warning: the mesh then renders untextured)."""
    scale, _ = _resolve(tex, "scale", time)
    bias, _ = _resolve(tex, "bias", time)
    scale = np.ones(4, np.float32) if scale is None else np.asarray(scale, np.float32)
    bias = np.zeros(4, np.float32) if bias is None else np.asarray(bias, np.float32)
    varname = "st"
    _, reader = _resolve(tex, "st", time)
    if reader is not None:
        name, _ = _resolve(reader, "varname", time)
        varname = str(name) if name else varname
    file_value, _ = _resolve(tex, "file", time)
    if file_value is None:
        return None, None, scale, bias
    if not file_value.resolvedPath:
        warn(f"texture '{file_value.path}' not found; rendering untextured ({prim.GetPath()})")
        return None, None, scale, bias
    try:
        texture = load_texture(file_value.resolvedPath)
    except OSError as exc:
        warn(f"{exc}; rendering untextured ({prim.GetPath()})")
        return None, None, scale, bias
    primvar = UsdGeom.PrimvarsAPI(prim).GetPrimvar(varname)
    st = corner_values(primvar, topology, time) if primvar else None
    if st is None or st.shape[-1] < 2:
        warn(f"texture coordinates '{varname}' missing; rendering untextured "
             f"({prim.GetPath()})")
        return None, None, scale, bias
    return texture, np.ascontiguousarray(st[..., :2]), scale, bias


def _display_color(prim: Usd.Prim, time) -> np.ndarray:
    display = UsdGeom.PrimvarsAPI(prim).GetPrimvar("displayColor")
    value = display.ComputeFlattened(time) if display and display.HasValue() else None
    return np.asarray(value[0], np.float32) if value is not None and len(value) else \
        DEFAULT_COLOR


def read_material(prim: Usd.Prim, topology: Topology, time, warn) -> MaterialRecord:
    """Resolve the bound material of a mesh into a MaterialRecord: UsdPreviewSurface's
    diffuseColor, constant or from a UsdUVTexture; else displayColor."""
    material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
    shader = material.ComputeSurfaceSource()[0] if material else None
    if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
        return MaterialRecord(np.asarray(_display_color(prim, time), np.float32)[:3])
    value, source = _resolve(shader, "diffuseColor", time)
    if source is None:
        color = _display_color(prim, time) if value is None else value
        return MaterialRecord(np.asarray(color, np.float32)[:3])
    texture, st, scale, bias = _texture(prim, source, topology, time, warn)
    # untextured means a neutral clay, not the (often black) texture fallback
    color = DEFAULT_COLOR if texture is None else np.ones(3, np.float32)
    return MaterialRecord(np.asarray(color, np.float32)[:3], texture, st, scale, bias)
