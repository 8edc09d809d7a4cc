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
class MapSet:
    """One set of maps, in one tangent frame and layout, and the material purpose its
    material is bound for: "all" (the one set: every purpose), "full" (the all-purpose
    binding, which final renderers resolve: Blender's importer, for Cycles and EEVEE,
    takes ``material:binding:full`` if authored, else the all-purpose one) or "preview"
    (``material:binding:preview``, which usdview's Storm resolves first)."""

    purpose: str
    tangent_space: str
    #: "islands", "asset", or None: asset, islands for a mesh without the UVs
    layout: str | None

    @property
    def shared(self) -> bool:
        """The set final renderers see, named as the mesh alone."""
        return self.purpose in ("all", "full")

    def file_stem(self, stem: str) -> str:
        """``Sleeve`` (the shared set) or ``Sleeve.preview``: prim names hold no dot, so no
        mesh's stem is another set's."""
        return stem if self.shared else f"{stem}.{self.purpose}"

    def material_name(self, stem: str) -> str:
        return stem if self.shared else f"{stem}_{self.purpose}"


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
    #: ``uv`` was named (--uv): a name no wrinkled mesh has is a typo, refused, not a
    #: reason to fall back to islands (as an unnamed default's absence is)
    uv_named: bool = False
    #: also bind the height map to UsdPreviewSurface's inputs:displacement (opt-in: Storm
    #: and most real-time renderers displace the coarse corners and keep their normals)
    displacement: bool = False
    #: the tangent frame the normal maps are expressed in, recorded in the layer's
    #: metadata: "triangle" (per triangle, from dP/ds, as Storm and usdwrinkle decode
    #: them) or "mikktspace" (per vertex, interpolated, as Blender's Cycles and EEVEE,
    #: Unreal, Substance and glTF viewers decode them); docs/method.md has the trade-off.
    #: With neither this nor ``layout`` given, the bake writes a set per purpose (sets)
    tangent_space: str | None = None
    #: where the maps' texels lie: "islands" (one island per face, in texture coordinates
    #: of the bake's own, primvars:wrinkleMapST: no renderer reads a neighbouring face's
    #: texels, and each face's frame is continuous, which Storm decodes best;
    #: maps/islands.py) or "asset" (the mesh's own texture coordinates, ``uv``: the maps
    #: line up with its textures, and Blender's importer, which decodes a normal map in the
    #: mesh's first UV set whatever the texture reads, decodes them); None: asset, and
    #: islands for a mesh without ``uv``
    layout: str | None = None
    #: the default's second set, for usdview's Storm (off where the preview purpose
    #: shows bake --display-color's ramp instead)
    preview: bool = True

    @property
    def sets(self) -> tuple[MapSet, ...]:
        """The map sets the bake writes. By default two, each in what its renderers
        decode: for final renderers (the all-purpose binding) MikkTSpace maps in the
        asset's UVs, for usdview's Storm (the preview binding) per-triangle maps in
        islands. A tangent frame or layout chosen by hand gives one set, bound for every
        purpose."""
        if self.tangent_space is None and self.layout is None:
            full = MapSet("full", "mikktspace", None)
            return (full, MapSet("preview", "triangle", "islands")) if self.preview else (full,)
        return (MapSet("all", self.tangent_space or "triangle", self.layout),)

    def folder_for(self, layer_path: str) -> str:
        if self.folder:
            return self.folder
        stem = os.path.splitext(os.path.basename(layer_path))[0]
        return os.path.join(os.path.dirname(os.path.abspath(layer_path)), f"{stem}_maps")
