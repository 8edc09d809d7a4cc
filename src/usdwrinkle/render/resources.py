"""GPU resources of one mesh: the tables the passes read and write.

Per-vertex, per-edge and per-triangle arrays live in *tables*: 2D float or int
textures TABLE_WIDTH texels wide, element i at texel (i % TABLE_WIDTH, i / TABLE_WIDTH).
Passes read them with texelFetch and write them with imageStore. On Mesa's llvmpipe a
texelFetch gather is about four times cheaper than the same SSBO load (each SSBO load
runs a per-lane loop with bounds checks; docs/benchmarks.md), and on a GPU a fetch
through the texture cache is at least as fast as a storage-buffer load.

Created when the topology is new or changed, reused every frame after that;
per-frame data is written into the existing tables.
"""
from __future__ import annotations

import numpy as np

from ..method.anchor import start_phases
from ..method.contract import COARSENING_MAX, JOINT_TEXELS, UDIM_REPEAT, UDIM_TILES, WrinkleFields
from ..process.errors import UsdWrinkleError
from ..process.limits import MAX_POINTS
from ..scene.records import MeshRecord
from ..scene.topology import rest_tangents, triangle_neighbors
from .bindings import TABLE_WIDTH
from .fields import WaveFields
from .mipmaps import build_mipmaps

#: relax.glsl stores neighbour indices as floats, exact below 2^24


#: the sized internal format of 8-bit sRGB textures with alpha
GL_SRGB8_ALPHA8 = 0x8C43


def vec4(points: np.ndarray, w: float | np.ndarray = 1.0) -> np.ndarray:
    """(n, 3) -> (n, 4) float32 (tables have 1, 2 or 4 components, never 3)."""
    out = np.empty((len(points), 4), np.float32)
    out[:, :3] = points
    out[:, 3] = w
    return out


def topology_block(topo) -> tuple[np.ndarray, dict]:
    """The int table of include/topology.glsl for a mesh's Topology (scene/topology.py)
    and the uniforms giving its part offsets."""
    parts = list(topo.rings())
    starts = np.concatenate([[0], np.cumsum([len(p) for p in parts])])
    uniforms = {"u_neighbor_indices_base": int(starts[1]),
                "u_triangle_offsets_base": int(starts[2]),
                "u_triangle_indices_base": int(starts[3])}
    return np.concatenate(parts).astype(np.int32), uniforms


def _hold(params, n: int) -> np.ndarray:
    """What held edges leave each point (scene.params.held_weights; zeros: nothing held)."""
    if params.hold is None:
        return np.zeros((n, 4), np.float32)
    return np.asarray(params.hold, np.float32)


def _coarsening(params, n: int) -> np.ndarray:
    """The most the mesh's compression coarsens each point's folds (folds.coarsening_cap;
    COARSENING_MAX everywhere where the record has none)."""
    if params.coarsening is None:
        return np.full((n, 1), COARSENING_MAX, np.float32)
    return np.asarray(params.coarsening, np.float32).reshape(n, 1)


def _anchor(record, tangents: np.ndarray | None = None) -> np.ndarray:
    """The waves' start phases (method/anchor.py: the paint's, else the curvature's), (n, 4).
    ``tangents``: the record's rest tangents where the caller has them already."""
    topology = record.topology
    if tangents is None:
        tangents = rest_tangents(record.rest_normals)
    return start_phases(record.rest_points, record.rest_normals, tangents,
                        topology.neighbor_offsets,
                        topology.neighbor_indices, record.params.q, record.params.width,
                        record.params.coarsening)


def _anchor_key(record) -> int:
    """What the start phases depend on beyond the topology: the rest pose, q, the width
    and the coarsening cap."""
    cap = record.params.coarsening
    return hash(tuple(np.ascontiguousarray(array).tobytes() for array in (
        record.rest_points, record.params.q, record.params.width,
        np.zeros(0) if cap is None else cap)))


