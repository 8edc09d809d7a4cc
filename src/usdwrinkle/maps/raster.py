"""The GPU half of the wrinkle maps: the wave blend rasterised in UV space, then padded.

Per mesh and UDIM tile, ``maps.glsl`` draws every triangle at its texture coordinates
into two float targets (tangent-space normal; height and normalised amplitude), with
the wave_blend that the draw pass uses (include/wave.glsl), and the targets are read
back. The UV islands are then grown by the padding: each texel within ``padding`` steps
of an island takes the value of the covered texel its dilation came from
(:func:`padding_plan`). The UV layout does not change over a shot, so the plan is made
once per mesh and tile and each frame is one gather over the padding texels (a GPU
dilation kernel, 8 full-map passes a frame, took 1.5 s a 2048² frame on llvmpipe). No
Usd objects here: the mesh's tables come from its MeshResources, the UVs as an array.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..render import bindings
from ..render.passes import bind_wave, irregular, set_uniforms
from ..render.passes.base import DrawnPass
from ..render.resources import MeshResources, Table

#: neighbour offsets of one dilation step: edge neighbours first, so that islands grow
#: round rather than square
NEIGHBOURS = ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1))


def padding_plan(covered: np.ndarray, padding: int) -> tuple[np.ndarray, np.ndarray]:
    """(destination, source) flat texel indices of the padding: every texel that
    ``padding`` 8-connected dilation steps of the islands reach, and the covered texel
    it copies."""
    height, width = covered.shape
    source = np.where(covered, np.arange(height * width).reshape(height, width), -1)
    for _ in range(int(padding)):
        if not (source < 0).any():
            break
        grown = source.copy()
        for dy, dx in NEIGHBOURS:
            # the value of the neighbour at (y + dy, x + dx), for every texel that has one
            target = grown[max(-dy, 0):height - max(dy, 0), max(-dx, 0):width - max(dx, 0)]
            neighbour = source[max(dy, 0):height + min(dy, 0), max(dx, 0):width + min(dx, 0)]
            take = (target < 0) & (neighbour >= 0)
            target[take] = neighbour[take]
        source = grown
    flat = source.ravel()
    destination = np.flatnonzero((flat >= 0) & ~covered.ravel())
    return destination, flat[destination]


@dataclass
class MapPixels:
    """One tile of one mesh's maps, row 0 at t = 0 (the bottom of the image).

    normal : (h, w, 3) float32, tangent-space unit normal ((0, 0, 1) off the islands).
    height : (h, w) float32, the wrinkle height h in scene units.
    amplitude : (h, w) float32, the amplitude over s COARSENING_MAX W / 4 (about the
        fold law's height of cloth crushed flat), clamped to [0, 1].
    covered : (h, w) bool, texels a triangle covers (before padding).
    bent, hs, ht : (h, w, 3) float32 or None, the parallax maps (with ``parallax``): the
        bent unit normal n' in the mesh's local space, and the height times the gradients
        of the texture's s and t per local offset (draw.glsl's texture deformation:
        ds = hS.(v/(v.n') - n'), dt likewise); zero off the islands.
    """

    normal: np.ndarray
    height: np.ndarray
    amplitude: np.ndarray
    covered: np.ndarray
    bent: np.ndarray | None = None
    hs: np.ndarray | None = None
    ht: np.ndarray | None = None


class MapRasterizer(DrawnPass):
    """The maps' pass (render/passes/base.DrawnPass) and its render targets of one size."""

    SHADER = "maps.glsl"
    #: the wave blend's units (include/wave.glsl) and its own
    UNITS = {**bindings.WAVE, "MAPS_UV": 7, "MAPS_Q_WIDTH": 9, "MAPS_SHADING_NORMALS": 10,
             "MAPS_NORMAL_CORNERS": 11, "MAPS_TANGENTS": 12,
             "MAPS_FRAME_NORMALS": 14}

    def __init__(self, ctx, size: int, parallax: bool = False):
        import moderngl

        super().__init__(ctx)
        self.size = int(size)
        #: also the parallax maps (three more targets)
        self.parallax = bool(parallax)
        self.mode = moderngl.TRIANGLES
        shape = (self.size, self.size)
        # normal, wrinkle; with parallax bent, hS, hT
        self.targets = [ctx.texture(shape, 4, dtype="f4")
                        for _ in range(5 if self.parallax else 2)]
        self.framebuffer = ctx.framebuffer(color_attachments=self.targets)
        #: UVs per triangle corner, by layout (a mesh's path, or the name its map set
        #: gives it: a mesh may be mapped in more than one layout)
        self.uv_tables: dict[str, Table] = {}
        #: MikkTSpace tangents per triangle corner, by mesh path (written each frame)
        self.tangent_tables: dict[str, Table] = {}
        #: the normals those frames are built about, per triangle corner (each frame)
        self.frame_tables: dict[str, Table] = {}
        #: (layout, tile, padding) -> padding_plan
        self.plans: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}

    def _corner_table(self, store: dict, res: MeshResources, components: int,
                      key: str | None = None) -> tuple:
        """(the mesh's table of one value per triangle corner in ``store`` under ``key``
        (default: the mesh's path), made now); a table of another size is replaced."""
        key = key or res.record.path
        table = store.get(key)
        if table is not None and table.count == 3 * res.num_triangles:
            return table, False
        if table is not None:
            table.release()
        table = store[key] = Table(self.ctx, 3 * res.num_triangles, components,
                                   path=res.record.path)
        return table, True

    def uv_table(self, res: MeshResources, corner_uv: np.ndarray,
                 layout: str | None = None) -> Table:
        """The mesh's UVs per triangle corner ([3t + c]) on the GPU, uploaded once per
        ``layout`` (default: the mesh's path)."""
        table, new = self._corner_table(self.uv_tables, res, 2, layout)
        if new:
            table.write(np.asarray(corner_uv, np.float32).reshape(-1, 2))
        return table

    def tangent_table(self, res: MeshResources, tangents: np.ndarray) -> Table:
        """This frame's MikkTSpace tangents ([3t + c]: xyz, sign) on the GPU."""
        table, _ = self._corner_table(self.tangent_tables, res, 4)
        table.write(np.asarray(tangents, np.float32).reshape(-1, 4))
        return table

    def frame_table(self, res: MeshResources, normals: np.ndarray) -> Table:
        """This frame's normals of the MikkTSpace frames ([3t + c]: xyz) on the GPU."""
        table, _ = self._corner_table(self.frame_tables, res, 4)
        padded = np.zeros((3 * res.num_triangles, 4), np.float32)
        padded[:, :3] = np.asarray(normals, np.float32).reshape(-1, 3)
        table.write(padded)
        return table

    def _draw(self, res: MeshResources, uv: Table, tile: tuple[int, int], count: bool,
              tangents: tuple[Table, Table] | None = None) -> None:
        import moderngl

        fbo = self.framebuffer
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        self.ctx.viewport = (0, 0, self.size, self.size)
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        if count:
            self.ctx.enable(moderngl.BLEND)
            self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        else:
            self.ctx.disable(moderngl.BLEND)
        variant = self.variants(TWO_SYSTEMS=res.waves.systems > 1,
                                IRREGULAR=irregular(res),
                                MIKKTSPACE=tangents is not None and not count,
                                PARALLAX=self.parallax)
        set_uniforms(variant.program, {
            "u_tile": (float(tile[0]), float(tile[1])),
            "u_count": int(count),
            "u_amplitude_scale": float(res.record.params.amplitude_scale),
        })
        bind_wave(self.UNITS, res, variant.program)
        self.bind(reads={"MAPS_UV": uv, "MAPS_Q_WIDTH": res.q_width,
                         "MAPS_SHADING_NORMALS": res.shading_normals,
                         "MAPS_NORMAL_CORNERS": res.normal_corners})
        if tangents is not None and not count:
            self.bind(reads={"MAPS_TANGENTS": tangents[0], "MAPS_FRAME_NORMALS": tangents[1]})
        variant.vao.render(mode=self.mode, vertices=3 * res.num_triangles)
        if count:
            self.ctx.disable(moderngl.BLEND)

    def overlap(self, res: MeshResources, corner_uv: np.ndarray, tile=(0, 0),
                layout: str | None = None) -> float:
        """The fraction of the covered texels of ``tile`` that more than one triangle
        covers: overlapping UV islands (shared edges count once, by GL's rasterisation
        rules)."""
        if res.num_triangles == 0:
            return 0.0
        self._draw(res, self.uv_table(res, corner_uv, layout), tile, count=True)
        counts = np.frombuffer(self.targets[0].read(), np.float32)[3::4]
        covered = np.count_nonzero(counts > 0.5)
        return float(np.count_nonzero(counts > 1.5) / covered) if covered else 0.0

    def render(self, res: MeshResources, corner_uv: np.ndarray, tile=(0, 0),
               padding: int = 8, tangents: tuple | None = None,
               layout: str | None = None) -> MapPixels:
        """The maps of ``res`` (its synced, computed frame) in UV tile ``tile``; the
        normal map in MikkTSpace when this frame's ``tangents`` are given ((tangents,
        the normals their frames are built about), per triangle corner;
        maps/tangents.py), else in the per-triangle frame. ``layout`` names the layout
        of ``corner_uv`` (default: the mesh's path): its UV table and padding plan are
        made once per name. With parallax, ``corner_uv`` must be the texture coordinates
        the mesh's textures read: the parallax maps hold their gradients."""
        uv = self.uv_table(res, corner_uv, layout)
        if res.num_triangles:
            table = (self.tangent_table(res, tangents[0]), self.frame_table(res, tangents[1])) \
                if tangents is not None else None
            self._draw(res, uv, tile, count=False, tangents=table)
        else:
            self.framebuffer.clear(0.0, 0.0, 0.0, 0.0)
        normal = self._read(self.targets[0])
        wrinkle = self._read(self.targets[1])
        extra = [self._read(target) for target in self.targets[2:]]
        covered = wrinkle[..., 3] > 0.0
        key = (layout or res.record.path, tuple(tile), int(padding))
        plan = self.plans.get(key)
        if plan is None:
            plan = self.plans[key] = padding_plan(covered, padding)
        destination, source = plan
        flat_normal = normal.reshape(-1, 4)
        flat_wrinkle = wrinkle.reshape(-1, 4)
        flat_normal[destination] = flat_normal[source]
        flat_wrinkle[destination] = flat_wrinkle[source]
        empty = normal[..., 3] == 0.0
        normal[empty] = (0.0, 0.0, 1.0, 0.0)  # flat beyond the padding
        wrinkle[empty] = 0.0
        for image in extra:  # padded as the others: no seam where a renderer's filter
            flat = image.reshape(-1, 4)  # reaches past an island's border
            flat[destination] = flat[source]
            image[empty] = 0.0
        parallax = {name: image[..., :3]
                    for name, image in zip(("bent", "hs", "ht")[:len(extra)], extra, strict=True)}
        return MapPixels(normal[..., :3], wrinkle[..., 0], wrinkle[..., 1], covered,
                         **parallax)

    def _read(self, texture) -> np.ndarray:
        return np.frombuffer(texture.read(), np.float32).reshape(self.size, self.size, 4).copy()

    def release(self) -> None:
        for table in [*self.uv_tables.values(), *self.tangent_tables.values(),
                      *self.frame_tables.values()]:
            table.release()
        self.uv_tables.clear()
        self.tangent_tables.clear()
        self.frame_tables.clear()
        self.framebuffer.release()
        for tex in self.targets:
            tex.release()
        super().release()

