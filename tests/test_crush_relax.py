"""Crush and relax: GPU against the numpy references, and analytic sheets."""
from __future__ import annotations

import numpy as np
import pytest

from usdwrinkle.engine import WrinkleEngine
from usdwrinkle.method.contract import FIELD_TEXELS
from usdwrinkle.reference.crush import crush as crush_reference
from usdwrinkle.reference.relax import phase_misfit, relax_shot, wrap
from usdwrinkle.render.delegate import COLD_START_FACTOR

from conftest import grid_sheet
from helpers import (
    fold_law,
    gpu_fields,
    interior,
    point_cache_stage,
    random_cloth,
    random_cloth_fields,
    rotation_matrix,
)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_crush_matches_numpy_reference(gl_context, seed):
    _, ours, record, ref = random_cloth_fields(gl_context, seed, relax_iterations=0)
    assert np.all(ours["usable"] == ref["usable"])
    np.testing.assert_allclose(ours["compression"], ref["compression"], atol=2e-4)
    np.testing.assert_allclose(ours["amplitude"], ref["amplitude"], atol=2e-4 * 0.05)
    # the fold as drawn, lowered where the mesh is stretched across the wave (the squashed
    # sphere is, at most of its folding points), to the amplitude's own tolerance (the
    # share alone is steep where the lowered fold starts: sqrt(rho^2 - 1); worst over the
    # three seeds 2.8e-6 on llvmpipe, 3.6e-6 on an NVIDIA H200, where before crush.glsl
    # took the unpainted gather as exactly 1 it was 2.3e-5: rho one ulp above 1)
    folding = ref["amplitude"] > 1e-3
    assert np.mean(ref["drawn"][folding] < 0.99) > 0.2
    np.testing.assert_allclose(ours["amplitude"] * ours["drawn"],
                               ref["amplitude"] * ref["drawn"], atol=2e-4 * 0.05)
    np.testing.assert_allclose(ours["normals"], ref["normals"], atol=1e-4)
    # directions and k are defined where the two eigenvalues differ
    lam = ref["compression"]
    defined = (lam < 0.98) & (ref["amplitude"] > 1e-3)
    assert defined.sum() > 50
    np.testing.assert_allclose(ours["direction"][defined], ref["direction"][defined], atol=2e-3)
    k_ours, k_ref = ours["wave_vector"][defined], ref["wave_vector"][defined]
    rel = np.linalg.norm(k_ours - k_ref, axis=1) / np.linalg.norm(k_ref, axis=1)
    assert np.max(rel) < 2e-3
    assert np.max(np.abs(wrap(ours["phase"][defined] - ref["phase"][defined]))) < 1e-3


def test_relax_matches_numpy_reference(gl_context):
    """A shot of three frames: a cold start, then two warm starts (phase history)."""
    rest, posed, faces, q = random_cloth(3)
    rng = np.random.default_rng(7)
    frames = {1: posed, 2: posed * 0.97 + 0.01 * rng.normal(size=posed.shape),
              3: posed * 0.94 + 0.01 * rng.normal(size=posed.shape)}
    iterations = 6
    stage = point_cache_stage(rest, {f: p.astype(np.float32) for f, p in frames.items()},
                              np.full(len(faces), 3), faces.ravel(), q=q, width=0.2,
                              relax_iterations=iterations)
    engine = WrinkleEngine(stage, ctx=gl_context)
    try:
        engine.compute_frame(3.0)  # replays frames 1 and 2 first
        ours = engine.read_fields("/Sheet").arrays()
        record = engine.meshes["/Sheet"]
    finally:
        engine.release()
    starts = [crush_reference(rest, frames[f], record.topology, q, record.params.width,
                              slack=record.params.slack, coarsening=record.params.coarsening)
              for f in (1, 2, 3)]
    for fields, f in zip(starts, (1, 2, 3), strict=True):
        fields["points"], fields["rest_points"] = frames[f], rest
    ref_phase = relax_shot(starts, record.topology, iterations, COLD_START_FACTOR)[-1]
    wrinkled = starts[-1]["amplitude"] > 1e-3
    assert wrinkled.sum() > 50
    diff = np.abs(wrap(ours["phase"][wrinkled] - ref_phase[wrinkled]))
    assert np.percentile(diff, 99) < 1e-2
    # relaxation lowers the misfit from the material-anchored start
    last = starts[-1]
    before = phase_misfit(last["points"], last["wave_vector"], last["phase"], record.topology,
                          wrinkled)
    after = phase_misfit(last["points"], ours["wave_vector"], ours["phase"], record.topology,
                         wrinkled)
    assert after < 0.5 * before


