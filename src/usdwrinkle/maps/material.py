"""The materials that bind the wrinkle maps: UsdPreviewSurface, written into the bake layer.

For each mesh, a Material ``WrinkleMaterials/<mesh>``:

- references the mesh's bound material when its surface is a UsdPreviewSurface inside
  it, so the rest of the look (diffuse texture, roughness, ...) is the original's, and
  later edits of the original flow through; otherwise it holds a plain UsdPreviewSurface
  with the mesh's displayColor;
- has ``inputs:wrinkleNormalFile`` (and ``wrinkleHeightFile``, ``wrinkleAmplitudeFile``)
  as interface inputs, time-sampled per frame, with the first frame's file as default;
- reads the normal map through a UsdUVTexture (sourceColorSpace raw, scale (2, 2, 2, 1),
  bias (-1, -1, -1, 0)) into the surface's ``inputs:normal``, the height map into
  ``inputs:displacement``; the amplitude map is named on the material only (a mask to
  composite with, no UsdPreviewSurface input takes it).

The mesh's ``material:binding`` is overridden to the new material. Written with the Sdf
API into the bake's layer: the source stage is read, never edited.
"""
from __future__ import annotations

import math

from pxr import Sdf, Usd, UsdGeom, UsdShade

from ..outputs.layers import bind_material
from ..schema import MAP_INPUTS

SCOPE = "WrinkleMaterials"
#: map kind -> (material interface input, texture shader name, its output, surface input)
TEXTURES = {
    "normal": (MAP_INPUTS["normal"], "WrinkleNormalTexture", ("rgb", "float3"),
               ("normal", "normal3f")),
    "height": (MAP_INPUTS["height"], "WrinkleHeightTexture", ("r", "float"),
               ("displacement", "float")),
    "amplitude": (MAP_INPUTS["amplitude"], None, None, None),
}
READER = "WrinkleUV"
VALUE_TYPES = Sdf.ValueTypeNames


def material_path(stage: Usd.Stage, mesh_path: str, stem: str) -> Sdf.Path:
    """Under the stage's default prim when the mesh is inside it (a reference to the
    layer then brings the material along), else at the root."""
    default = stage.GetDefaultPrim()
    mesh = Sdf.Path(mesh_path)
    if default and mesh.HasPrefix(default.GetPath()) and mesh != default.GetPath():
        return default.GetPath().AppendChild(SCOPE).AppendChild(stem)
    return Sdf.Path.absoluteRootPath.AppendChild(SCOPE).AppendChild(stem)


def _define(layer: Sdf.Layer, path: Sdf.Path, type_name: str) -> Sdf.PrimSpec:
    spec = Sdf.CreatePrimInLayer(layer, path)
    spec.specifier = Sdf.SpecifierDef
    spec.typeName = type_name
    return spec


def _attribute(prim_spec: Sdf.PrimSpec, name: str, type_name, value=None, connect=None):
    spec = prim_spec.attributes.get(name) or Sdf.AttributeSpec(prim_spec, name, type_name)
    if value is not None:
        spec.default = value
    if connect is not None:
        spec.connectionPathList.explicitItems = [connect]
    return spec


def _shader(layer: Sdf.Layer, path: Sdf.Path, shader_id: str) -> Sdf.PrimSpec:
    spec = _define(layer, path, "Shader")
    _attribute(spec, "info:id", VALUE_TYPES.Token, shader_id).SetInfo("variability",
                                                                       Sdf.VariabilityUniform)
    return spec


def _source_surface(prim: Usd.Prim):
    """(bound material path, its UsdPreviewSurface's path inside it) or Nones."""
    material, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial()
    if not material:
        return None, None
    shader = material.ComputeSurfaceSource()[0]
    if not shader or shader.GetIdAttr().Get() != "UsdPreviewSurface":
        return material.GetPath(), None
    if not shader.GetPath().HasPrefix(material.GetPath()):
        return material.GetPath(), None
    return material.GetPath(), shader.GetPath()


