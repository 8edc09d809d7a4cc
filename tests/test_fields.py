"""render/fields.py: one mesh's wave fields (issue 25: MeshResources no longer mixes the
fields' ping-pong with geometry, skinning and textures, and no pass flips it by hand)."""
from __future__ import annotations

import numpy as np
import pytest

from usdwrinkle.method.contract import FIELD_TEXELS, FIELD_WAVE_TEXEL
from usdwrinkle.render.fields import WaveFields
from usdwrinkle.render.resources import Table


def owned(ctx):
    """A WaveFields whose tables live in a list, as MeshResources keeps them."""
    tables = []

    def table(count, components, dtype="f4", data=None):
        tables.append(Table(ctx, count, components, dtype, data))
        return tables[-1]

    def drop(t):
        tables.remove(t)
        t.release()

    return WaveFields(5, 7, table, drop), tables


def test_a_frame_writes_one_state_and_reads_another(gl_context):
    waves, tables = owned(gl_context)
    waves.begin(1, 0)
    assert waves.slots == 2
    first, second = waves.state(0), waves.state(1)
    assert waves.current is second.fields and waves.phase is second.phase
    assert waves.history is first and first.fields.count == FIELD_TEXELS * 5
    waves.begin(0, None)  # a cold start: the history bound is the written state, unread
    assert waves.current is first.fields and waves.history is first
    with pytest.raises(ValueError):
        waves.begin(1, 1)
    waves.begin(3, 1)
    assert waves.slots == 4
    dropped = [*waves.state(2).tables(), *waves.state(3).tables()]
    assert all(t in tables for t in dropped)
    waves.release_slots(2)  # the engine keeps fewer states: their tables are released
    assert waves.slots == 2 and not any(t in tables for t in dropped)
    for t in tables:
        t.release()


def test_a_second_wave_system_relays_the_relax_tables_and_frees_the_old(gl_context):
    waves, tables = owned(gl_context)
    old = [*waves.phasors, waves.edge_rotations]
    assert [t.components for t in waves.phasors] == [2, 2] and waves.edge_rotations.count == 7
    waves.set_systems(2)
    assert waves.systems == 2
    assert [t.components for t in waves.phasors] == [4, 4] and waves.edge_rotations.count == 14
    assert not any(t in tables for t in old)  # released, not kept by the owner
    assert all(t in tables for t in [*waves.phasors, waves.edge_rotations])
    count = len(tables)
    waves.set_systems(2)  # unchanged: nothing re-made
    assert len(tables) == count
    for t in tables:
        t.release()


def test_read_gives_the_fields_of_the_current_table(gl_context):
    waves, tables = owned(gl_context)
    points = Table(gl_context, 5, 4, data=np.arange(20, dtype=np.float32).reshape(5, 4))
    block = np.zeros((5, FIELD_TEXELS, 4), np.float32)
    block[:, FIELD_WAVE_TEXEL, 3] = [0.1, 0.2, 0.3, 0.4, 0.5]  # the wave texel's w: amplitude
    waves.begin(1, None)
    waves.current.write(block.reshape(-1, 4))
    fields = waves.read(points)
    np.testing.assert_allclose(fields.amplitude, [0.1, 0.2, 0.3, 0.4, 0.5], rtol=1e-6)
    np.testing.assert_allclose(fields.points, np.arange(20).reshape(5, 4)[:, :3])
    waves.begin(0, 1)  # the other state: still zeros
    assert not waves.read(points).amplitude.any()
    for t in [*tables, points]:
        t.release()