def _shot_fields(ctx, rest, frames, faces, q, iterations):
    """A point-cached shot's GPU fields per frame (each from the one before)."""
    stage = point_cache_stage(rest, {f: p.astype(np.float32) for f, p in frames.items()},
                              np.full(len(faces), 3), faces.ravel(), q=q, width=0.2,
                              relax_iterations=iterations)
    engine = WrinkleEngine(stage, ctx=ctx)
    out = {}
    try:
        for frame in sorted(frames):
            engine.compute_frame(float(frame))
            out[frame] = engine.read_fields("/Sheet").arrays()
        topology = engine.meshes["/Sheet"].topology
    finally:
        engine.release()
    return out, topology


def _kappa(fields):
    """The material wave vectors (2 pi / L) d3 (rest space) of a frame's GPU fields, from
    its wave numbers and rest directions: what relax's mobility compares."""
    return fields["wavenumber"][:, None] * fields["direction"].astype(np.float64)


def test_a_pose_that_stops_keeps_its_phases(gl_context):
    """Mobility (docs/method.md): frame 3 repeats frame 2's points, so nothing the waves
    are made of changed and the phases stay where frame 2 left them, exactly, as cloth
    that stops keeps its folds. Before, every frame's eight Jacobi steps went on moving
    them towards the relaxation's fixed point (the referee's held sleeve: crests moving
    8.6x the cloth's); with mobility off (every vertex moving fully) they move here too."""
    from usdwrinkle.reference.relax import relax_frame

    rest, posed, faces, q = random_cloth(4)
    frames = {1: rest + 0.5 * (posed - rest), 2: posed, 3: posed.copy()}
    gpu, topology = _shot_fields(gl_context, rest, frames, faces, q, 8)
    wave = (gpu[2]["amplitude"] > 0) & (gpu[3]["amplitude"] > 0)
    assert wave.sum() > 200
    np.testing.assert_array_equal(gpu[3]["phase"][wave], gpu[2]["phase"][wave])
    # the fit reads the phases as phasors (cos, sin here; the steps' own before): rounding
    np.testing.assert_allclose(gpu[3]["wave_vector"], gpu[2]["wave_vector"], rtol=1e-5,
                               atol=1e-5 * np.abs(gpu[2]["wave_vector"]).max())
    # the same step with every vertex fully mobile (the reference without kappa) moves them
    fields = {"points": gpu[3]["points"], "wave_vector": gpu[3]["wave_vector"],
              "amplitude": gpu[3]["amplitude"], "normals": gpu[3]["normals"],
              "phase": gpu[3]["anchor_phase"]}
    state = {"wave_vector": gpu[2]["wave_vector"], "amplitude": gpu[2]["amplitude"],
             "phase": gpu[2]["phase"]}
    crush_k = _shot_fields(gl_context, rest, frames, faces, q, 0)[0][3]
    fields["wave_vector"], fields["amplitude"] = crush_k["wave_vector"], crush_k["amplitude"]
    moved, _ = relax_frame(fields, state, topology, 8)
    assert np.percentile(np.abs(wrap(moved - gpu[2]["phase"]))[wave], 90) > 0.01


def test_mobility_matches_the_reference(gl_context):
    """Frames that change a little: relax moves each vertex by its mobility's share of
    the way, between none and all (reference/relax.py's mobility, fed the GPU's own crush
    output and previous state, the material wave vectors kappa = (2 pi / L) d3 from its
    wave numbers), and the GPU's phases are the reference's."""
    from usdwrinkle.reference.relax import mobility, relax_frame

    rest, posed, faces, q = random_cloth(5)
    frames = {1: posed, 2: posed + 0.004 * np.sin(4 * rest[:, [2, 0, 1]]),
              3: posed + 0.008 * np.sin(4 * rest[:, [2, 0, 1]])}
    iterations = 6
    gpu, topology = _shot_fields(gl_context, rest, frames, faces, q, iterations)
    raw, _ = _shot_fields(gl_context, rest, frames, faces, q, 0)  # crush's own waves

    for frame in (2, 3):
        before, crushed = gpu[frame - 1], raw[frame]
        share = mobility(rest, _kappa(crushed), _kappa(before), crushed["amplitude"],
                         before["amplitude"], topology)
        wave = (crushed["amplitude"] > 0) & (before["amplitude"] > 0)
        partly = wave & (share > 0.05) & (share < 0.95)
        assert partly.sum() > 0.2 * wave.sum(), (partly.sum(), wave.sum())
        fields = {"points": crushed["points"], "wave_vector": crushed["wave_vector"],
                  "amplitude": crushed["amplitude"], "phase": crushed["anchor_phase"],
                  "normals": crushed["normals"], "rest_points": rest,
                  "kappa": _kappa(crushed)}
        state = {"wave_vector": before["wave_vector"], "amplitude": before["amplitude"],
                 "phase": before["phase"], "kappa": _kappa(before)}
        phase, _ = relax_frame(fields, state, topology, iterations)
        diff = np.abs(wrap(gpu[frame]["phase"] - phase))[wave]
        assert np.percentile(diff, 99) < 1e-3, np.percentile(diff, [50, 99, 100])
        # and all of the way, it would be another frame: the test can tell them apart
        full, _ = relax_frame({k: v for k, v in fields.items() if k != "kappa"}, state,
                              topology, iterations)
        assert np.percentile(np.abs(wrap(full - phase))[partly], 90) > 1e-2


