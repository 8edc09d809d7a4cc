"""What ``bake --maps`` and its options ask for (light: the CLI's help reads the defaults
without loading the bake)."""
from __future__ import annotations

import os
from dataclasses import dataclass

#: the --tangent-space choices
TANGENT_SPACES = ("triangle", "mikktspace")
#: the --map-layout choices
LAYOUTS = ("islands", "asset")


@dataclass(frozen=True)
class MapOptions:
    """What ``--maps`` and its options ask for."""

    kinds: tuple = ("normal",)
    size: int = 2048
    #: the map folder (default: ``<layer name>_maps`` beside the layer)
    folder: str | None = None
    fmt: str = "png"
    padding: int = 8
    uv: str = "st"
    #: also bind the height map to UsdPreviewSurface's inputs:displacement (opt-in: Storm
    #: and most real-time renderers displace the coarse corners and keep their normals)
    displacement: bool = False
    #: the tangent frame the normal maps are expressed in, recorded in the layer's
    #: metadata: "triangle" (per triangle, from dP/ds, as Storm and usdwrinkle decode
    #: them) or "mikktspace" (per vertex, interpolated, as Blender's Cycles and EEVEE,
    #: Unreal, Substance and glTF viewers decode them); docs/method.md has the trade-off
    tangent_space: str = "triangle"
    #: where the maps' texels lie: "islands" (one island per face, in texture coordinates
    #: of the bake's own, primvars:wrinkleMapST: no renderer reads a neighbouring face's
    #: texels, and each face's frame is continuous, which Storm decodes best;
    #: maps/islands.py) or "asset" (the mesh's own texture coordinates, ``uv``: the maps
    #: line up with its textures, and Blender's importer, which decodes a normal map in the
    #: mesh's first UV set whatever the texture reads, decodes them); None: asset, and
    #: islands for a mesh without ``uv``
    layout: str | None = None

    def folder_for(self, layer_path: str) -> str:
        if self.folder:
            return self.folder
        stem = os.path.splitext(os.path.basename(layer_path))[0]
        return os.path.join(os.path.dirname(os.path.abspath(layer_path)), f"{stem}_maps")