def _display_color(prim: Usd.Prim):
    display = UsdGeom.PrimvarsAPI(prim).GetPrimvar("displayColor")
    value = display.ComputeFlattened(Usd.TimeCode.Default()) if display and \
        display.HasValue() else None
    return tuple(float(c) for c in value[0]) if value is not None and len(value) else \
        (0.6, 0.6, 0.6)


def author_material(layer: Sdf.Layer, stage: Usd.Stage, mesh_path: str, path: Sdf.Path,
                    files: dict, uv_name: str, warn) -> None:
    """Write the material at ``path`` and bind it to the mesh.

    ``files``: map kind -> [(frame, asset path)], frames in order (NaN: default only).
    """
    prim = stage.GetPrimAtPath(mesh_path)
    source_material, source_surface = _source_surface(prim)
    scope = Sdf.CreatePrimInLayer(layer, path.GetParentPath())
    if not scope.typeName:
        scope.specifier = Sdf.SpecifierDef
        scope.typeName = "Scope"
    material = _define(layer, path, "Material")
    if source_surface is not None:
        material.referenceList.Prepend(Sdf.Reference(primPath=source_material))
        surface = path.AppendPath(source_surface.MakeRelativePath(source_material))
        surface_spec = Sdf.CreatePrimInLayer(layer, surface)
        existing = UsdShade.Shader(stage.GetPrimAtPath(source_surface)).GetInput("normal")
        if existing and existing.HasConnectedSource():
            warn(f"the mesh's material has a normal map; the wrinkle normal map replaces it "
                 f"({mesh_path})")
    else:
        if source_material is not None:
            warn(f"the mesh's material {source_material} has no UsdPreviewSurface; the "
                 f"wrinkle material is a plain UsdPreviewSurface ({mesh_path})")
        surface = path.AppendChild("PreviewSurface")
        surface_spec = _shader(layer, surface, "UsdPreviewSurface")
        _attribute(surface_spec, "inputs:diffuseColor", VALUE_TYPES.Color3f,
                   _display_color(prim))
        _attribute(surface_spec, "outputs:surface", VALUE_TYPES.Token)
        _attribute(material, "outputs:surface", VALUE_TYPES.Token,
                   connect=surface.AppendProperty("outputs:surface"))
    reader = path.AppendChild(READER)
    reader_spec = _shader(layer, reader, "UsdPrimvarReader_float2")
    _attribute(reader_spec, "inputs:varname", VALUE_TYPES.String, uv_name)
    _attribute(reader_spec, "outputs:result", VALUE_TYPES.Float2)
    for kind, frames in files.items():
        input_name, shader_name, output, surface_input = TEXTURES[kind]
        file_input = _attribute(material, f"inputs:{input_name}", VALUE_TYPES.Asset)
        file_input.default = Sdf.AssetPath(frames[0][1])  # readers that ignore time samples
        for frame, asset in frames:
            if not math.isnan(frame):
                layer.SetTimeSample(file_input.path, frame, Sdf.AssetPath(asset))
        if shader_name is None:
            continue
        texture = path.AppendChild(shader_name)
        spec = _shader(layer, texture, "UsdUVTexture")
        _attribute(spec, "inputs:file", VALUE_TYPES.Asset, connect=file_input.path)
        _attribute(spec, "inputs:st", VALUE_TYPES.Float2,
                   connect=reader.AppendProperty("outputs:result"))
        _attribute(spec, "inputs:sourceColorSpace", VALUE_TYPES.Token, "raw")
        if kind == "normal":  # stored as 0.5 n + 0.5
            _attribute(spec, "inputs:scale", VALUE_TYPES.Float4, (2.0, 2.0, 2.0, 1.0))
            _attribute(spec, "inputs:bias", VALUE_TYPES.Float4, (-1.0, -1.0, -1.0, 0.0))
        output_name, output_type = output
        _attribute(spec, f"outputs:{output_name}", getattr(VALUE_TYPES, output_type.title()))
        input_name, input_type = surface_input
        type_name = VALUE_TYPES.Normal3f if input_type == "normal3f" else VALUE_TYPES.Float
        _attribute(surface_spec, f"inputs:{input_name}", type_name,
                   connect=texture.AppendProperty(f"outputs:{output_name}"))
    bind_material(layer, mesh_path, path)
