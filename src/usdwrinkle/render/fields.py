"""One mesh's wave fields on the GPU: what crush writes, relax refines and draw, the maps
and the geometry read (render/resources.py holds the mesh's other tables).

A frame reads the wave state of the shot's previous grid frame (fields, relaxed phases,
damped directions: :class:`WaveState`) and writes its own into another slot; reading a
state never changes it, so a frame computed twice from one state is the same twice. The
phasors alternate (ping-pong) inside one relaxation (relax.py picks the pair by step).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..method.contract import FIELD_FLOATS, FIELD_TEXELS, WAVE_SYSTEMS, WrinkleFields

#: GPU bytes of one wave state per point: FIELD_TEXELS RGBA float texels, the phases
#: (WAVE_SYSTEMS floats) and the damped direction (RGBA float) (WaveFields.state)
STATE_BYTES_PER_POINT = (FIELD_TEXELS * 4 + WAVE_SYSTEMS + 4) * 4


@dataclass
class WaveState:
    """What the next grid frame of the shot reads of this one (docs/method.md, "The wave
    state"): the fields (the wave vectors, for the seed's flip test), the relaxed phases
    (the seed) and the damped rest directions (crest damping). A computed frame writes
    one; the engine keeps the states of grid frames as values (engine.WaveHistory), and a
    frame computed from a state never changes it."""

    fields: object
    phase: object
    damped: object

    def tables(self) -> list:
        return [self.fields, self.phase, self.damped]

    def read(self) -> dict[str, np.ndarray]:
        """The state as numpy arrays (tests, the numpy reference)."""
        return {"fields": self.fields.read(), "phase": self.phase.read(),
                "damped": self.damped.read()}


class WaveFields:
    """The wave states, the anchored phase and the relax tables of one mesh.

    ``table(count, components, data=None)`` makes a table that the mesh's resources own
    (and release); ``drop(table)`` releases one of them early (a re-layout).

    The wave states live in numbered slots (made on first use, the same slot numbers in
    every mesh of an engine): :meth:`begin` names the slot a frame writes and the slot
    of the shot's previous grid frame it reads (None: no history). Nothing here decides
    which frame a slot holds: the engine's WaveHistory does."""

    def __init__(self, num_points: int, num_edges: int, table, drop):
        self.num_points = num_points
        self.num_edges = num_edges
        self._table, self._drop = table, drop
        self._states: list[WaveState] = []
        self._write = 0
        self._read: int | None = None
        self.state(0)
        #: crush's material-anchored phases per vertex and wave system (RG: systems 1, 2):
        #: this frame's, not part of the state
        n = num_points
        self.anchor_phase = table(n, WAVE_SYSTEMS, data=np.zeros((n, WAVE_SYSTEMS), np.float32))
        #: relax's per-vertex mobility and seed phases (x: mobility, yz: seeds): this frame's
        self.mobility = table(n, 4, data=np.zeros((n, 4), np.float32))
        #: unit phasors during relaxation (ping-pong) and the per-edge rotations, laid
        #: out for the wave systems relaxed (set_systems)
        self.phasors: list = []
        self.edge_rotations = None
        #: wave systems the passes run and draw: 2 with wrinkle:biaxial (or a bake of it)
        self.systems = 0
        self.set_systems(1)
        self.baked_waves = None  # write_baked() makes it

    def state(self, slot: int) -> WaveState:
        """The wave state in ``slot`` (made, zeroed, on first use)."""
        n = self.num_points
        while len(self._states) <= slot:
            # FIELD_TEXELS per vertex: normal, wave, direction, wave2, direction2, deepen
            # (method/contract.py); phases RG (systems 1, 2); damped: xy the damped direction
            # (T1, T2 coordinates), z 1 once written
            self._states.append(WaveState(
                self._table(FIELD_TEXELS * n, 4,
                            data=np.zeros((FIELD_TEXELS * n, 4), np.float32)),
                self._table(n, WAVE_SYSTEMS, data=np.zeros((n, WAVE_SYSTEMS), np.float32)),
                self._table(n, 4, data=np.zeros((n, 4), np.float32))))
        return self._states[slot]

    @property
    def slots(self) -> int:
        """How many wave states this mesh holds on the GPU."""
        return len(self._states)

    def release_slots(self, keep: int) -> None:
        """Release the states in slots ``keep`` and above (the engine's cache shrank)."""
        while len(self._states) > max(keep, 1):
            for table in self._states.pop().tables():
                self._drop(table)

    def begin(self, write: int, read: int | None) -> None:
        """A frame: it writes the state in slot ``write`` and reads the previous grid
        frame's in slot ``read`` (None: a cold start). The two are never one slot."""
        if read is not None and read == write:
            raise ValueError(f"a frame cannot write the state it reads (slot {write})")
        self.state(write)
        if read is not None:
            self.state(read)
        self._write, self._read = write, read

    @property
    def written(self) -> WaveState:
        """The state this frame writes (crush, relax) and draw and the bakes read."""
        return self._states[self._write]

    @property
    def history(self) -> WaveState:
        """The previous grid frame's state that this frame reads; without history, the
        written state itself (bound, never read: the passes' u_has_history is 0)."""
        return self._states[self._read if self._read is not None else self._write]

    @property
    def current(self):
        """This frame's field table (crush writes it; relax, draw and the bakes read it)."""
        return self.written.fields

    @property
    def phase(self):
        """This frame's relaxed phases (relax writes them; draw and the bakes read them)."""
        return self.written.phase

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
        table ([5i] = (k, amplitude), [5i + 1] = (direction, r), [5i + 2], [5i + 3]: the
        second system's, [5i + 4] x: the deepening offset), phases into the phase table
        that draw reads. The baked table is made on first use."""
        n = self.num_points
        if self.baked_waves is None:
            self.baked_waves = self._table(5 * n, 4)
        block = np.zeros((n, 5, 4), np.float32)
        block[:, 0, :3] = baked.wave_vector
        block[:, 0, 3] = baked.amplitude
        block[:, 1, :3] = baked.direction
        block[:, 1, 3] = baked.compression
        if baked.offset is not None:
            block[:, 4, 0] = baked.offset
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
                                         self.anchor_phase.read(), self.written.damped.read())