def test_a_creep_within_the_dead_band_keeps_the_phases(gl_context):
    """A dead band (docs/method.md): frame 3 moves frame 2's points by a fraction of a
    millimetre on a metre of cloth, as cloth creeps after its pose stops. Its waves change
    (crush's wave vectors differ), but no edge's phase difference changes by more than
    MOBILITY_DEADBAND's share, so every mobility is 0 and the phases stay exactly where
    frame 2 left them; a creep 30 times larger moves some of them."""
    from usdwrinkle.method.contract import MOBILITY_DEADBAND, MOBILITY_PHASE
    from usdwrinkle.reference.relax import mobility

    rest, posed, faces, q = random_cloth(4)
    start = rest + 0.5 * (posed - rest)
    for size, keeps in ((2e-5, True), (6e-4, False)):
        frames = {1: start, 2: posed, 3: posed + size * np.sin(4 * rest[:, [2, 0, 1]])}
        gpu, topology = _shot_fields(gl_context, rest, frames, faces, q, 8)
        raw, _ = _shot_fields(gl_context, rest, frames, faces, q, 0)
        wave = (gpu[2]["amplitude"] > 0) & (gpu[3]["amplitude"] > 0)
        assert wave.sum() > 200
        assert not np.array_equal(raw[3]["wave_vector"][wave], raw[2]["wave_vector"][wave])

        share = mobility(rest, _kappa(raw[3]), _kappa(gpu[2]), raw[3]["amplitude"],
                         gpu[2]["amplitude"], topology)
        moved = np.abs(wrap(gpu[3]["phase"] - gpu[2]["phase"]))[wave]
        if keeps:
            assert np.all(share[wave] == 0.0)
            np.testing.assert_array_equal(gpu[3]["phase"][wave], gpu[2]["phase"][wave])
            assert MOBILITY_DEADBAND * MOBILITY_PHASE == pytest.approx(0.005)
        else:
            assert np.mean(share[wave] > 0) > 0.1
            assert np.percentile(moved, 99) > 1e-3


@pytest.mark.parametrize("ratio", [0.5, 0.8, 0.95])
def test_uniform_compression_is_analytic(gl_context, ratio):
    rest, counts, indices = grid_sheet(31, 31, 2.0)
    posed = rest * np.array([ratio, 1, 1], np.float32)
    width = 0.3
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=width)
    ours, record = gpu_fields(gl_context, stage)
    inside = interior(rest, 0.1)
    # the fold law (docs/method.md): the material wavelength coarsens with the excess
    # length 1/r, the wave restores the cloth's length for the default profile
    expected_h, expected_k = fold_law(ratio, width)
    np.testing.assert_allclose(ours["amplitude"][inside], expected_h, rtol=0.01)
    k = ours["wave_vector"][inside]
    np.testing.assert_allclose(np.linalg.norm(k, axis=1), expected_k, rtol=0.01)
    assert np.all(np.abs(k[:, 0]) / np.linalg.norm(k, axis=1) > 0.999)  # k parallel to x
    np.testing.assert_allclose(ours["compression"][inside], ratio, atol=1e-3)
    misfit = phase_misfit(posed, ours["wave_vector"], ours["phase"], record.topology, inside)
    assert misfit < 0.1


