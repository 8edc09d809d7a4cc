"""``bake --maps``: per frame, each wrinkled mesh's wrinkle maps, and the materials that
bind them (maps/raster.py on the GPU, maps/files.py for the files, maps/material.py for
the layer). The frames come from the bake's loop (frameloop.bake_layer), so a map is made
from exactly the fields the bake writes as primvars.
"""
from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field, replace

import numpy as np

from ..outputs.sink import BakeScene
from ..outputs.writer import FrameWriter
from ..process.errors import UsdWrinkleError
from ..process.memory import require_memory
from ..usd.schema import MAP_ST
from .files import (
    MAP_KINDS,
    PARALLAX_FILES,
    PIXELS,
    MapStaging,
    encode_map,
    file_kinds,
    frame_token,
    map_file_name,
    mesh_file_names,
    relative_asset,
    tile_file_name,
    udim_number,
    uv_tiles,
)
from .islands import MIN_ISLAND, island_layout
from .options import MapOptions, MapSet
from .raster import MapRasterizer
from .tangents import (
    blender_vertex_normals,
    corner_groups,
    mikktspace,
    mikktspace_triangles,
)

_log = logging.getLogger(__name__)

#: the smallest map side; at most the GPU's GL_MAX_TEXTURE_SIZE
MIN_MAP_SIZE = 16
MAX_PADDING = 256
#: one map target's bytes per texel (RGBA float, maps/raster.py), and the most one target
#: may hold: Mesa's llvmpipe refuses a framebuffer of 2 GiB or more as incomplete (measured:
#: --map-size 11600 exited 3), and GL offers no query for it
TARGET_BYTES_PER_TEXEL = 16
MAX_TARGET_BYTES = 2**31
#: bytes per texel: two float targets, their read-back copies, the planes handed to the
#: writer (up to two frames in flight) and the encoded ones
BYTES_PER_TEXEL = 2 * 16 + 2 * 16 + 2 * 16 + 16
#: and per texel of the parallax maps: a second rasteriser's five targets, their read-back
#: copies, and three planes in flight
PARALLAX_BYTES_PER_TEXEL = 5 * 16 + 5 * 16 + 3 * 2 * 12
#: a texel covered more than once over this fraction of a tile's islands gets a warning
OVERLAP_WARNING = 0.002