def _bytes(array: np.ndarray) -> bytes:
    data = np.ascontiguousarray(array).tobytes()
    return data if data else b"\0" * 16  # GL buffers cannot be empty


class Table:
    """``count`` elements of 1, 2 or 4 float32 (or int32) components in a 2D texture.

    Element i is texel (i % TABLE_WIDTH, i // TABLE_WIDTH): shaders read it with
    ``FETCH(table, i)`` and write it with ``STORE(image, i, value)`` (common.glsl).
    """

    def __init__(self, ctx, count: int, components: int, dtype: str = "f4", data=None,
                 what: str = "table", path: str | None = None):
        import moderngl

        self.count = int(count)
        self.components = components
        self.dtype = np.dtype(np.int32 if dtype == "i4" else np.float32)
        rows = max(-(-self.count // TABLE_WIDTH), 1)
        max_rows = int(ctx.info.get("GL_MAX_TEXTURE_SIZE", 16384) or 16384)
        if rows > max_rows:
            raise UsdWrinkleError(
                f"mesh too large for the GPU: its {what} has {self.count:,} elements, "
                f"at most {TABLE_WIDTH * max_rows:,} fit ({TABLE_WIDTH} x "
                f"GL_MAX_TEXTURE_SIZE {max_rows})", path)
        self.texture = ctx.texture((TABLE_WIDTH, rows), components, dtype=dtype)
        self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)  # integer tables need it
        if data is not None:
            self.write(data)

    def write(self, array) -> None:
        """Write all ``count`` elements: whole rows in one upload, the rest in another."""
        flat = np.ascontiguousarray(array, dtype=self.dtype).reshape(-1)
        expected = self.count * self.components
        if flat.size != expected:
            raise ValueError(f"table of {self.count} x {self.components}: got {flat.size} values")
        full_rows, rest = divmod(self.count, TABLE_WIDTH)
        row_values = TABLE_WIDTH * self.components
        if full_rows:
            self.texture.write(flat[:full_rows * row_values].tobytes(),
                               viewport=(0, 0, TABLE_WIDTH, full_rows))
        if rest:
            self.texture.write(flat[full_rows * row_values:].tobytes(),
                               viewport=(0, full_rows, rest, 1))

    def read(self) -> np.ndarray:
        """The ``count`` elements, (count, components) (or (count,) for one component)."""
        data = np.frombuffer(self.texture.read(), self.dtype)[:self.count * self.components]
        return data.reshape(self.count, self.components) if self.components > 1 else data

    def use(self, unit: int) -> None:
        """Bind for reading (texelFetch) on texture unit ``unit``."""
        self.texture.use(location=unit)

    def bind_image(self, unit: int, read: bool = False) -> None:
        """Bind for writing (imageStore), and reading with imageLoad if ``read``."""
        self.texture.bind_to_image(unit, read=read, write=True)

    def release(self) -> None:
        self.texture.release()


class MeshResources:
    """All tables and buffers of one mesh on the GPU."""

    def __init__(self, ctx, record: MeshRecord):
        self.ctx = ctx
        self.record = record
        n = len(record.rest_points)
        if n >= MAX_POINTS:
            raise UsdWrinkleError(f"mesh too large: {n:,} points, usdwrinkle handles fewer "
                                  f"than {MAX_POINTS:,} per mesh", record.path, "points")
        self.num_points = n
        self.num_triangles = len(record.topology.triangles)
        self.num_edges = len(record.topology.rings()[1])  # the directed edges relax reads
        self.buffers = []
        self.tables = []
        self.textures = []
        #: tables the passes own (render/passes/base.Pass.table), by pass and name
        self.owned: dict[str, Table] = {}
        try:
            self._create(record)
        except BaseException:
            self.release()  # a table that does not fit must not leak the ones before it
            raise

    def _create(self, record: MeshRecord) -> None:
        n = self.num_points
        self.rest_points = self._table(n, 4, data=vec4(record.rest_points))
        self.posed_points = self._table(n, 4, data=vec4(record.rest_points))
        topo, self.topology_uniforms = topology_block(record.topology)
        self.topology = self._table(len(topo), 1, "i4", topo)
        # the three corners of each triangle in one texel (w unused)
        corners = np.zeros((self.num_triangles, 4), np.int32)
        corners[:, :3] = record.topology.triangles
        self.triangles = self._table(self.num_triangles, 4, "i4", corners)
        frame = np.empty((n, 2, 4), np.float32)
        frame[:, 0, :3] = record.rest_normals
        frame[:, 0, 3] = 0.0
        tangents = rest_tangents(record.rest_normals)
        frame[:, 1, :3] = tangents
        frame[:, 1, 3] = 0.0
        # [2i] = rest normal, [2i + 1] = rest tangent
        self.rest_frame = self._table(2 * n, 4, data=frame)
        self.q_width = self._table(n, 4, data=vec4(record.params.q, record.params.width))
        self.hold = self._table(n, 4, data=_hold(record.params, n))
        self.coarsening = self._table(n, 1, data=_coarsening(record.params, n))
        #: the waves' start phases (method/anchor.py: painted loops, gathered tubes)
        self.anchor = self._table(n, 4, data=_anchor(record, tangents))
        self._anchor_key = _anchor_key(record)
        #: the wave fields' ping-pong, phases and relax tables (render/fields.py)
        self.waves = WaveFields(n, self.num_edges, self._table, self._drop)
        self.corner_st = self._table(3 * self.num_triangles, 2,
                                     data=self._corner_st(record))  # [3t + c]
        #: colours per triangle corner ([3t + c], linear RGB) that multiply the diffuse
        #: colour: a per-vertex displayColor (MaterialRecord.corner_colors), else None
        self.corner_colors: Table | None = None
        self._set_corner_colors(record.material.corner_colors)
        #: a display override (the paint window's |q| and W ramps): colours per triangle
        #: corner ([3t + c], linear RGB) drawn instead of the material's colour and
        #: texture, the wrinkles and lights as they are; None: the material
        self.display_colors: Table | None = None
        #: the normal map's texture coordinates ([3t + c]), its tiles (a texture array)
        #: and their layers by UDIM tile (set_normal_map)
        self.normal_st = self._table(3 * self.num_triangles, 2)
        self.normal_map = None
        self.normal_map_record = None
        self.udim_layers = np.full(UDIM_TILES, -1, np.int32)
        self.face_normals = self._table(self.num_triangles, 4)
        self._create_shading_normals(record)
        skin = record.skin
        if skin is not None:
            self.influences = skin.joint_indices.shape[1]
            count = n * self.influences
            # one texel per influence: (joint index as a float, exact below 2^24; weight);
            # indices outside the skeleton become -1, which the pass skips
            indices = np.asarray(skin.joint_indices, np.int64)
            valid = (indices >= 0) & (indices < max(skin.num_joints, 0))
            packed = np.empty((count, 2), np.float32)
            packed[:, 0] = np.where(valid, indices, -1).reshape(-1)
            packed[:, 1] = np.asarray(skin.joint_weights, np.float32).reshape(-1)
            self.influence_table = self._table(count, 2, data=packed)
            #: a joint moves the points (else blend shapes alone, or nothing)
            self.skinned = skin.skinned
            #: DQS: a joint of this frame scales or shears (the skin pass sets it)
            self.has_scale = False
            self.joints = self._table(max(skin.num_joints, 1) * JOINT_TEXELS, 4)
            subshapes = max(skin.num_subshapes, 1)
            self.subshape_offsets = self._buffer(np.zeros((subshapes * n, 4), np.float32))
            self.subshape_weights = self._buffer(np.zeros(subshapes, np.float32))
            self.uploaded_subshapes: set[int] = set()
        # textures join self.textures as they are made, so release() frees them on failure
        self.texture = None
        self._upload_texture(record)
        self.set_normal_map(record.material.normal_map)
        self.profiles = [self._profile_texture(table) for table in
                         (record.params.height_profile, record.params.gradient_profile)]
        self._profile_bounds(record.params.gradient_profile)

    def _create_shading_normals(self, record: MeshRecord) -> None:
        """The shading normals (scene/normals.py): a table of ``entries`` normals made per
        frame by the normals pass (or uploaded), and each triangle corner's entry."""
        plan = record.normals
        self.normal_plan = plan
        self.shading_normals = self._table(plan.entries, 4, data=vec4(
            plan.authored if plan.authored is not None else np.zeros((plan.entries, 3)), 1.0))
        self.normal_corners = self._table(3 * self.num_triangles, 1, "i4",
                                          plan.corner_entry.reshape(-1))
        self.normal_plan_table = self._table(len(plan.csr), 1, "i4", plan.csr)
        #: the authored normals a skinned mesh's pass skins (rest values)
        self.authored_normals = self._table(plan.entries, 4, data=vec4(plan.authored, 0.0)) \
            if plan.authored is not None and record.skin is not None else None

    def _profile_texture(self, table: np.ndarray):
        """A profile (height or gradient) as an N x 1 texture, repeating along the period."""
        tex = self.ctx.texture((len(table), 1), 1, _bytes(table.astype(np.float32)), dtype="f4")
        self.textures.append(tex)
        tex.repeat_x = True
        tex.repeat_y = False
        return tex

    def _corner_st(self, record: MeshRecord) -> np.ndarray:
        """Texture coordinates per triangle corner ([3t + c]); zeros without a texture."""
        corner = np.zeros((self.num_triangles * 3, 2), np.float32)
        if record.material.corner_st is not None:
            corner[:] = record.material.corner_st.reshape(-1, 2)
        return corner

    def update_params(self, record: MeshRecord) -> None:
        """Re-upload the wrinkle parameters (q, width, profiles) of an edited record; the
        rest of the resources, and the phase tables, stay."""
        self.record = record
        self.q_width.write(vec4(record.params.q, record.params.width))
        self.hold.write(_hold(record.params, self.num_points))
        self.coarsening.write(_coarsening(record.params, self.num_points))
        key = _anchor_key(record)
        if key != self._anchor_key:  # amplitude, profile... edits keep it
            self.anchor.write(_anchor(record))
            self._anchor_key = key
        for index, table in enumerate((record.params.height_profile,
                                       record.params.gradient_profile)):
            old = self.profiles[index]
            if old.size == (len(table), 1):
                old.write(_bytes(table.astype(np.float32)))
                continue
            self.profiles[index] = self._profile_texture(table)
            self.textures.remove(old)
            old.release()
        self._profile_bounds(record.params.gradient_profile)

    def _corner_table(self, table: Table | None, colors) -> Table | None:
        """A table of colours per triangle corner ((m, 3, 3), linear) with ``colors``
        written into it (made where ``table`` is None), or none for None (``table``
        freed)."""
        if colors is None:
            if table is not None:
                self.tables.remove(table)
                table.release()
            return None
        if table is None:
            table = self._table(3 * self.num_triangles, 4)
        table.write(vec4(np.asarray(colors, np.float32).reshape(-1, 3), 1.0))
        return table

    def _set_corner_colors(self, colors) -> None:
        """Upload colours per triangle corner ((m, 3, 3)), or drop them (None)."""
        self.corner_colors = self._corner_table(self.corner_colors, colors)

    def set_frame_colors(self, colors) -> None:
        """Write corner colours ((m, 3, 3)) into the table the material made (a frame's
        own, where displayColor is time-sampled)."""
        if colors is not None and self.corner_colors is not None:
            self.corner_colors.write(vec4(np.asarray(colors, np.float32).reshape(-1, 3), 1.0))

    def set_display_colors(self, colors) -> None:
        """Draw ``colors`` ((m, 3, 3) per triangle corner, linear) instead of the
        material's colour, or the material again (None)."""
        self.display_colors = self._corner_table(self.display_colors, colors)

    def update_material(self, record: MeshRecord) -> None:
        """Re-upload the material (texture, texture coordinates) of an edited record."""
        self.record = record
        self.corner_st.write(self._corner_st(record))
        self._set_corner_colors(record.material.corner_colors)
        if self.texture is not None:
            self.textures.remove(self.texture)
            self.texture.release()
            self.texture = None
        self._upload_texture(record)
        self.set_normal_map(record.material.normal_map)

    def set_normal_map(self, normal_map) -> None:
        """Upload a NormalMapRecord (or drop the map: None); the same files as the
        uploaded ones (its key) cost nothing, so a per-frame map uploads once a frame."""
        if normal_map is self.normal_map_record or (
                normal_map is not None and self.normal_map_record is not None
                and normal_map.key == self.normal_map_record.key):
            return
        if self.normal_map is not None:
            self.textures.remove(self.normal_map)
            self.normal_map.release()
            self.normal_map = None
        self.normal_map_record = normal_map
        self.udim_layers[:] = -1
        if normal_map is None:
            return
        self.normal_st.write(normal_map.corner_st.reshape(-1, 2))
        height, width = normal_map.tiles[0][1].shape[:2]
        images = [image for _, image in normal_map.tiles]
        if all(image.pixels.dtype == np.uint8 and not image.srgb for image in images):
            layers, dtype = np.stack([image.pixels for image in images]), "f1"  # raw codes
        else:
            layers, dtype = np.stack([image.linear() for image in images]), "f4"
        self.normal_map = self.ctx.texture_array((width, height, len(layers)), 4,
                                                 _bytes(layers), dtype=dtype)
        self.textures.append(self.normal_map)
        if not self.record.material.normal_map_varies:
            build_mipmaps(self.ctx, self.normal_map, layers, srgb=False)
        else:
            # a map per frame (a bake's wrinkle maps): the driver's generator, quicker
            # than our pass's read-back (docs/decisions.md, "Mip chains of a map a frame")
            self.normal_map.build_mipmaps()
        for layer, (tile, _) in enumerate(normal_map.tiles):
            if tile == -1:  # one texture that repeats (draw.glsl: normal_map)
                self.udim_layers[:] = UDIM_REPEAT
                break
            self.udim_layers[tile] = layer
        # a UDIM tile is clamped at its edges (its neighbour is another file); one texture
        # repeats, as UsdUVTexture's wrap modes default to
        repeats = bool(self.udim_layers[0] == UDIM_REPEAT)
        self.normal_map.repeat_x = self.normal_map.repeat_y = repeats

    def _upload_texture(self, record: MeshRecord) -> None:
        if record.material.texture is None:
            return
        image = record.material.texture
        size = (image.shape[1], image.shape[0])
        if image.pixels.dtype == np.uint8:
            # 8-bit codes as they are; an sRGB texture decodes in the sampler, before
            # filtering (GL_SRGB8_ALPHA8), as the float path decoded before filtering
            self.texture = self.ctx.texture(size, 4, _bytes(image.pixels), dtype="f1",
                                            internal_format=GL_SRGB8_ALPHA8 if image.srgb
                                            else None)
            self.textures.append(self.texture)
            build_mipmaps(self.ctx, self.texture, image.pixels, image.srgb)
        else:
            self.texture = self.ctx.texture(size, 4, _bytes(image.pixels), dtype="f4")
            self.textures.append(self.texture)
            build_mipmaps(self.ctx, self.texture, image.pixels, srgb=False)
        self.texture.repeat_x = self.texture.repeat_y = True

    def _table(self, count: int, components: int, dtype: str = "f4", data=None) -> Table:
        table = Table(self.ctx, count, components, dtype, data, path=self.record.path)
        self.tables.append(table)
        return table

    def _profile_bounds(self, gradient_profile: np.ndarray) -> None:
        """What the draw pass reads of the profile: max |H''| (turn_across_pixel) and max
        |H'| (the relief's bound of the folds' slope: draw.glsl, relief_slope)."""
        self.profile_curvature = profile_curvature(gradient_profile)
        self.profile_steepest = float(np.max(np.abs(gradient_profile), initial=0.0))

    @property
    def triangle_neighbors(self) -> Table:
        """Per triangle, the triangle across the edge opposite each corner, -1 where none
        (ivec4, w unused; scene/topology.triangle_neighbors): made on first use, by the
        draw pass's relief (draw.glsl: RELIEF), which walks it."""
        table = self.owned.get("triangle_neighbors")
        if table is None:
            data = np.full((self.num_triangles, 4), -1, np.int32)
            data[:, :3] = triangle_neighbors(self.record.topology.triangles)
            table = self.owned["triangle_neighbors"] = self._table(self.num_triangles, 4,
                                                                    "i4", data)
        return table

    def owned_table(self, key: str, spec) -> Table:
        """The table ``key`` that a pass owns (``spec``: passes/base.TableSpec), made on
        first use and released with the others."""
        table = self.owned.get(key)
        if table is None:
            table = self.owned[key] = self._table(spec.count(self), spec.components,
                                                  spec.dtype)
        return table

    def _drop(self, table: Table) -> None:
        """Release one table before the others (WaveFields re-lays its relax tables)."""
        self.tables.remove(table)
        table.release()

    def _buffer(self, array: np.ndarray):
        buf = self.ctx.buffer(_bytes(array))
        self.buffers.append(buf)
        return buf

    def upload_subshape(self, blend_shape: int, subshape: int) -> None:
        """Scatter one sub-shape's offsets into its dense row (first use only)."""
        if subshape in self.uploaded_subshapes:
            return
        skin = self.record.skin
        offsets = skin.subshape_offsets[subshape]
        row = np.zeros((self.num_points, 4), np.float32)
        ids = skin.blend_point_indices[blend_shape] if blend_shape < len(
            skin.blend_point_indices) else None
        if len(offsets):
            if ids is None:
                row[:len(offsets), :3] = offsets[:self.num_points]
            else:
                row[ids[:len(offsets)], :3] = offsets[:len(ids)]
        self.subshape_offsets.write(row.tobytes(), offset=subshape * self.num_points * 16)
        self.uploaded_subshapes.add(subshape)

    def read_fields(self) -> WrinkleFields:
        """Read back what the passes computed (the bake's single source of truth)."""
        return self.waves.read(self.posed_points)

    def read_shading_normals(self) -> np.ndarray:
        """This frame's shading normals (the normals pass's table: one per NormalPlan
        entry), (entries, 3) float32, local space, unit length."""
        return np.ascontiguousarray(self.shading_normals.read()[:, :3], np.float32)

    def release(self) -> None:
        for buf in self.buffers:
            buf.release()
        for table in self.tables:
            table.release()
        for tex in self.textures:
            tex.release()
        self.buffers, self.tables, self.textures = [], [], []
        self.owned = {}


def profile_curvature(gradient_profile: np.ndarray) -> float:
    """max |H''| of a height profile H from its gradient profile H' (N samples over one
    period, read with linear filtering, so H'' is the slope between neighbours): how fast
    a wave's slope turns per radian of phase (draw.glsl: turn_across_pixel)."""
    table = np.asarray(gradient_profile, np.float64)
    if table.size < 2:
        return 0.0
    steps = np.diff(np.append(table, table[0]))
    return float(np.max(np.abs(steps)) * table.size / (2.0 * np.pi))
