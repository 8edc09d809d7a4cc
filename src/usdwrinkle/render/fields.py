"""One mesh's wave fields on the GPU: what crush writes, relax refines and draw, the maps
and the geometry read (render/resources.py holds the mesh's other tables).

Two field tables alternate (ping-pong). Each frame ``advance()`` makes the other one
current: crush writes this frame's fields into it, while the previous frame's stay
readable for relax's seed step, which carries the phases over (the phase history). The
phasors alternate the same way inside one relaxation (relax.py picks the pair by step).
"""
from __future__ import annotations

import numpy as np

from ..contract import FIELD_FLOATS, FIELD_TEXELS, WAVE_SYSTEMS, WrinkleFields


class WaveFields:
    """The field ping-pong, the phases and the relax tables of one mesh.

    ``table(count, components, data=None)`` makes a table that the mesh's resources own
    (and release); ``drop(table)`` releases one of them early (a re-layout)."""

    def __init__(self, num_points: int, num_edges: int, table, drop):
        n = self.num_points = num_points
        self.num_edges = num_edges
        self._table, self._drop = table, drop
        #: crest damping: each point's damped rest direction of the last frame
        self.damped = table(n, 4, data=np.zeros((n, 4), np.float32))
        # FIELD_TEXELS per vertex: normal, wave, direction, wave2, direction2 (contract.py)
        self._tables = [table(FIELD_TEXELS * n, 4,
                              data=np.zeros((FIELD_TEXELS * n, 4), np.float32))
                        for _ in range(2)]
        self._current = 0
        #: phases per vertex and wave system (RG: systems 1, 2): crush's anchored start,
        #: and the relaxed phase that draw and the bake read
        self.anchor_phase = table(n, WAVE_SYSTEMS, data=np.zeros((n, WAVE_SYSTEMS), np.float32))
        self.phase = table(n, WAVE_SYSTEMS, data=np.zeros((n, WAVE_SYSTEMS), np.float32))
        #: unit phasors during relaxation (ping-pong) and the per-edge rotations, laid
        #: out for the wave systems relaxed (set_systems)
        self.phasors: list = []
        self.edge_rotations = None
        #: wave systems the passes run and draw: 2 with wrinkle:biaxial (or a bake of it)
        self.systems = 0
        self.set_systems(1)
        self.baked_waves = None  # write_baked() makes it

    @property
    def current(self):
        """This frame's field table (crush writes it; relax, draw and the bakes read it)."""
        return self._tables[self._current]

    @property
    def previous(self):
        """The previous frame's field table (relax's seed step reads its wave vectors)."""
        return self._tables[1 - self._current]

    def advance(self) -> None:
        """A new frame: the other field table becomes current, this one previous."""
        self._current = 1 - self._current

    def set_systems(self, systems: int) -> None:
        """Lay the relax tables out for 1 or 2 wave systems: phasors RG (one system, as
        in the paper) or RGBA (xy, zw: systems 1, 2), and one edge texel per edge and
        system (relax.glsl). A change re-makes them (an edit of wrinkle:biaxial)."""
        if systems == self.systems:
            return
        for table in [*self.phasors, self.edge_rotations]:
            if table is not None:
                self._drop(table)
        self.systems = systems
        self.phasors = [self._table(self.num_points, 2 * systems) for _ in range(2)]
        self.edge_rotations = self._table(systems * self.num_edges, 4)

    def write_baked(self, baked) -> None:
        """Upload one frame's baked fields (scene.baked.BakedFields): waves into the baked
        table ([4i] = (k, amplitude), [4i + 1] = (direction, r), [4i + 2], [4i + 3]: the
        second system's), phases into the phase table that draw reads. The baked table is
        made on first use."""
        n = self.num_points
        if self.baked_waves is None:
            self.baked_waves = self._table(4 * n, 4)
        block = np.zeros((n, 4, 4), np.float32)
        block[:, 0, :3] = baked.wave_vector
        block[:, 0, 3] = baked.amplitude
        block[:, 1, :3] = baked.direction
        block[:, 1, 3] = baked.compression
        phases = np.zeros((n, WAVE_SYSTEMS), np.float32)
        phases[:, 0] = baked.phase
        self.set_systems(2 if baked.amplitude2 is not None else 1)
        if baked.amplitude2 is not None:
            block[:, 2, :3] = baked.wave_vector2
            block[:, 2, 3] = baked.amplitude2
            block[:, 3, :3] = baked.direction2
            block[:, 3, 3] = baked.compression2
            phases[:, 1] = baked.phase2
        self.baked_waves.write(block)
        self.phase.write(phases)

    def read(self, posed_points) -> WrinkleFields:
        """Read back what the passes computed (the bake's single source of truth), with
        the posed points table they were computed on."""
        fields = self.current.read().reshape(self.num_points, FIELD_FLOATS)
        return WrinkleFields.from_tables(posed_points.read(), fields, self.phase.read(),
                                         self.anchor_phase.read())