def check_map_options(options: MapOptions, max_texture_size: int | None = None) -> None:
    """Refuse sizes and paddings out of range, and maps the memory cannot hold."""
    limit = max_texture_size or 16384
    if not MIN_MAP_SIZE <= options.size <= limit:
        raise UsdWrinkleError(f"`map_size` must be in {MIN_MAP_SIZE}..{limit} "
                              f"(got {options.size})")
    if not 0 <= options.padding <= MAX_PADDING:
        raise UsdWrinkleError(f"`map_padding` must be in 0..{MAX_PADDING} "
                              f"(got {options.padding})")
    target = options.size * options.size * TARGET_BYTES_PER_TEXEL
    if target >= MAX_TARGET_BYTES:
        largest = int((MAX_TARGET_BYTES // TARGET_BYTES_PER_TEXEL) ** 0.5)
        raise UsdWrinkleError(f"`map_size` {options.size} needs render targets of "
                              f"{target / 2**30:.2f} GiB each; at most {largest} fits "
                              "the 2 GiB a GL target may hold (llvmpipe refuses larger)")
    per_texel = BYTES_PER_TEXEL + (PARALLAX_BYTES_PER_TEXEL if "parallax" in options.kinds
                                   else 0)
    require_memory(options.size * options.size * per_texel,
                   f"{options.size}x{options.size} maps need", "lower `map_size`")


@dataclass
class MeshMaps:
    """One mesh's plan for one map set (maps/options.MapSet): its file stem, UVs per
    triangle corner and UDIM tiles."""

    path: str
    stem: str
    corner_uv: np.ndarray
    tiles: list
    map_set: MapSet = MapSet("all", "triangle", None)
    #: kind -> [(frame, asset path)], frames in order
    files: dict = field(default_factory=dict)
    #: MikkTSpace's corner groups (maps/tangents.corner_groups), made on the first frame
    groups: tuple | None = None
    #: the islands layout per face corner (faceVarying, authored as primvars:wrinkleMapST),
    #: or None: the mesh's own texture coordinates
    face_uv: np.ndarray | None = None

    @property
    def udim(self) -> bool:
        return self.tiles != [(0, 0)]


class MapBake:
    """The bake sink of the wrinkle maps (outputs/sink.py): renders and stages each
    frame's maps of the scene's wrinkled meshes; :meth:`finish` writes the materials into
    the layer and :meth:`commit` moves the maps into their folder."""

    def __init__(self, scene: BakeScene, options: MapOptions):
        self.scene = scene
        self.options = options
        self.layer_path = scene.output
        self.folder = options.folder_for(scene.output)
        self.plans: list[MeshMaps] = []
        self.layer = None
        meshes = scene.meshes
        #: mesh path -> its file stem (the full set's, and its material's name)
        self.stems = mesh_file_names(meshes, getattr(scene.facts, "material_names", ()))
        if options.uv_named and meshes and options.layout != "islands" and \
                not any(self._own_uv(path) is not None for path in meshes):
            raise UsdWrinkleError(
                f"`uv` {options.uv}: no wrinkled mesh has texture coordinates of that name "
                f"({', '.join(sorted(meshes))}); name the meshes' own (st by default), or "
                "use `map_layout` islands")
        islands: dict[str, MeshMaps | None] = {}   # one layout per mesh, for every set
        for map_set in options.sets:
            for path in meshes:
                plan = self._plan(path, self.stems[path], map_set, islands)
                if plan is not None:
                    self.plans.append(plan)
        if meshes and not self.plans:
            raise UsdWrinkleError(
                f"no wrinkled mesh has the texture coordinates '{options.uv}' that `maps` "
                f"lays the maps out in ({', '.join(sorted(meshes))}): author them, pass "
                "`uv` with the name of the mesh's texture coordinates, or use `map_layout` "
                "islands")
        for path in dict.fromkeys(plan.path for plan in self.plans):
            facts = scene.facts.meshes.get(path)
            if facts is not None and getattr(facts, "stronger_ancestor", None):
                _log.warning(f"the wrinkle maps' material bound to {path} never resolves: "
                             f"{facts.stronger_ancestor} binds its material with "
                             "bindMaterialAs = strongerThanDescendants, which wins over the "
                             "mesh's own binding; bind the maps' material there, or make "
                             "that binding weakerThanDescendants")
        #: path -> the mesh's parallax maps (one set per mesh, in its own UVs)
        self.parallax = self._parallax_plans()
        self._rasterizer: MapRasterizer | None = None
        self._parallax_rasterizer: MapRasterizer | None = None
        self._staging: MapStaging | None = None
        self._writer: FrameWriter | None = None
        self._checked_overlap: set[tuple] = set()
        for name in self.file_names(list(scene.frames)):
            if scene.facts.inputs.protects(name):
                raise UsdWrinkleError(f"wrinkle map '{name}' would overwrite a file the stage "
                                      "reads (choose another `map_dir`)")

    def uv_name(self, plan: MeshMaps) -> str:
        """The texture coordinates ``plan``'s maps are laid out in."""
        return MAP_ST if plan.face_uv is not None else self.options.uv

    def _plan(self, path: str, stem: str, map_set: MapSet, islands: dict) -> MeshMaps | None:
        """``path``'s plan for ``map_set``: in the mesh's UVs, or in islands (made once per
        mesh, ``islands``: path -> plan, and shared by the sets that use them); None
        where the mesh gets no maps of that set. Where the islands do not fit the map,
        the preview set is laid out in the mesh's UVs instead (a default bake that did
        without islands before does not fail for them)."""
        options = self.options
        corner_uv = None if map_set.layout == "islands" else self._own_uv(path)
        if corner_uv is not None:
            plan = self._asset_plan(path, stem, corner_uv)
        elif map_set.layout == "asset":
            _log.warning(f"mesh has no texture coordinates '{options.uv}' (`uv`); no "
                         f"wrinkle maps for it (`map_layout` islands needs none) ({path})")
            return None
        else:
            if map_set.layout is None:
                _log.warning(f"mesh has no texture coordinates '{options.uv}' (`uv`): its "
                             f"wrinkle maps are laid out in islands, primvars:{MAP_ST} "
                             f"({path})")
            try:
                if path not in islands:
                    islands[path] = self._island_plan(path, stem)
                plan = islands[path]
            except UsdWrinkleError:
                own = self._own_uv(path) if map_set.purpose == "preview" else None
                if own is None:
                    raise
                _log.warning(f"{len(self.scene.facts.meshes[path].face_counts)} faces leave "
                             f"islands too small on a {options.size}-texel map: the preview "
                             f"maps are laid out in '{options.uv}' instead (raise `map_size` "
                             f"for islands, which usdview's Storm decodes best) ({path})")
                plan = self._asset_plan(path, stem, own)
        if plan is None:
            return None
        return replace(plan, stem=map_set.file_stem(stem), map_set=map_set,
                       files={kind: [] for kind in self.kinds})

    @property
    def kinds(self) -> tuple[str, ...]:
        """The kinds of file each map set's maps are (the parallax maps are per mesh)."""
        return tuple(kind for kind in file_kinds(self.options.kinds)
                     if kind not in PARALLAX_FILES)

    def _parallax_plans(self) -> dict:
        """path -> the plan of a mesh's parallax maps (``parallax``): one set per mesh,
        whichever map sets it has, laid out in the texture coordinates its textures
        read (``uv``), which are continuous where the textures are; islands would jump
        at every face, and a renderer's filter across that jump draws a seam."""
        if "parallax" not in self.options.kinds:
            return {}
        plans = {}
        for path in dict.fromkeys(plan.path for plan in self.plans):
            own = self._own_uv(path)
            if own is None:
                _log.warning(f"mesh has no texture coordinates '{self.options.uv}' (`uv`) "
                             "for its textures to move with the folds; no parallax maps "
                             f"for it ({path})")
                continue
            plan = self._asset_plan(path, self.stems[path], own)
            plans[path] = replace(plan, files={kind: [] for kind in PARALLAX_FILES})
        return plans

    def _own_uv(self, path: str) -> np.ndarray | None:
        """The mesh's texture coordinates (--uv) per triangle corner, or None."""
        corner_uv = self.scene.corner_primvar(path, self.options.uv)
        if corner_uv is None or corner_uv.shape[-1] < 2:
            return None
        return np.ascontiguousarray(corner_uv[..., :2], np.float32)

    def _asset_plan(self, path: str, stem: str, corner_uv: np.ndarray) -> MeshMaps:
        tiles, outside = uv_tiles(corner_uv)
        if outside:
            _log.warning(f"{outside} triangle(s) have texture coordinates outside the UDIM "
                         f"tiles 1001..1100; their wrinkle maps are not written ({path})")
        return MeshMaps(path, stem, corner_uv, tiles)

    def _island_plan(self, path: str, stem: str) -> MeshMaps | None:
        """The islands layout of a mesh (maps/islands.py), from its rest pose."""
        record = self.scene.meshes[path]
        counts = self.scene.facts.meshes[path].face_counts
        topology = record.topology
        if not len(topology.triangles):
            return None
        try:
            face_uv, padding, typical = island_layout(
                record.rest_points, topology.triangles, topology.triangle_face,
                topology.corner_face_vertex, counts, self.options.size, self.options.padding)
        except ValueError as exc:
            raise UsdWrinkleError(f"{exc}: raise `map_size`, or use `map_layout` asset",
                                  path) from None
        if typical < MIN_ISLAND:
            _log.warning(f"{len(counts)} faces on a {self.options.size}-texel map: the wrinkle "
                         f"maps' islands are {typical:.0f} texels across and {padding} apart "
                         f"(raise `map_size`) ({path})")
        corner_uv = np.ascontiguousarray(face_uv[topology.corner_face_vertex], np.float32)
        return MeshMaps(path, stem, corner_uv, [(0, 0)], face_uv=face_uv)

    def file_names(self, frames: list[float]) -> list[str]:
        """Every map file the bake will write (to refuse overwriting an input)."""
        names = []
        for plan, kinds in [(plan, self.kinds) for plan in self.plans] + \
                [(plan, PARALLAX_FILES) for plan in self.parallax.values()]:
            for kind in kinds:
                for frame in frames:
                    name = map_file_name(plan.stem, kind, frame_token(frame), self.options.fmt,
                                         plan.udim)
                    names += [os.path.join(self.folder, tile_file_name(name, tile))
                              for tile in plan.tiles]
        return names

    def _start(self) -> None:
        if self._rasterizer is None:
            self._staging = MapStaging(self.folder)
            self._rasterizer = MapRasterizer(self.scene.ctx, self.options.size)
            if self.parallax:
                self._parallax_rasterizer = MapRasterizer(self.scene.ctx, self.options.size,
                                                          parallax=True)
            # frame f's maps encode while frame f + 1 computes and rasterises
            # (outputs/writer.py: OpenImageIO releases the GIL while it encodes)
            self._writer = FrameWriter(
                lambda path, item: encode_map(path, item[0], item[1], item[2]), threads=1,
                max_in_flight=2 * len(PIXELS))

    def begin(self, layer) -> None:
        self.layer = layer

    def add_frame(self, frame: float, fields: dict, resources: dict) -> None:
        """Render, encode and stage a frame's maps from each mesh's GPU tables."""
        if not self.plans:
            return
        self._start()
        token = frame_token(frame)
        for plan in self.plans:
            res = resources[plan.path]
            if (plan.path, plan.stem) not in self._checked_overlap:
                self._check_overlap(plan, res)
            self._record(plan, self.kinds, frame, token)
            if not self.kinds:  # parallax alone
                continue
            tangents = self._tangents(plan, res) \
                if plan.map_set.tangent_space == "mikktspace" else None
            for tile in plan.tiles:
                pixels = self._rasterizer.render(res, plan.corner_uv, tile,
                                                 self.options.padding, tangents, plan.stem)
                self._submit(plan, self.kinds, frame, token, tile, pixels)
        self._add_parallax(frame, token, resources)

    def _record(self, plan: MeshMaps, kinds, frame: float, token: str | None) -> None:
        """Name ``plan``'s files of ``kinds`` for ``frame`` (the material's time samples)."""
        for kind in kinds:
            name = map_file_name(plan.stem, kind, token, self.options.fmt, plan.udim)
            plan.files[kind].append(
                (frame, relative_asset(os.path.join(self.folder, name), self.layer_path)))

    def _submit(self, plan: MeshMaps, kinds, frame: float, token: str | None, tile,
                pixels) -> None:
        """Hand one tile's maps of ``kinds`` to the writer, into the staging folder."""
        for kind in kinds:
            name = tile_file_name(
                map_file_name(plan.stem, kind, token, self.options.fmt, plan.udim), tile)
            self._writer.submit(frame, self._staging.path(name),
                                (kind, getattr(pixels, PIXELS[kind]), self._staging.final(name)))

    def _add_parallax(self, frame: float, token: str | None, resources: dict) -> None:
        """Render, move to world space and stage a frame's parallax maps."""
        for path, plan in self.parallax.items():
            self._record(plan, PARALLAX_FILES, frame, token)
            for tile in plan.tiles:
                pixels = self._parallax_rasterizer.render(
                    resources[path], plan.corner_uv, tile, self.options.padding, None,
                    f"{plan.stem}.parallax")
                self._to_world(pixels, plan)
                self._submit(plan, PARALLAX_FILES, frame, token, tile, pixels)

    def _to_world(self, pixels, plan: MeshMaps) -> None:
        """The parallax maps from the mesh's local space into world space, in place: the
        bent normal and the st gradients (covectors of a local offset) both go through
        the inverse transpose, and the normal is made unit again. World space because
        renderers' MaterialX networks know the view and the frame there (Storm gives
        no object space: measured, its object-space normal was constant)."""
        to_world = self.scene.local_to_world(plan.path) \
            if self.scene.local_to_world is not None else np.eye(4)
        linear = np.asarray(to_world, np.float64)[:3, :3]
        try:
            covector = np.linalg.inv(linear).T.astype(np.float32)
        except np.linalg.LinAlgError:  # a scale of 0 flattens the mesh
            covector = np.linalg.pinv(linear).T.astype(np.float32)
        for image in (pixels.bent, pixels.hs, pixels.ht):
            image[...] = image @ covector
        length = np.linalg.norm(pixels.bent, axis=-1, keepdims=True)
        np.divide(pixels.bent, length, out=pixels.bent, where=length > 1e-12)

    def _tangents(self, plan: MeshMaps, res) -> tuple[np.ndarray, np.ndarray]:
        """This frame's MikkTSpace tangents per triangle corner, and the normals they are
        built about (maps/tangents.py): the shading normals the passes made, except on a
        mesh that authors none and is smooth (a subdivision mesh), where Blender makes its
        own, angle-weighted, and decodes the map about those; over the triangles
        mikktspace.c sums over (a quad split along its shorter diagonal)."""
        topology = res.record.topology
        corner_entry = res.normal_plan.corner_entry.reshape(-1)
        triangles = topology.triangles
        if plan.groups is None:
            plan.groups = corner_groups(triangles, corner_entry, plan.corner_uv)
        points = res.posed_points.read()[:, :3]
        normals = res.read_shading_normals()[corner_entry]
        if res.normal_plan.source == "smooth":
            facts = self.scene.facts.meshes[plan.path]
            counts = facts.face_counts
            indices = np.zeros(int(np.sum(counts)), np.int64)
            indices[topology.corner_face_vertex] = triangles
            drawn = np.zeros(len(counts), bool)
            drawn[topology.triangle_face] = True   # not holes
            own = blender_vertex_normals(points, counts, indices, drawn)[triangles.reshape(-1)]
            # Blender's importer turns a leftHanded mesh's winding, and so its normals
            left = facts.uniform.get("orientation") == "leftHanded"
            normals = -own if left else own
        ids = mikktspace_triangles(points, triangles, topology.triangle_face, plan.corner_uv)
        return mikktspace(points, triangles, normals, plan.corner_uv, plan.groups, ids), normals

    def _check_overlap(self, plan: MeshMaps, res) -> None:
        self._checked_overlap.add((plan.path, plan.stem))
        for tile in plan.tiles:
            fraction = self._rasterizer.overlap(res, plan.corner_uv, tile, plan.stem)
            if fraction > OVERLAP_WARNING:
                where = f" in UDIM tile {udim_number(tile)}" if plan.udim else ""
                _log.warning(f"texture coordinates '{self.uv_name(plan)}' overlap{where}: "
                             f"{100 * fraction:.1f}% of the map's texels lie under more than one "
                             f"triangle, and hold the wrinkles of only one of them ({plan.path})")

    def finish(self) -> dict:
        """Write each mesh's material and binding into the layer (maps/material.py);
        returns the layer's record of the maps."""
        from .material import MaterialTarget, author_islands, author_material, material_path

        facts = self.scene.facts
        authored = set()
        for plan in self.plans:
            path = plan.path
            if plan.face_uv is not None and path not in authored:
                author_islands(self.layer, path, plan.face_uv)
                authored.add(path)
            parallax = self.parallax.get(path)
            target = MaterialTarget(facts.meshes[path], material_path(
                facts.default_prim_path, path, plan.map_set.material_name(self.stems[path])),
                {**plan.files, **(parallax.files if parallax is not None else {})},
                plan.udim, self.uv_name(plan), plan.map_set.purpose, self.layer_path,
                parallax_udim=parallax is not None and parallax.udim)
            author_material(self.layer, target, self.options)
        return {"maps": self.metadata()}

    def commit(self) -> None:
        """Finish the encodes and move the staged maps into the map folder (before the
        layer is renamed)."""
        if self._staging is not None:
            self._writer.close()
            self._staging.commit()

    def metadata(self) -> dict:
        """The shared set's (the one set's, or final renderers') frame and islands; a
        second set's under its purpose."""
        def described(map_set: MapSet) -> dict:
            plans = [plan for plan in self.plans if plan.map_set == map_set]
            return {"meshes": ",".join(sorted(plan.path for plan in plans)),
                    "islands": ",".join(sorted(plan.path for plan in plans
                                               if plan.face_uv is not None)),
                    "tangentSpace": map_set.tangent_space}

        shared, *others = self.options.sets
        data = {"kinds": ",".join(self.options.kinds), "size": self.options.size,
                "folder": relative_asset(self.folder, self.layer_path),
                "format": self.options.fmt, "padding": self.options.padding,
                "uv": self.options.uv, **described(shared),
                "purpose": shared.purpose, "displacement": self.options.displacement}
        for map_set in others:
            data[map_set.purpose] = described(map_set)
        return data

    def release(self) -> None:
        """Free the GPU targets; staged maps not committed are removed."""
        if self._writer is not None:
            self._writer.shutdown()  # before the staging folder goes
        if self._staging is not None:
            self._staging.discard()
        for rasterizer in (self._rasterizer, self._parallax_rasterizer):
            if rasterizer is not None:
                rasterizer.release()
        self._rasterizer = self._parallax_rasterizer = None


__all__ = ["MAP_KINDS", "MapBake", "MapOptions", "check_map_options"]
