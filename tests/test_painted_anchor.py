"""The painted waves' start phases (method/anchor.py): a stripe pattern of the painted q in
rest space, used where a smooth painted region winds around a loop of the mesh, and what
crush starts such waves from (the GPU against the numpy reference)."""
from __future__ import annotations

import numpy as np
import pytest

from usdwrinkle.method.anchor import painted_phases, painted_wavelength
from usdwrinkle.reference.crush import crush as crush_reference
from usdwrinkle.reference.relax import wrap
from usdwrinkle.scene.topology import build_topology, vertex_normals

from helpers import gathered_cuff, gpu_fields, point_cache_stage, random_cloth

RADIUS, RINGS, AROUND, AMOUNT, WIDTH = 0.3, 6, 40, 0.6, 0.1


def sleeve_band(q_around: bool = True):
    """A band of a cylinder (RINGS rings of AROUND points, radius RADIUS, along z) with q
    painted around it (or along it): (rest, quads, q)."""
    theta = np.arange(AROUND) * 2 * np.pi / AROUND
    rest = np.array([[RADIUS * np.cos(t), RADIUS * np.sin(t), 0.05 * ring]
                     for ring in range(RINGS) for t in theta])
    quads = np.array([[r * AROUND + a, r * AROUND + (a + 1) % AROUND,
                       (r + 1) * AROUND + (a + 1) % AROUND, (r + 1) * AROUND + a]
                      for r in range(RINGS - 1) for a in range(AROUND)])
    angle = np.tile(theta, RINGS)
    direction = np.stack([-np.sin(angle), np.cos(angle), np.zeros_like(angle)], 1) \
        if q_around else np.tile([0.0, 0.0, 1.0], (len(rest), 1))
    return rest, quads, AMOUNT * direction


def phases_of(rest, quads, q, width=WIDTH):
    topology = build_topology(np.full(len(quads), 4), quads.ravel(), rest)
    return painted_phases(rest, vertex_normals(rest, topology), topology.neighbor_offsets,
                          topology.neighbor_indices, q, np.full(len(rest), width))


def test_a_loop_painted_around_a_sleeve_winds_as_often_as_it_is_long():
    """Around each ring the start phase winds round(C / L) times (C the circumference, L
    the wavelength the paint gives), and between neighbours it advances by the paint's
    wave number times the edge, away from where the search's two fronts met."""
    rest, quads, q = sleeve_band()
    out = phases_of(rest, quads, q)
    length = painted_wavelength(np.array([AMOUNT]), np.array([WIDTH]))[0]
    assert length == pytest.approx(1.5 * WIDTH)  # the gather 1 / (1 - 0.36), capped at 1.5
    turns = 2 * np.pi * RADIUS / length
    chord = 2 * RADIUS * np.sin(np.pi / AROUND)
    # the rings at the band's edges have their normals tilted by its quads' diagonals
    inner = slice(AROUND, (RINGS - 1) * AROUND)
    np.testing.assert_allclose(out[inner, :3], q[inner] / AMOUNT, atol=1e-6)
    for ring in range(RINGS):
        phase = out[ring * AROUND:(ring + 1) * AROUND, 3].astype(np.float64)
        step = wrap(np.roll(phase, -1) - phase)
        assert step.sum() / (2 * np.pi) == pytest.approx(round(turns), abs=1e-3)
        assert np.median(step) == pytest.approx(chord * 2 * np.pi / length, rel=0.01)


def test_paint_that_does_not_wind_keeps_the_anchored_start():
    """q along the sleeve (rings of crests): (2pi/L) d.X is consistent there, and the table
    says so with zeros; q painted at random is noise, not a stripe pattern, and gets zeros
    too; an unpainted mesh as well."""
    rest, quads, q = sleeve_band(q_around=False)
    assert not phases_of(rest, quads, q).any()
    assert not phases_of(rest, quads, np.zeros_like(q)).any()
    rest, _, faces, q = random_cloth(3)
    topology = build_topology(np.full(len(faces), 3), faces.ravel(), rest)
    out = painted_phases(rest, vertex_normals(rest, topology), topology.neighbor_offsets,
                         topology.neighbor_indices, q, np.full(len(rest), 0.2))
    assert not out.any()


def test_crush_starts_a_painted_loop_from_its_stripe_pattern(gl_context):
    """The GPU's start phases (no relaxation) are the reference's, which wind round(C / L)
    times around each ring (each phase read along q: crush's direction d has the sign of
    its largest component, so half the ring's phases are along -q); the old start,
    (2pi/L) d.X, wound 0 times."""
    rest, quads, q = sleeve_band()
    rest32 = rest.astype(np.float32)
    stage = point_cache_stage(rest32, {1: rest32}, np.full(len(quads), 4), quads.ravel(),
                              q=q.astype(np.float32), width=WIDTH, relax_iterations=0)
    ours, record = gpu_fields(gl_context, stage)
    ref = crush_reference(rest32, rest32, record.topology, q, record.params.width,
                          slack=record.params.slack, coarsening=record.params.coarsening)
    assert (ref["amplitude"] > 0).all()
    np.testing.assert_allclose(wrap(ours["phase"] - ref["phase"]), 0.0, atol=1e-4)
    # the paint coarsens its folds up to the cap: 1.5 here (the stage is in centimetres,
    # USD's fallback, so the band's radius is 3 mm and W 1 mm, far short of the 3.4 cm a
    # tube that tight folds at)
    cap = record.params.coarsening
    np.testing.assert_allclose(cap, 1.5, rtol=1e-5)
    length = painted_wavelength(np.array([AMOUNT]), np.array([WIDTH]), cap[0])[0]
    along_q = np.where(np.sum(ours["direction"] * q, axis=1) < 0, -1.0, 1.0)
    for ring in range(RINGS):
        phase = (along_q * ours["phase"])[ring * AROUND:(ring + 1) * AROUND]
        winding = wrap(np.roll(phase, -1) - phase).sum() / (2 * np.pi)
        assert winding == pytest.approx(round(2 * np.pi * RADIUS / length), abs=1e-3)