def test_wrinkles_finer_than_the_mesh(gl_context):
    """W at half an edge: the exact k.dx prediction keeps the phases consistent."""
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    edge = 2.0 / 20
    posed = rest * np.array([0.7, 1, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=0.5 * edge)
    ours, record = gpu_fields(gl_context, stage)
    inside = interior(rest, 0.15)
    k = np.linalg.norm(ours["wave_vector"][inside], axis=1)
    assert np.all(k * edge * 0.7 > 2 * np.pi)  # more than one wave per posed edge
    misfit = phase_misfit(posed, ours["wave_vector"], ours["phase"], record.topology, inside)
    assert misfit < 0.1


@pytest.mark.parametrize("amount", [0.3, 0.6, 0.9])
def test_painted_q_without_deformation(gl_context, amount):
    rest, counts, indices = grid_sheet(15, 15, 2.0)
    direction = np.array([np.cos(0.4), np.sin(0.4), 0.0])
    q = np.tile(direction * amount, (len(rest), 1)).astype(np.float32)
    stage = point_cache_stage(rest, {1: rest}, counts, indices, q=q, width=0.25)
    ours, _ = gpu_fields(gl_context, stage)
    np.testing.assert_allclose(ours["compression"], 1 - amount ** 2, atol=1e-4)
    d = ours["direction"]
    assert np.all(np.abs(d @ direction) > 0.9999)  # compression along q
    # painting means folds (issue 55): the painted gather is excess length on an
    # uncompressed mesh, so the posed wave is the coarsened material wave, not finer
    expected_h, expected_k = fold_law(1 - amount ** 2, 0.25, geometric=1.0)
    np.testing.assert_allclose(ours["amplitude"], expected_h, rtol=0.01)
    np.testing.assert_allclose(np.linalg.norm(ours["wave_vector"], axis=1), expected_k,
                               rtol=0.01)
    assert expected_k <= 2 * np.pi / 0.25 + 1e-9  # never finer than W


def test_rigid_motion_changes_nothing(gl_context):
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([0.75, 1, 1], np.float32)
    posed[:, 2] += 0.2 * np.sin(posed[:, 0] * 2)  # some bending too
    rot = rotation_matrix([0.3, -0.8, 0.5], 1.1)
    moved = (posed @ rot.T + np.array([3.0, -2.0, 1.0])).astype(np.float32)
    base, _ = gpu_fields(gl_context, point_cache_stage(rest, {1: posed}, counts, indices,
                                                       width=0.3))
    turned, _ = gpu_fields(gl_context, point_cache_stage(rest, {1: moved}, counts, indices,
                                                         width=0.3))
    wrinkled = base["amplitude"] > 1e-3
    assert wrinkled.sum() > 100
    rel_h = np.abs(turned["amplitude"] - base["amplitude"])[wrinkled] / base["amplitude"][wrinkled]
    k0 = np.linalg.norm(base["wave_vector"], axis=1)[wrinkled]
    k1 = np.linalg.norm(turned["wave_vector"], axis=1)[wrinkled]
    assert rel_h.max() < 0.005
    assert (np.abs(k1 - k0) / k0).max() < 0.005
    # and k turns with the sheet
    np.testing.assert_allclose(turned["wave_vector"][wrinkled],
                               base["wave_vector"][wrinkled] @ rot.T, rtol=0, atol=1e-2 * k0.max())


def test_degenerate_geometry_gives_no_wrinkle_and_no_nan(gl_context):
    # collinear strip, coincident points, an isolated vertex
    rest = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0], [3, 0, 0], [5, 5, 5]],
                    np.float32)
    counts = [3, 3]
    indices = [0, 1, 2, 2, 3, 4]
    stage = point_cache_stage(rest, {1: rest * 0.5}, counts, indices, width=0.5)
    ours, _ = gpu_fields(gl_context, stage)
    for name, value in ours.items():
        assert np.all(np.isfinite(value)), name
    np.testing.assert_array_equal(ours["compression"], 1.0)
    np.testing.assert_array_equal(ours["amplitude"], 0.0)


def test_every_wave_of_cesium_man_is_finite_cold_and_with_history(gl_context, corpus):
    """The fields after relax's fit, every frame 1..24 of CesiumMan (in metres, its faint
    onset waves a few micrometres high), computed with the phase history and from a cold
    start at each frame: finite, and no amplitude beyond the mesh's own size. On an NVIDIA
    H200 (2026-12-04) the cold frame 23 drew a NaN wave of amplitude 7e26 at one point,
    whose only wrinkled neighbour stood 5e-6 m high across an edge the wave barely
    sampled (a fold the GPU's division drew where nothing folds: crush.glsl's gather): the
    fit divided its condition by the trace cubed, below float32's smallest normal number
    (relax.glsl now divides the equations by their trace first)."""
    from benchmarks.crests_across_gl import tables

    largest = 0.0
    for cold in (False, True):
        # CesiumMan's one mesh, in metres (crests_across_gl's stage), frame by frame
        for frame, (points, fields, *_) in tables(cold, gl_context, "cesium_man").items():
            fields = fields.reshape(-1, FIELD_TEXELS, 4)
            assert np.isfinite(fields).all(), (frame, cold)
            size = float(np.ptp(points[:, :3], axis=0).max())
            amplitude = float(fields[:, [1, 3], 3].max())
            assert amplitude < 0.1 * size, (frame, cold, amplitude)
            largest = max(largest, amplitude)
    assert largest > 1e-3  # the shot wrinkles (millimetres at least)


