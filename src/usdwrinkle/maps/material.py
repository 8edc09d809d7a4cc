"""The materials that bind the wrinkle maps: UsdPreviewSurface, written into the bake layer.

For each mesh, a Material ``WrinkleMaterials/<mesh>``:

- references the mesh's bound material when its surface is a UsdPreviewSurface inside
  it, so the rest of the look (diffuse texture, roughness, ...) is the original's, and
  later edits of the original flow through; otherwise it holds a plain UsdPreviewSurface
  with the mesh's displayColor;
- has ``inputs:wrinkleNormalFile`` (and ``wrinkleHeightFile``, ``wrinkleAmplitudeFile``)
  as interface inputs, time-sampled per frame, with the first frame's file as default;
- reads the normal map through a UsdUVTexture (sourceColorSpace raw, scale (2, 2, 2, 1),
  bias (-1, -1, -1, 0), wrapS/wrapT repeat, or clamp for UDIM sets) into the surface's
  ``inputs:normal``; the height map into ``inputs:displacement`` only when asked
  (``--map-displacement``: Storm displaces the coarse corners and keeps their normals,
  which streaks); the amplitude map is named on the material only (a mask to composite
  with, no UsdPreviewSurface input takes it).

The mesh's ``material:binding`` is overridden to the new material. Written with the Sdf
API into the bake's layer: the source stage is read, never edited.
"""
from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from pxr import Sdf, Usd, UsdShade

from ..outputs.layers import attribute_spec, bind_material, define_prim
from ..scene.material import bound_surface, display_color
from ..schema import MAP_INPUTS

_log = logging.getLogger(__name__)

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


def _shader(layer: Sdf.Layer, path: Sdf.Path, shader_id: str) -> Sdf.PrimSpec:
    spec = define_prim(layer, path, "Shader")
    attribute_spec(spec, "info:id", VALUE_TYPES.Token, shader_id, uniform=True)
    return spec


def _source_surface(prim: Usd.Prim):
    """(bound material path, its UsdPreviewSurface's path inside it) or Nones."""
    material, shader = bound_surface(prim)
    if not material:
        return None, None
    if shader is None or not shader.GetPath().HasPrefix(material.GetPath()):
        return material.GetPath(), None
    return material.GetPath(), shader.GetPath()


@dataclass(frozen=True)
class MaterialTarget:
    """One mesh's wrinkle material: the mesh, the material's path (material_path), its
    map files (kind -> [(frame, asset path)], frames in order; NaN: default only), and
    whether they are UDIM sets (a tile's edge is clamped; one texture repeats)."""

    mesh_path: str
    path: Sdf.Path
    files: dict
    udim: bool = False


def author_material(layer: Sdf.Layer, stage: Usd.Stage, target: MaterialTarget,
                    options) -> None:
    """Write ``target``'s material and bind it to the mesh. ``options``
    (maps.options.MapOptions): the UV primvar the maps are laid out in, and whether the
    height map is also bound to ``inputs:displacement``."""
    mesh_path, path, files, udim = target.mesh_path, target.path, target.files, target.udim
    uv_name, displacement = options.uv, options.displacement
    prim = stage.GetPrimAtPath(mesh_path)
    source_material, source_surface = _source_surface(prim)
    scope = Sdf.CreatePrimInLayer(layer, path.GetParentPath())
    if not scope.typeName:
        scope.specifier = Sdf.SpecifierDef
        scope.typeName = "Scope"
    material = define_prim(layer, path, "Material")
    if source_surface is not None:
        material.referenceList.Prepend(Sdf.Reference(primPath=source_material))
        surface = path.AppendPath(source_surface.MakeRelativePath(source_material))
        surface_spec = Sdf.CreatePrimInLayer(layer, surface)
        existing = UsdShade.Shader(stage.GetPrimAtPath(source_surface)).GetInput("normal")
        if existing and existing.HasConnectedSource():
            _log.warning(f"the mesh's material has a normal map; the wrinkle normal map replaces "
                         f"it ({mesh_path})")
    else:
        if source_material is not None:
            _log.warning(f"the mesh's material {source_material} has no UsdPreviewSurface; the "
                         f"wrinkle material is a plain UsdPreviewSurface ({mesh_path})")
        surface = path.AppendChild("PreviewSurface")
        surface_spec = _shader(layer, surface, "UsdPreviewSurface")
        attribute_spec(surface_spec, "inputs:diffuseColor", VALUE_TYPES.Color3f,
                   tuple(float(c) for c in display_color(prim, Usd.TimeCode.Default())))
        attribute_spec(surface_spec, "outputs:surface", VALUE_TYPES.Token)
        attribute_spec(material, "outputs:surface", VALUE_TYPES.Token,
                   connect=surface.AppendProperty("outputs:surface"))
    reader = path.AppendChild(READER)
    reader_spec = _shader(layer, reader, "UsdPrimvarReader_float2")
    attribute_spec(reader_spec, "inputs:varname", VALUE_TYPES.String, uv_name)
    attribute_spec(reader_spec, "outputs:result", VALUE_TYPES.Float2)
    for kind, frames in files.items():
        input_name, shader_name, output, surface_input = TEXTURES[kind]
        file_input = attribute_spec(material, f"inputs:{input_name}", VALUE_TYPES.Asset)
        file_input.default = Sdf.AssetPath(frames[0][1])  # readers that ignore time samples
        for frame, asset in frames:
            if not math.isnan(frame):
                layer.SetTimeSample(file_input.path, frame, Sdf.AssetPath(asset))
        if shader_name is None or (kind == "height" and not displacement):
            continue
        texture = path.AppendChild(shader_name)
        spec = _shader(layer, texture, "UsdUVTexture")
        attribute_spec(spec, "inputs:file", VALUE_TYPES.Asset, connect=file_input.path)
        attribute_spec(spec, "inputs:st", VALUE_TYPES.Float2,
                   connect=reader.AppendProperty("outputs:result"))
        attribute_spec(spec, "inputs:sourceColorSpace", VALUE_TYPES.Token, "raw")
        # the wrap the maps were made for: a seam across the 0/1 border reads the other
        # side (UsdUVTexture's fallback, "useMetadata", is a black border in Storm)
        wrap = "clamp" if udim else "repeat"
        attribute_spec(spec, "inputs:wrapS", VALUE_TYPES.Token, wrap)
        attribute_spec(spec, "inputs:wrapT", VALUE_TYPES.Token, wrap)
        if kind == "normal":  # stored as 0.5 n + 0.5
            attribute_spec(spec, "inputs:scale", VALUE_TYPES.Float4, (2.0, 2.0, 2.0, 1.0))
            attribute_spec(spec, "inputs:bias", VALUE_TYPES.Float4, (-1.0, -1.0, -1.0, 0.0))
        output_name, output_type = output
        attribute_spec(spec, f"outputs:{output_name}", getattr(VALUE_TYPES, output_type.title()))
        input_name, input_type = surface_input
        type_name = VALUE_TYPES.Normal3f if input_type == "normal3f" else VALUE_TYPES.Float
        attribute_spec(surface_spec, f"inputs:{input_name}", type_name,
                   connect=texture.AppendProperty(f"outputs:{output_name}"))
    bind_material(layer, mesh_path, path)
    preview, _ = UsdShade.MaterialBindingAPI(prim).ComputeBoundMaterial(UsdShade.Tokens.preview)
    if preview and (not source_material or preview.GetPath() != source_material):
        # the mesh binds another material for the preview purpose, which usdview's Storm
        # resolves first: the maps are bound for it too
        bind_material(layer, mesh_path, path, purpose="preview")