def curved_of(rest, quads, width=WIDTH):
    from usdwrinkle.method.anchor import curved_phases
    from usdwrinkle.scene.topology import rest_tangents

    topology = build_topology(np.full(len(quads), 4), quads.ravel(), rest)
    normals = vertex_normals(rest, topology)
    return curved_phases(rest, normals, rest_tangents(normals), topology.neighbor_offsets,
                         topology.neighbor_indices, np.full(len(rest), width))


def test_a_tube_nobody_painted_starts_from_a_stripe_around_itself():
    """method/anchor.curved_phases: on the band of a cylinder the direction is the one it
    curves along (around it), and the phase winds round(C / W) times around each ring,
    advancing 2 pi / W times the edge; on a flat sheet (nothing curves) and on random
    cloth there is none."""
    width = 0.27  # 7 waves around (6.98), 1.1 rad an edge: each step is unambiguous
    rest, quads, q = sleeve_band()
    out = curved_of(rest, quads, width)
    inner = slice(AROUND, (RINGS - 1) * AROUND)
    around = q[inner] / AMOUNT
    np.testing.assert_allclose(np.abs(np.sum(out[inner, :3] * around, 1)), 1.0, atol=1e-4)
    turns = 2 * np.pi * RADIUS / width
    chord = 2 * RADIUS * np.sin(np.pi / AROUND)
    sign = np.sign(np.sum(out[:, :3] * np.tile(around[:AROUND], (RINGS, 1)), 1))
    for ring in range(1, RINGS - 1):
        part = slice(ring * AROUND, (ring + 1) * AROUND)
        phase = (sign[part] * out[part, 3]).astype(np.float64)  # along "around" throughout
        step = wrap(np.roll(phase, -1) - phase)
        assert step.sum() / (2 * np.pi) == pytest.approx(round(turns), abs=1e-3)
        assert np.median(step) == pytest.approx(chord * 2 * np.pi / width, rel=0.01)
    flat = np.array([[x, y, 0.0] for y in range(6) for x in range(8)], np.float64) * 0.05
    quads_flat = np.array([[r * 8 + c, r * 8 + c + 1, (r + 1) * 8 + c + 1, (r + 1) * 8 + c]
                           for r in range(5) for c in range(7)])
    assert not np.any(curved_of(flat, quads_flat))


def gathered_cuff_ring(tmp_path, shift: float) -> np.ndarray:
    """A cuff (helpers.gathered_cuff, as tests/test_deepen.py's) gathered to 0.6 of its
    circumference from the shot's first frame (a garment whose rest shape is the
    ungathered one: a cold start), its axis
    ``shift`` from the mesh's origin; baked with --geometry: the displaced mesh's radius
    around its middle ring, sorted by angle, less its mean."""
    from pxr import Usd, UsdGeom

    from usdwrinkle.cli.main import main

    rest, counts, indices, _ = gathered_cuff()
    move = np.array([shift, 0.0, 0.0])
    posed = (gathered_cuff(0.6)[0] + move).astype(np.float32)
    stage = point_cache_stage((rest + move).astype(np.float32), {1: posed, 2: posed}, counts,
                              indices, width=0.15)
    source = tmp_path / f"cuff{shift}.usda"
    stage.GetRootLayer().Export(str(source))
    layer = tmp_path / f"cuff{shift}_geometry.usdc"
    assert main(["bake", str(source), str(layer), "--geometry", "--frames", "2",
                 "--quiet"]) == 0
    baked = Usd.Stage.Open(str(layer))
    fine = baked.GetPrimAtPath("/Sheet_wrinkled")
    points = np.asarray(UsdGeom.Mesh(fine).GetPointsAttr().Get(2), np.float64) - move
    middle = np.abs(points[:, 1] - 0.15) < 0.004
    angle = np.arctan2(points[middle, 0], points[middle, 2])
    radius = np.hypot(points[middle, 0], points[middle, 2])[np.argsort(angle)]
    return radius - radius.mean()


def test_a_cuff_gathered_about_its_own_axis_folds_wherever_its_origin_is(gl_context,
                                                                          tmp_path):
    """Section "Gathered tubes" of docs/method.md: the cuff's material-anchored start was 0
    all around with its axis through the mesh's origin, and the relaxation kept it: the
    displaced cuff stood as a smooth tube 1 cm proud (its radius's spread 0.1 mm, measured
    2026-12-06 before the curved start), and with the axis 0.3 away its folds were a mix
    (the strongest harmonic 6 of the ring, 34% of the spectrum). With the curved start
    both fold round(C / W) = 4 times (the rest circumference 0.63 over W 0.15), 57% of
    the spectrum, alike: the start no longer depends on where the origin lies."""
    rings = [gathered_cuff_ring(tmp_path, shift) for shift in (0.0, 0.3)]
    for ring in rings:
        assert ring.std() > 0.01  # folds 2 cm deep, not a smooth tube
        spectrum = np.abs(np.fft.rfft(ring))
        assert int(np.argmax(spectrum)) == 4
        assert spectrum[4] / spectrum.sum() > 0.4
    # alike to within float rounding of the moved points (0.2 mm of 2 cm folds)
    np.testing.assert_allclose(rings[0], rings[1], atol=5e-4)