def test_a_point_of_huge_valence_reads_a_capped_ring(gl_context):
    """Issue 54, finding 15: a pass loops over a point's ring serially, so the centre of a
    fan (2 million triangles) set a whole pass's time, every frame and relax iteration.
    Beyond MAX_RING a point reads MAX_RING of its ring, evenly spaced: the GPU and the
    numpy reference agree on that, and a point of ordinary valence reads its whole ring."""
    from usdwrinkle.process.limits import MAX_RING
    from usdwrinkle.scene.topology import build_topology

    n = 5000  # a fan of n triangles about the centre, compressed along x
    angle = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    rest = np.concatenate([[[0.0, 0.0, 0.0]],
                           np.stack([np.cos(angle), np.sin(angle), 0 * angle], 1)])
    faces = np.stack([np.zeros(n, int), np.arange(1, n + 1), np.roll(np.arange(1, n + 1), -1)],
                     1)
    posed = rest * [0.6, 1.0, 1.0] + [0.0, 0.0, 0.05] * np.cos(3 * rest[:, :1])
    topology = build_topology(np.full(n, 3), faces.ravel(), rest)
    ring_offsets, ring, triangle_offsets, triangles = topology.rings()
    assert np.diff(ring_offsets)[0] == MAX_RING and np.diff(triangle_offsets)[0] == MAX_RING
    full = topology.neighbor_indices[topology.neighbor_offsets[0]:topology.neighbor_offsets[1]]
    np.testing.assert_array_equal(ring[:MAX_RING], full[(np.arange(MAX_RING) * n) // MAX_RING])
    np.testing.assert_array_equal(np.diff(ring_offsets)[1:],  # the rim: whole rings
                                  np.diff(topology.neighbor_offsets)[1:])
    stage = point_cache_stage(rest.astype(np.float32), {1: posed.astype(np.float32)},
                              np.full(n, 3), faces.ravel(), width=0.2, relax_iterations=0)
    ours, record = gpu_fields(gl_context, stage)
    ref = crush_reference(rest, posed, record.topology, np.zeros_like(rest),
                          record.params.width, slack=record.params.slack,
                          hold=record.params.hold, coarsening=record.params.coarsening)
    np.testing.assert_allclose(ours["normals"][0], ref["normals"][0], atol=1e-5)
    np.testing.assert_allclose(ours["compression"][0], ref["compression"][0], atol=1e-4)
    assert ref["compression"][0] == pytest.approx(0.6, abs=0.01)


def _sheet_wave(twist: float):
    """A flat 21 x 21 sheet, one wave k along x everywhere, amplitude 0.02, and phases
    that advance ``twist`` times as fast as k: (normals, k, a, phases, topology)."""
    from usdwrinkle.scene.topology import build_topology

    rest, counts, indices = grid_sheet(21, 21, 2.0)
    points = rest.astype(np.float64)
    topology = build_topology(counts, indices, rest)
    n = len(points)
    k = np.tile([20.0, 0.0, 0.0], (n, 1))
    normals = np.tile([0.0, 0.0, 1.0], (n, 1))
    return points, normals, k, np.full(n, 0.02), twist * 20.0 * points[:, 0], topology


def test_the_fit_keeps_a_wave_that_its_phases_draw():
    """relax's fit (reference/relax.py, fit): phases that agree with k leave k and the
    amplitude as they are; phases that advance 1.3x as fast make k 1.3x as long and the
    amplitude 1/1.3, the same slope a|k| (the length the fold law restores); phases that
    advance slower leave k (only shorter waves are fitted). Only where the folds coarsen:
    times smoothstep(1, 1.5, the point's coarsening cap)."""
    from usdwrinkle.reference.relax import fit

    points, normals, k, a, phases, topology = _sheet_wave(1.0)
    fitted, amplitude = fit(points, normals, k, a, phases, topology)
    np.testing.assert_allclose(fitted, k, atol=1e-9)
    np.testing.assert_allclose(amplitude, a, atol=1e-12)
    points, normals, k, a, phases, topology = _sheet_wave(1.3)
    fitted, amplitude = fit(points, normals, k, a, phases, topology)
    np.testing.assert_allclose(fitted, 1.3 * k, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(amplitude * np.linalg.norm(fitted, axis=1), 0.02 * 20.0,
                               rtol=1e-9)
    # where the folds do not coarsen (cap 1) there is no twist to follow: k stays; half
    # way (cap 1.25, smoothstep(1, 1.5) = 0.5) half the fit
    points, normals, k, a, phases, topology = _sheet_wave(1.3)
    for cap, expected in ((1.0, 1.0), (1.25, 1.15), (1.5, 1.3)):
        fitted, amplitude = fit(points, normals, k, a, phases, topology,
                                np.full(len(points), cap))
        np.testing.assert_allclose(fitted, expected * k, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(amplitude * expected, a, rtol=1e-9)
    # slower phases, and beyond FIT_RANGE (not taken as one wave): k and a stay
    for twist in (0.8, 2.5):
        points, normals, k, a, phases, topology = _sheet_wave(twist)
        fitted, amplitude = fit(points, normals, k, a, phases, topology)
        np.testing.assert_allclose(fitted, k, atol=1e-9)
        np.testing.assert_allclose(amplitude, a, atol=1e-12)


@pytest.mark.parametrize("meters", [None, 0.8])
def test_the_fit_matches_numpy_reference(gl_context, meters):
    """The GPU's fitted waves (relax.glsl's FIT) against reference/relax.fit fed the same
    relaxed phases and crush's waves (the numpy reference). At 0.8 m a unit the squashed
    sphere's W (0.16 m) nears its tube's wavelength, its coarsening caps fall to 1.19-1.32,
    and the fit, scaled by smoothstep(1, 1.5, cap), follows them as the reference does."""
    from usdwrinkle.reference.relax import fit

    posed, ours, record, law = random_cloth_fields(gl_context, 3, relax_iterations=6,
                                                   meters=meters)
    caps = record.params.coarsening
    assert (1.1 < caps.min() and caps.max() < 1.4) if meters else caps.min() == 1.5
    k, a = fit(posed, ours["normals"], law["wave_vector"], law["amplitude"], ours["phase"],
               record.topology, record.params.coarsening)
    wrinkled = law["amplitude"] > 1e-3
    assert wrinkled.sum() > 50
    length = np.linalg.norm(k, axis=1)
    rel = np.linalg.norm(ours["wave_vector"] - k, axis=1)[wrinkled] / length[wrinkled]
    assert np.percentile(rel, 99) < 1e-2, np.percentile(rel, 99)
    np.testing.assert_allclose(ours["amplitude"][wrinkled], a[wrinkled], atol=2e-4 * 0.05,
                               rtol=1e-2)
    # and the fit did something: k changed by more than 1% at some of the points
    changed = np.linalg.norm(k - law["wave_vector"], axis=1)[wrinkled] / length[wrinkled]
    assert np.mean(changed > 1e-2) > 0.05


def test_the_fit_is_the_same_in_any_units(gl_context):
    """The same cloth in units 100x smaller (a shot in metres instead of centimetres):
    the fitted wave vectors are 100x longer and the heights 100x lower, to float32
    precision (the fit's normal equations keep their digits at any scale)."""
    rest, posed, faces, q = random_cloth(3)
    fields = []
    for scale in (1.0, 0.01):
        stage = point_cache_stage((rest * scale).astype(np.float32),
                                  {1: (posed * scale).astype(np.float32)},
                                  np.full(len(faces), 3), faces.ravel(), q=q,
                                  width=0.2 * scale, relax_iterations=6)
        fields.append(gpu_fields(gl_context, stage)[0])
    big, small = fields
    wrinkled = big["amplitude"] > 1e-3
    assert wrinkled.sum() > 50
    length = np.linalg.norm(big["wave_vector"], axis=1)[wrinkled]
    rel = np.linalg.norm(small["wave_vector"] * 0.01 - big["wave_vector"], axis=1)[wrinkled]
    assert np.percentile(rel / length, 99) < 1e-3, np.percentile(rel / length, 99)
    np.testing.assert_allclose(small["amplitude"][wrinkled] * 100, big["amplitude"][wrinkled],
                               rtol=1e-3)


def test_mobility_counts_the_turn_less_than_the_wave_number():
    """The turn counts less (docs/method.md): the change of the material wave vector is
    split into the wave number's part and the direction's. On a flat grid whose waves
    all change alike, an interior vertex's mobility is the largest ring edge's phase
    change over MOBILITY_PHASE for a wave number that changes, over MOBILITY_TURN for a
    direction that turns, and their sum for both, less the dead band (MOBILITY_DEADBAND,
    the share rescaled to reach 1 where it did), each computed by hand here; a change
    within the dead band keeps the phases exactly."""
    from usdwrinkle.authoring.builders import grid_sheet
    from usdwrinkle.method.contract import MOBILITY_DEADBAND, MOBILITY_PHASE, MOBILITY_TURN
    from usdwrinkle.reference.relax import mobility, ring_edges
    from usdwrinkle.scene.topology import build_topology

    points, counts, indices = grid_sheet(9, 9, 2.0)
    points = np.asarray(points, np.float64)
    topology = build_topology(counts, indices, points)
    n = len(points)
    ones = np.ones(n)
    w, step, turn = 40.0, 0.1, np.radians(5.0)  # rad/m, rad/m, rad: a change of each
    before = np.tile([w, 0.0, 0.0], (n, 1))
    grown = np.tile([w + step, 0.0, 0.0], (n, 1))
    turned = np.tile([w * np.cos(turn), w * np.sin(turn), 0.0], (n, 1))
    both = np.tile([(w + step) * np.cos(turn), (w + step) * np.sin(turn), 0.0], (n, 1))
    src, dst = ring_edges(topology)
    edges = points[dst] - points[src]

    def largest(change: np.ndarray) -> np.ndarray:
        out = np.zeros(n)
        np.maximum.at(out, src, np.abs(edges @ change))
        return out

    d_now = np.array([np.cos(turn), np.sin(turn), 0.0])
    by_wave = largest(np.array([step, 0.0, 0.0])) / MOBILITY_PHASE
    by_turn = largest(w * (d_now - [1.0, 0.0, 0.0])) / MOBILITY_TURN
    by_both = largest(step * d_now) / MOBILITY_PHASE + by_turn
    inner = np.flatnonzero((np.abs(points[:, 0]) < 0.9) & (np.abs(points[:, 1]) < 0.9))
    assert len(inner) > 20
    for now, moved in ((grown, by_wave), (turned, by_turn), (both, by_both)):
        share = mobility(points, now, before, ones, ones, topology)
        assert 0.1 < moved[inner].max() < 0.98  # partly mobile: the test can tell
        expected = (moved - MOBILITY_DEADBAND) / (1.0 - MOBILITY_DEADBAND)
        np.testing.assert_allclose(share[inner], expected[inner], rtol=1e-9)
    # within the dead band: a wave number that changes a tenth as much keeps the phases
    assert MOBILITY_DEADBAND == 0.05 and 0.0 < 0.1 * by_wave[inner].max() < MOBILITY_DEADBAND
    creep = np.tile([w + 0.1 * step, 0.0, 0.0], (n, 1))
    assert np.all(mobility(points, creep, before, ones, ones, topology)[inner] == 0.0)
    # the same change of an edge's phase difference moves the phases MOBILITY_TURN /
    # MOBILITY_PHASE times more from the wave number than from the turn
    assert MOBILITY_TURN / MOBILITY_PHASE >= 10
    # no wave now, or none before: the vertex relaxes fully
    gone = ones.copy()
    gone[inner[0]] = 0.0
    assert mobility(points, grown, before, gone, ones, topology)[inner[0]] == 1.0
    assert mobility(points, grown, before, ones, gone, topology)[inner[0]] == 1.0


def plane_wave_grid():
    """A flat 9 x 9 grid with a plane wave along x (40 rad per unit) and the phase it asks
    for: (points, topology, the centre vertex, w, k, phase, ring edges' src, dst)."""
    from usdwrinkle.authoring.builders import grid_sheet
    from usdwrinkle.reference.relax import ring_edges
    from usdwrinkle.scene.topology import build_topology

    points, counts, indices = grid_sheet(9, 9, 2.0)
    points = np.asarray(points, np.float64)
    topology = build_topology(counts, indices, points)
    centre = int(np.argmin(np.linalg.norm(points, axis=1)))
    w = 40.0
    k = np.tile([w, 0.0, 0.0], (len(points), 1))
    src, dst = ring_edges(topology)
    return points, topology, centre, w, k, w * points[:, 0], src, dst


def test_a_ring_neighbour_pulls_only_with_a_wave_along_the_vertex_s():
    """relax (and its seed and fit) weigh a neighbour by its amplitude times
    smoothstep(0, RELAX_ALIGNED, |cos|) of the angle between the wave vectors; the
    mobility counts a ring edge by smoothstep(0, MOBILITY_RING, a_j / a_i) times the same
    alignment (docs/method.md, "Sensitivity": a neighbour at right angles, or one without
    a wave, has nothing to say about the vertex's phase). On a flat grid of waves along x:
    a vertex whose wave runs along y keeps its phase, one at 45 degrees is pulled to its
    neighbours'; a neighbour with no wave whose direction turns moves no mobility, one
    with a wave does."""
    from usdwrinkle.method.contract import MOBILITY_RING, RELAX_ALIGNED, WEIGHT_FLOOR
    from usdwrinkle.reference.relax import aligned, mobility, relax

    points, topology, centre, w, k, phase, src, dst = plane_wave_grid()
    n = len(points)
    amplitude = np.full(n, 0.01)
    assert RELAX_ALIGNED == 0.2 and MOBILITY_RING == 0.25
    for turn, pulled in ((90.0, False), (45.0, True)):
        turned = k.copy()
        turned[centre] = w * np.array([np.cos(np.radians(turn)), np.sin(np.radians(turn)), 0])
        np.testing.assert_allclose(aligned(turned, src, dst)[src == centre],
                                   0.0 if not pulled else 1.0, atol=1e-12)
        start = phase.copy()
        start[centre] += 2.0  # off the ring's phase by 2 rad
        out = relax(points, turned, amplitude, start, topology, 20)
        off = abs(wrap(out[centre] - start[centre]))
        # at right angles only WEIGHT_FLOOR pulls: 20 steps of 6 floors over its own 0.01
        floors = 20 * 6 * WEIGHT_FLOOR / 0.01 * 2.0
        assert (off > 1.0) if pulled else (off < floors), (turn, off, floors)
    # the mobility: nothing changes but a neighbour's direction, turned by 30 degrees
    turned = k.copy()
    neighbour = int(dst[src == centre][0])
    turned[neighbour] = w * np.array([np.cos(np.radians(30)), np.sin(np.radians(30)), 0.0])
    ones = np.ones(n)
    moved = mobility(points, turned, k, ones, ones, topology)[centre]
    assert moved > 0.5  # the turn reaches the vertex through its ring
    for gone in ("now", "before"):
        without = ones.copy()
        without[neighbour] = 0.0
        a_now, a_before = (without, ones) if gone == "now" else (ones, without)
        assert mobility(points, turned, k, a_now, a_before, topology)[centre] == 0.0


def test_a_point_without_a_wave_is_pulled_only_along_its_own_direction():
    """A point without a wave has a phase only as the start of a wave that may grow in
    there; a neighbour's wave pulls it by smoothstep(FLOOR_ALIGNED_FROM, FLOOR_ALIGNED,
    |cos|) (fully within 18 degrees, not at all beyond 46), where a point with a wave is
    pulled fully within 78. Beside the painted loop, waves at 84-88 degrees pulled such
    points a million times harder than the floor, and the elbow's first waves inherited a
    drift that means nothing at right angles (docs/method.md, "Three couplings"). On a flat
    grid of waves along x, a bare centre turned 60 degrees keeps its phase, one turned 10
    degrees is pulled to its neighbours'; with a wave, the 60-degree one is pulled too."""
    from usdwrinkle.method.contract import FLOOR_ALIGNED, FLOOR_ALIGNED_FROM
    from usdwrinkle.reference.relax import aligned, relax

    assert (FLOOR_ALIGNED_FROM, FLOOR_ALIGNED) == (0.7, 0.95)
    points, topology, centre, w, k, phase, src, dst = plane_wave_grid()
    n = len(points)
    for turn, own, pulled in ((60.0, 0.0, False), (10.0, 0.0, True), (60.0, 0.01, True)):
        turned = k.copy()
        turned[centre] = w * np.array([np.cos(np.radians(turn)), np.sin(np.radians(turn)), 0])
        amplitude = np.full(n, 0.01)
        amplitude[centre] = own
        bare = ~(amplitude > 0)
        cos = abs(np.cos(np.radians(turn)))
        t = np.clip((cos - FLOOR_ALIGNED_FROM) / (FLOOR_ALIGNED - FLOOR_ALIGNED_FROM), 0, 1)
        expected = t * t * (3 - 2 * t) if own == 0 else 1.0
        np.testing.assert_allclose(aligned(turned, src, dst, bare)[src == centre], expected,
                                   atol=1e-12)
        start = phase.copy()
        start[centre] += 2.0
        out = relax(points, turned, amplitude, start, topology, 20)
        off = abs(wrap(out[centre] - start[centre]))
        assert (off > 1.0) if pulled else (off < 1e-9), (turn, own, off)
