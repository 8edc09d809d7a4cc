"""The GPU half of the wrinkle maps: the wave blend rasterised in UV space, then padded.

Per mesh and UDIM tile, ``maps.glsl`` draws every triangle at its texture coordinates
into two float targets (tangent-space normal; height and normalised amplitude), with
the wave_blend that the draw pass uses (include/wave.glsl). ``dilate.glsl`` then grows
the UV islands by the padding, and the targets are read back. No Usd objects here: the
mesh's tables come from its MeshResources, the UVs as an array.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..render import bindings
from ..render.passes import bind, bind_wave, set_uniforms
from ..render.resources import MeshResources, Table
from ..render.shaders import compute_shader, program

DILATE_GROUP = 8  # dilate.glsl's local size, both axes


@dataclass
class MapPixels:
    """One tile of one mesh's maps, row 0 at t = 0 (the bottom of the image).

    normal : (h, w, 3) float32, tangent-space unit normal ((0, 0, 1) off the islands).
    height : (h, w) float32, the wrinkle height h in scene units.
    amplitude : (h, w) float32, the amplitude over s W / 4, in [0, 1].
    covered : (h, w) bool, texels a triangle covers (before padding).
    """

    normal: np.ndarray
    height: np.ndarray
    amplitude: np.ndarray
    covered: np.ndarray


class MapRasterizer:
    """The maps program, the dilation kernel and render targets of one size."""

    def __init__(self, ctx, size: int):
        import moderngl

        self.ctx = ctx
        self.size = int(size)
        defines = {**bindings.COMMON, **bindings.MAPS}
        self.program = program(ctx, "maps.glsl", defines)
        self.vao = ctx.vertex_array(self.program, [])
        self.dilate = compute_shader(ctx, "dilate.glsl", defines)
        self.mode = moderngl.TRIANGLES
        shape = (self.size, self.size)
        # [target][ping-pong]: the draw writes pair 0, dilation steps alternate
        self.targets = [[ctx.texture(shape, 4, dtype="f4") for _ in range(2)] for _ in range(2)]
        self.framebuffers = [ctx.framebuffer(color_attachments=[self.targets[0][i],
                                                                self.targets[1][i]])
                             for i in range(2)]
        self.uv_tables: dict[str, Table] = {}

    def uv_table(self, res: MeshResources, corner_uv: np.ndarray) -> Table:
        """The mesh's UVs per triangle corner ([3t + c]) on the GPU, uploaded once."""
        table = self.uv_tables.get(res.record.path)
        if table is None or table.count != 3 * res.num_triangles:
            if table is not None:
                table.release()
            table = Table(self.ctx, 3 * res.num_triangles, 2,
                          data=np.asarray(corner_uv, np.float32).reshape(-1, 2),
                          path=res.record.path)
            self.uv_tables[res.record.path] = table
        return table

    def _draw(self, res: MeshResources, uv: Table, tile: tuple[int, int], count: bool) -> None:
        import moderngl

        fbo = self.framebuffers[0]
        fbo.use()
        fbo.clear(0.0, 0.0, 0.0, 0.0)
        self.ctx.viewport = (0, 0, self.size, self.size)
        self.ctx.disable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
        if count:
            self.ctx.enable(moderngl.BLEND)
            self.ctx.blend_func = moderngl.ONE, moderngl.ONE
        else:
            self.ctx.disable(moderngl.BLEND)
        set_uniforms(self.program, {
            "u_tile": (float(tile[0]), float(tile[1])),
            "u_count": int(count),
            "u_amplitude_scale": float(res.record.params.amplitude_scale),
            "u_profile_samples": float(len(res.record.params.height_profile)),
        })
        units = bindings.MAPS
        bind_wave(units, res)
        bind(units, reads={"MAPS_UV": uv, "MAPS_Q_WIDTH": res.q_width})
        self.vao.render(mode=self.mode, vertices=3 * res.num_triangles)
        if count:
            self.ctx.disable(moderngl.BLEND)

    def overlap(self, res: MeshResources, corner_uv: np.ndarray, tile=(0, 0)) -> float:
        """The fraction of the covered texels of ``tile`` that more than one triangle
        covers: overlapping UV islands (shared edges count once, by GL's rasterisation
        rules)."""
        if res.num_triangles == 0:
            return 0.0
        self._draw(res, self.uv_table(res, corner_uv), tile, count=True)
        counts = np.frombuffer(self.targets[0][0].read(), np.float32)[3::4]
        covered = np.count_nonzero(counts > 0.5)
        return float(np.count_nonzero(counts > 1.5) / covered) if covered else 0.0

    def render(self, res: MeshResources, corner_uv: np.ndarray, tile=(0, 0),
               padding: int = 8) -> MapPixels:
        """The maps of ``res`` (its synced, computed frame) in UV tile ``tile``."""
        uv = self.uv_table(res, corner_uv)
        if res.num_triangles:
            self._draw(res, uv, tile, count=False)
        else:
            self.framebuffers[0].clear(0.0, 0.0, 0.0, 0.0)
        source = 0
        groups = -(-self.size // DILATE_GROUP)
        units = bindings.MAPS
        for _ in range(int(padding)):
            target = 1 - source
            self.targets[0][source].bind_to_image(units["DILATE_NORMAL_IN"], read=True,
                                                  write=False)
            self.targets[1][source].bind_to_image(units["DILATE_WRINKLE_IN"], read=True,
                                                  write=False)
            self.targets[0][target].bind_to_image(units["DILATE_NORMAL_OUT"], read=False,
                                                  write=True)
            self.targets[1][target].bind_to_image(units["DILATE_WRINKLE_OUT"], read=False,
                                                  write=True)
            self.dilate.run(groups, groups, 1)
            self.ctx.memory_barrier()
            source = target
        normal = self._read(self.targets[0][source])
        wrinkle = self._read(self.targets[1][source])
        covered = wrinkle[..., 2] > 0.5
        empty = normal[..., 3] == 0.0
        normal_xyz = normal[..., :3]
        normal_xyz[empty] = (0.0, 0.0, 1.0)  # flat beyond the padding
        wrinkle[empty] = 0.0
        return MapPixels(np.ascontiguousarray(normal_xyz), np.ascontiguousarray(wrinkle[..., 0]),
                         np.ascontiguousarray(wrinkle[..., 1]), covered)

    def _read(self, texture) -> np.ndarray:
        return np.frombuffer(texture.read(), np.float32).reshape(self.size, self.size, 4).copy()

    def release(self) -> None:
        for table in self.uv_tables.values():
            table.release()
        self.uv_tables.clear()
        for fbo in self.framebuffers:
            fbo.release()
        for pair in self.targets:
            for tex in pair:
                tex.release()
        self.vao.release()
        self.program.release()
        self.dilate.release()
