"""The materials that bind the wrinkle maps: UsdPreviewSurface, written into the bake layer.

For each mesh, a Material ``WrinkleMaterials/<mesh>``:

- references the material the mesh binds for that set's renderers (the full purpose's,
  or the preview purpose's for the preview set, each falling back to the all-purpose
  binding) when its surface is a UsdPreviewSurface inside it, so the rest of the look
  (diffuse texture, roughness, ...) is the original's, and later edits of the original
  flow through; otherwise it holds a plain UsdPreviewSurface with the mesh's displayColor;
- has ``inputs:wrinkleNormalFile`` (and ``wrinkleHeightFile``, ``wrinkleAmplitudeFile``)
  as interface inputs, time-sampled per frame, with the first frame's file as default;
- reads the normal map through a UsdUVTexture (sourceColorSpace raw, scale (2, 2, 2, 1),
  bias (-1, -1, -1, 0), wrapS/wrapT repeat, or clamp for UDIM sets) into the surface's
  ``inputs:normal``; the height map into ``inputs:displacement`` only when asked
  (``--map-displacement``: Storm displaces the coarse corners and keeps their normals,
  which streaks); the amplitude map is named on the material only (a mask to composite
  with, no UsdPreviewSurface input takes it).

The mesh's ``material:binding`` is overridden to the new material; a second map set made
for usdview's Storm (maps/options.MapSet "preview": ``WrinkleMaterials/<mesh>_preview``)
is bound as ``material:binding:preview``, which Storm resolves first and final renderers
ignore. Written with the Sdf API into the bake's layer, from what the scene read of the
mesh's materials before the first frame (scene/overrides.MeshFacts): the source stage is
neither read here nor edited.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

from pxr import Sdf

from ..outputs.layers import attribute_spec, bind_material, define_prim
from ..usd.schema import MAP_INPUTS
from .files import PARALLAX_FILES

_log = logging.getLogger(__name__)

SCOPE = "WrinkleMaterials"
#: map kind -> (material interface input, texture shader name, its output, surface input)
TEXTURES = {
    "normal": (MAP_INPUTS["normal"], "WrinkleNormalTexture", ("rgb", "float3"),
               ("normal", "normal3f")),
    "height": (MAP_INPUTS["height"], "WrinkleHeightTexture", ("r", "float"),
               ("displacement", "float")),
    "amplitude": (MAP_INPUTS["amplitude"], None, None, None),
    # read by the MaterialX network only (maps/mtlx.py)
    **{kind: (MAP_INPUTS[kind], None, None, None) for kind in ("parallaxN", "parallaxS",
                                                              "parallaxT")},
}
READER = "WrinkleUV"
VALUE_TYPES = Sdf.ValueTypeNames


def material_path(default_prim: str | None, mesh_path: str, stem: str) -> Sdf.Path:
    """Under the stage's default prim (its path, or None) when the mesh is inside it (a
    reference to the layer then brings the material along), else at the root."""
    mesh = Sdf.Path(mesh_path)
    if default_prim and mesh.HasPrefix(Sdf.Path(default_prim)) and mesh != Sdf.Path(
            default_prim):
        return Sdf.Path(default_prim).AppendChild(SCOPE).AppendChild(stem)
    return Sdf.Path.absoluteRootPath.AppendChild(SCOPE).AppendChild(stem)


def _shader(layer: Sdf.Layer, path: Sdf.Path, shader_id: str) -> Sdf.PrimSpec:
    spec = define_prim(layer, path, "Shader")
    attribute_spec(spec, "info:id", VALUE_TYPES.Token, shader_id, uniform=True)
    return spec


@dataclass(frozen=True)
class MaterialTarget:
    """One mesh's wrinkle material: the mesh (scene/overrides.MeshFacts), the material's
    path (material_path), its map files (kind -> [(frame, asset path)], frames in order;
    NaN: default only), and whether they are UDIM sets (a tile's edge is clamped; one
    texture repeats)."""

    mesh: object
    path: Sdf.Path
    files: dict
    udim: bool = False
    #: the texture coordinates the maps are laid out in (the primvar the reader reads)
    st: str = "st"
    #: the material purpose it is bound for (maps/options.MapSet): "all", "full" (the
    #: all-purpose binding only) or "preview"
    purpose: str = "all"
    #: the bake layer's path (the MaterialX network names the look's textures relative
    #: to it)
    layer_path: str = ""
    #: the parallax maps (laid out in ``st`` whatever the set's layout) are UDIM sets
    parallax_udim: bool = False


def author_islands(layer: Sdf.Layer, mesh_path: str, face_uv) -> None:
    """The islands layout on the mesh: ``primvars:wrinkleMapST``, texCoord2f[],
    faceVarying, one value per face corner (static: made from the rest pose)."""
    from pxr import Vt

    from ..usd.schema import MAP_ST

    attribute_spec(Sdf.CreatePrimInLayer(layer, Sdf.Path(mesh_path)), f"primvars:{MAP_ST}",
                   VALUE_TYPES.TexCoord2fArray, Vt.Vec2fArray.FromNumpy(face_uv),
                   interpolation="faceVarying")


def author_material(layer: Sdf.Layer, target: MaterialTarget, options) -> None:
    """Write ``target``'s material and bind it to the mesh. ``options``
    (maps.options.MapOptions): whether the height map is also bound to
    ``inputs:displacement``."""
    mesh, path, files, udim = target.mesh, target.path, target.files, target.udim
    mesh_path, uv_name, displacement = mesh.path, target.st, options.displacement
    # the look this set's renderers would resolve without the bake: the preview set the
    # preview purpose's material, the others the full purpose's (each falling back to the
    # all-purpose one)
    look = mesh.look_for("preview" if target.purpose == "preview" else "full")
    source_material = Sdf.Path(look.material) if look.material else None
    source_surface = Sdf.Path(look.surface) if look.surface else None
    scope = Sdf.CreatePrimInLayer(layer, path.GetParentPath())
    if not scope.typeName:
        scope.specifier = Sdf.SpecifierDef
        scope.typeName = "Scope"
    material = define_prim(layer, path, "Material")
    if source_surface is not None:
        material.referenceList.Prepend(Sdf.Reference(primPath=source_material))
        surface = path.AppendPath(source_surface.MakeRelativePath(source_material))
        surface_spec = Sdf.CreatePrimInLayer(layer, surface)
        if look.normal_mapped:
            _log.warning(f"the mesh's material has a normal map; the wrinkle normal map replaces "
                         f"it ({mesh_path})")
        look_inputs = look.inputs
    else:
        look_inputs = (("diffuseColor", "value", tuple(float(c) for c in mesh.display_color)),)
        if source_material is not None:
            _log.warning(f"the mesh's material {source_material} has no UsdPreviewSurface; the "
                         f"wrinkle material is a plain UsdPreviewSurface ({mesh_path})")
        surface = path.AppendChild("PreviewSurface")
        surface_spec = _shader(layer, surface, "UsdPreviewSurface")
        attribute_spec(surface_spec, "inputs:diffuseColor", VALUE_TYPES.Color3f,
                       mesh.display_color)
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
            if frame is not None:
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
    if all(kind in files for kind in PARALLAX_FILES):
        from .mtlx import author_network

        author_network(layer, path, look_inputs, options.uv,
                       "clamp" if target.parallax_udim else "periodic", target.layer_path)
    if target.purpose == "preview":
        bind_material(layer, mesh_path, path, purpose="preview")
        return
    bind_material(layer, mesh_path, path)
    # where the mesh binds another material for a purpose (preview: usdview's Storm
    # resolves it first; full: final renderers and Blender's importer do), the maps are
    # bound for it too; the preview purpose only when no set is made for it
    for purpose in ("full",) + (("preview",) if target.purpose == "all" else ()):
        if purpose in mesh.looks:
            bind_material(layer, mesh_path, path, purpose=purpose)
