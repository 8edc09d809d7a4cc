"""The fold law (usdwrinkle/method/folds.py, crush.glsl; issue 55): inextensible waves whose
material wavelength coarsens with compression, that never pass through the surface, and
painting that makes folds. Against analytic sheets, numpy and the baked geometry."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from usdwrinkle import api
from usdwrinkle.geometry.measure import self_intersections, triangle_areas
from usdwrinkle.geometry.subdivide import fine_point_count, subdivide
from usdwrinkle.method.contract import COARSENING_MAX
from usdwrinkle.method.folds import length_of, material_wavelength, restored, slope_table
from usdwrinkle.method.profiles import PRESETS, profile_preset

from conftest import grid_sheet
from helpers import fold_law, point_cache_stage

SAMPLES = Path(__file__).resolve().parents[1] / "sample_stages"
STAGES = ("shirt", "zeppelin", "curtain", "flag", "pillow", "pull")


@pytest.mark.parametrize("name", list(PRESETS))
def test_every_profile_restores_the_length_it_is_given(name):
    """The slope table of each preset gives a wave exactly sqrt(1 + u^2) times as long as
    its posed length (the inextensible law); the triangle's is the paper's zigzag,
    a|k| = (pi / 2) u."""
    from usdwrinkle.method.contract import SLOPE_SAMPLES, SLOPE_STEP
    from usdwrinkle.method.folds import gradient_of

    height = profile_preset(name)
    table = slope_table(height)
    u = np.arange(SLOPE_SAMPLES) * SLOPE_STEP
    np.testing.assert_allclose(length_of(gradient_of(height), table), np.sqrt(1 + u * u),
                               rtol=1e-6)
    if name == "triangle":  # its sampled corners are a little round: within 1%
        np.testing.assert_allclose(table[1:], np.pi / 2 * u[1:], rtol=0.01)


def test_the_material_wavelength_coarsens_and_saturates():
    """L = W min(rho^a, L_max): with a = 1 a uniformly compressed sheet keeps its posed
    wavelength at W (r L = W) until the material wavelength reaches L_max W."""
    from usdwrinkle.method.contract import COARSENING_EXPONENT

    rho = np.array([1.0, 1.05, 1.2, 1.5, 3.0, 20.0])
    law = material_wavelength(0.1, rho)
    np.testing.assert_allclose(law, 0.1 * np.minimum(rho ** COARSENING_EXPONENT,
                                                     COARSENING_MAX))
    assert np.all(np.diff(law) >= 0) and law[-1] == pytest.approx(0.1 * COARSENING_MAX)
    assert COARSENING_EXPONENT == 1.0
    below = rho <= COARSENING_MAX
    np.testing.assert_allclose((law / rho)[below], 0.1)  # the posed wavelength r L = W


def _sheet_geometry(tmp_path, ratio, q=None, width=0.3, levels=4, across=1.0):
    rest, counts, indices = grid_sheet(21, 21, 2.0)
    posed = rest * np.array([ratio, across, 1], np.float32)
    stage = point_cache_stage(rest, {1: posed}, counts, indices, width=width, q=q)
    path = tmp_path / "sheet.usda"
    stage.GetRootLayer().Export(str(path))
    layer = api.bake(path, tmp_path / "geo.usda", frames=[1], geometry=True, levels=levels)
    baked = Usd.Stage.Open(layer)
    fine = UsdGeom.Mesh(baked.GetPrimAtPath("/Sheet_wrinkled"))
    points = np.asarray(fine.GetPointsAttr().Get(1), np.float64)
    faces = np.asarray(fine.GetFaceVertexIndicesAttr().Get(), np.int64).reshape(-1, 3)
    tri = np.asarray(indices).reshape(-1, 4)
    coarse = np.concatenate([tri[:, [0, 1, 2]], tri[:, [0, 2, 3]]])
    rest_fine = subdivide(rest, coarse, levels)
    return points, faces, rest_fine


@pytest.mark.parametrize("ratio", [0.5, 0.7, 0.9])
def test_the_wrinkled_sheet_keeps_its_rest_area(gl_context, tmp_path, ratio):
    """Inextensibility as a law (issue 55): on a sheet compressed by r, the displaced
    surface's area equals the rest area (within the fine mesh's sampling, 2%), away from
    the open border where the 1-ring is one-sided."""
    points, faces, rest = _sheet_geometry(tmp_path, ratio)
    centre = np.abs(rest.points[faces].mean(axis=1)[:, :2]).max(axis=1) < 0.6
    area = triangle_areas(points, faces)[centre].sum()
    rest_area = triangle_areas(rest.points, faces)[centre].sum()
    assert area / rest_area == pytest.approx(1.0, abs=0.02), area / rest_area
    assert len(self_intersections(points, faces)) == 0


@pytest.mark.parametrize("ratio, across", [(0.6, 0.85), (0.5, 0.6), (0.6, 1.2), (0.5, 1.6)])
def test_a_sheet_compressed_both_ways_keeps_its_area(gl_context, tmp_path, ratio, across):
    """The area across (docs/method.md): on a sheet compressed by r along x and by r2
    across, the surface restores the area, r r2 rho_A = 1, where r2 lies in
    [ACROSS_MIN, 1] (a compression across deepens the fold); below, r2 counts as
    ACROSS_MIN. A stretch across lowers the drawn fold only beyond STRETCH_ONSET (a
    wrinkling cloth's own stretch): r2 counts as r2 / STRETCH_ONSET, at most ACROSS_MAX.
    So the surface keeps r2 / counted of its rest area. The wave itself is the uniaxial
    law's (its |k|)."""
    from usdwrinkle.method.contract import ACROSS_MAX, ACROSS_MIN, STRETCH_ONSET

    points, faces, rest = _sheet_geometry(tmp_path, ratio, across=across)
    centre = np.abs(rest.points[faces].mean(axis=1)[:, :2]).max(axis=1) < 0.6
    area = triangle_areas(points, faces)[centre].sum()
    rest_area = triangle_areas(rest.points, faces)[centre].sum()
    counted = (float(np.clip(across, ACROSS_MIN, 1.0)) if across < 1.0
               else float(np.clip(across / STRETCH_ONSET, 1.0, ACROSS_MAX)))
    expected = across / counted
    assert area / rest_area == pytest.approx(expected, abs=0.02), area / rest_area
    assert len(self_intersections(points, faces)) == 0


@pytest.mark.parametrize("amount", [0.5, 0.8])
def test_a_painted_gather_adds_its_length(gl_context, tmp_path, amount):
    """Painted q on an uncompressed sheet: the folds hold what the gather says the cloth
    has, 1 / (1 - |q|^2) of the mesh's area, at most PAINT_GATHER_MAX (0.8 is past it)."""
    from usdwrinkle.method.contract import PAINT_GATHER_MAX
    rest, _, _ = grid_sheet(21, 21, 2.0)
    q = np.tile([amount, 0.0, 0.0], (len(rest), 1)).astype(np.float32)
    points, faces, rest_fine = _sheet_geometry(tmp_path, 1.0, q=q)
    centre = np.abs(rest_fine.points[faces].mean(axis=1)[:, :2]).max(axis=1) < 0.6
    ratio = triangle_areas(points, faces)[centre].sum() / \
        triangle_areas(rest_fine.points, faces)[centre].sum()
    expected = min(1.0 / (1.0 - amount ** 2), PAINT_GATHER_MAX)
    assert ratio == pytest.approx(expected, rel=0.01)


def test_painting_more_makes_bigger_folds_not_finer():
    """Issue 55: painting more over one spot made the waves finer and darker. Along q the
    fold law now grows both the wavelength and the height with the amount."""
    from usdwrinkle.method.contract import PAINT_GATHER_MAX

    amounts = np.array([0.2, 0.4, 0.6, 0.7, 0.8, 0.95, 1.0])
    heights, ks = fold_law(1 - amounts ** 2, 0.1, geometric=np.ones_like(amounts))
    gathered = (1 - amounts ** 2) * PAINT_GATHER_MAX > 1  # beyond, the gather is capped
    assert np.all(np.diff(heights[gathered]) > 0) and np.all(np.diff(heights) >= 0)
    assert np.all(np.diff(ks) <= 1e-12)


@pytest.mark.parametrize("radius", [0.02, 0.2])
def test_the_room_lowers_a_fold_to_half_the_radius_of_a_tube(radius):
    """The room (method/contract.py FOLD_ROOM): a tube compressed along its axis to 0.6 of
    its length folds at the law's height where its radius leaves room (0.2 m, W 0.3),
    and at FOLD_ROOM of its radius where it does not (2 cm): the numpy reference's
    over_room is the law's height over that room, and the drawn amplitude the smaller of
    the two. 96 points around, so the chord's curvature is the circle's within 0.1%."""
    from usdwrinkle.authoring.builders import grid_faces
    from usdwrinkle.method.contract import FOLD_ROOM
    from usdwrinkle.reference.crush import crush
    from usdwrinkle.scene.topology import build_topology

    around, along, length = 96, 21, 1.0
    theta = np.arange(around) * 2 * np.pi / around
    x, t = np.meshgrid(np.linspace(0, length, along), theta, indexing="ij")
    rest = np.stack([x.ravel(), radius * np.cos(t).ravel(), radius * np.sin(t).ravel()], 1)
    counts, indices = grid_faces(along, around, wrap_cols=True)
    topology = build_topology(counts, indices, rest)
    posed = rest * [0.6, 1.0, 1.0]
    width = np.full(len(rest), 0.3)
    law = crush(rest, posed, topology, np.zeros_like(rest), width)
    free = fold_law(np.array([0.6]), 0.3)[0][0]  # the law on flat cloth: no room
    inner = (x.ravel() > 0.2) & (x.ravel() < 0.8)
    room = FOLD_ROOM * radius
    np.testing.assert_allclose(law["over_room"][inner], free / room, rtol=2e-3)
    np.testing.assert_allclose(law["amplitude"][inner], min(free, room), rtol=2e-3)
    assert np.all(law["capped"][inner] == (free > room))
    assert (free > room) == (radius == 0.02)  # one case of each


def _fine_of(layer_stage, prim_path, record):
    fine = UsdGeom.Mesh(layer_stage.GetPrimAtPath(prim_path + "_wrinkled"))
    faces = np.asarray(fine.GetFaceVertexIndicesAttr().Get(), np.int64).reshape(-1, 3)
    points = np.asarray(fine.GetPointsAttr().Get(24), np.float64)
    triangles = record.topology.triangles
    levels = next(level for level in range(11) if fine_point_count(
        len(record.rest_points), triangles, level) == len(points))
    return points, faces, subdivide(record.rest_points, triangles, levels)


@pytest.mark.slow
@pytest.mark.parametrize("name", STAGES)
def test_sample_stages_keep_their_area_and_never_pass_through_themselves(gl_context,
                                                                         tmp_path, name):
    """Issue 55: the displaced geometry of every sample stage passes nowhere through itself
    (black patches where folds crossed), except where the coarse mesh itself does (the
    shirt's elbow, skinned); and where the coarse mesh is compressed along one direction
    (neither stretched nor compressed across it by more than 10%) and the fold has room,
    the wrinkled surface keeps its rest area within issue 55's 5%. The measure is
    benchmarks/physics/area.py's, whose table in docs/physics.md ("Inextensibility") has
    the ratio everywhere compressed, with what limits it elsewhere."""
    from benchmarks.physics.area import measure_stage

    measured = 0
    rows = measure_stage(name, gl_context, tmp_path)
    for row in rows:
        assert row["crossings"] == 0, row
        # everywhere compressed too, where the stage has such a region. The curtain,
        # whose folds the room lowers, kept 0.627 of its rest area until the length the
        # room denies went into its deepened pleats (method/deepen.py): 0.911 at their
        # cap 0.6, 0.990 at 0.75 (since 2026-12-06, when the crest damping's catch-up no
        # longer moved the referee's held sleeve past its bar at that cap; docs/physics.md,
        # "Deepening the pleats where the room is short"). The pillow drew 1.082 there
        # before its drawn folds counted the stretch across beyond STRETCH_ONSET (its
        # bulging sides), 1.026 with it
        if np.isfinite(row["compressed"]):
            assert 0.95 <= row["compressed"] <= 1.05, row
        if not np.isfinite(row["uniaxial"]):
            continue
        # the analytic sheets keep it within 2%; the zeppelin drew 1.086 before relax's
        # fit (its phases' misfit; docs/physics.md), 0.990 with it, the pillow 0.986 (the
        # curtain's folds are all lowered by the room: none measured). The shirt kept
        # 0.925 before the blend was divided by its coherence (its corner waves differ
        # up to 2.2x in length beside the elbow's pinch and cancel inside the coarse
        # triangles; docs/method.md, "Coherence"), 1.020 with it; then 1.02-1.054 by
        # which of two layouts its collapsed elbow's pinch settled into under a 0.01
        # degree change of a joint, until its rig kept the elbow round (2026-12-04:
        # 1.031 over the stage and five random axes alike; docs/physics.md); 1.044 with
        # its irregularity 0.15 (2026-12-05; 1.101 while the irregular shift's directions
        # were taken through each triangle's map)
        assert 0.95 <= row["uniaxial"] <= 1.05, row
        measured += 1
    if name in ("zeppelin", "pillow", "shirt"):
        assert measured, "no uniaxially compressed region with room was measured"


def test_the_slack_restores_by_its_documented_ramp():
    """wrinkle:slack c = 0.05 (docs/method.md, the fold law): folds begin at r = 1 - c
    restoring 1 - c and restore the whole length from r = 1 - 3 c on, a smoothstep
    between; values worked by hand (at r = 0.875: t = 1/4, smoothstep 5/32)."""
    r = np.array([1.0, 0.95, 0.9, 0.875, 0.85, 0.8])
    expected = np.array([0.95, 0.95, 0.975, 1.0 - 0.05 * 5.0 / 32.0, 1.0, 1.0])
    np.testing.assert_allclose(restored(r, 0.05), expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(restored(r, 0.0), np.ones_like(r))
