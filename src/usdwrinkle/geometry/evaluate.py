"""The GPU half of the displaced geometry: geometry.glsl at every fine vertex.

Per mesh, the fine vertices' (coarse triangle, barycentrics) are uploaded once; each
frame one compute dispatch evaluates the wave blend of the frame the engine computed
(include/wave.glsl, as the draw pass does per pixel) and the displaced points and
normals are read back. No Usd objects here.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..render import bindings
from ..render.passes import bind_wave, irregular
from ..render.passes.base import Pass
from ..render.resources import MeshResources, Table
from .subdivide import FineMesh

#: the band limit: no wave on the fine mesh shorter than this many rest fine edges
BAND_LIMIT_EDGES = 2.0


@dataclass
class FineFrame:
    """One frame of a fine mesh, in the coarse mesh's local space.

    points : (n, 3) float32 displaced points.
    normals : (n, 3) float32 unit normals from the wrinkle gradient.
    """

    points: np.ndarray
    normals: np.ndarray


class GeometryEvaluator(Pass):
    """The displaced geometry's pass (render/passes/base.Pass) and, per mesh, its
    fine-vertex table and output tables."""

    SHADER = "geometry.glsl"
    #: the wave blend's units (include/wave.glsl) and its own
    UNITS = {**bindings.WAVE, "GEOMETRY_RANGES": 9, "GEOMETRY_ENTRIES": 10,
             "GEOMETRY_SHADING_NORMALS": 11, "GEOMETRY_NORMAL_CORNERS": 12,
             # image units
             "GEOMETRY_POINTS": 0, "GEOMETRY_NORMALS": 1}

    def __init__(self, ctx):
        super().__init__(ctx)
        self.tables: dict[str, tuple[Table, Table, Table, Table]] = {}

    def _tables(self, res: MeshResources, fine: FineMesh):
        path = res.record.path
        tables = self.tables.get(path)
        count = len(fine.points)
        if tables is None or tables[2].count != count:
            self._release(path)
            ranges = np.stack([fine.entry_offsets[:-1], fine.entry_offsets[1:]], 1)
            entries = np.empty((len(fine.entry_triangle), 4), np.float32)
            entries[:, 0] = fine.entry_triangle
            entries[:, 1:] = fine.entry_bary
            tables = (Table(self.ctx, count, 2, "i4", ranges, "fine vertex table", path),
                      Table(self.ctx, len(entries), 4, data=entries, what="fine vertex table",
                            path=path),
                      Table(self.ctx, count, 4, path=path), Table(self.ctx, count, 4, path=path))
            self.tables[path] = tables
        return tables

    def evaluate(self, res: MeshResources, fine: FineMesh, wrinkles: bool = True) -> FineFrame:
        """The fine mesh at the frame ``res`` holds (synced and computed)."""
        ranges, entries, points, normals = self._tables(res, fine)
        two = res.waves.systems > 1
        rough = irregular(res)
        bind_wave(self.UNITS, res, self.variants(TWO_SYSTEMS=two, IRREGULAR=rough))
        self.dispatch(len(fine.points), {
            "u_count": len(fine.points), "u_wrinkles": int(wrinkles),
            "u_min_wavelength": float(BAND_LIMIT_EDGES * fine.edge_length),
            "u_profile_samples": float(len(res.record.params.height_profile))},
            reads={"GEOMETRY_RANGES": ranges, "GEOMETRY_ENTRIES": entries,
                   "GEOMETRY_SHADING_NORMALS": res.shading_normals,
                   "GEOMETRY_NORMAL_CORNERS": res.normal_corners},
            writes={"GEOMETRY_POINTS": points, "GEOMETRY_NORMALS": normals}, TWO_SYSTEMS=two,
            IRREGULAR=rough)
        out_points = points.read()
        out_normals = normals.read()
        return FineFrame(np.ascontiguousarray(out_points[:, :3]),
                         np.ascontiguousarray(out_normals[:, :3]))

    def _release(self, path: str) -> None:
        for table in self.tables.pop(path, ()):
            table.release()

    def release(self) -> None:
        for path in list(self.tables):
            self._release(path)
        super().release()
