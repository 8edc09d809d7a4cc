"""Deepened pleats (method/deepen.py, docs/method.md "deepened pleats"): where the room
lowers a fold on curved cloth, the surface is offset away from its centre of curvature
along the wave by the length the room denies. The law is checked on a cuff (a tube
gathered around itself), where every quantity of it is known: its curvature along the
wave is -1/R (outward normals), its room 0.5 R. The passes against the numpy reference on
the cuff and the curtain sample; the area on the sample stages: tests/test_folds.py."""
from __future__ import annotations

import numpy as np
import pytest
from pxr import Usd

from usdwrinkle.authoring.builders import grid_faces, point_cache_stage
from usdwrinkle.method.contract import DEEPEN_CAP, FOLD_ROOM
from usdwrinkle.method.deepen import length_at, offset
from usdwrinkle.reference.crush import crush, default_slope
from usdwrinkle.scene.topology import build_topology

from helpers import gathered_cuff

RADIUS, LENGTH, WIDTH, RATIO = 0.1, 0.3, 0.15, 0.6
ALONG, AROUND = 11, 96


def cuff(ratio: float = 1.0):
    """helpers.gathered_cuff at this module's size: (points, counts, indices, interior)."""
    return gathered_cuff(ratio, RADIUS, LENGTH, ALONG, AROUND)


def outward(points, normals):
    radial = points * [1.0, 0.0, 1.0]
    radial /= np.linalg.norm(radial, axis=1, keepdims=True)
    return np.sum(normals * radial, 1)


def test_a_gathered_cuff_is_offset_outward_by_the_law():
    """The numpy reference on the cuff gathered to 0.6 of its circumference (posed radius
    R = 6 cm): the ring's fitted curvature along the wave is the circle's (its chords give
    2 (e.n) / |e|^2 = 1/R exactly), so the offset is the law's closed form at kappa =
    -1/R, away from the axis; the room binds (the full fold stands 1.46x its room 0.5 R),
    and the first bound sets the offset, (D - 1) R: 1.40 cm."""
    rest, counts, indices, inner = cuff()
    posed = cuff(RATIO)[0]
    radius = RADIUS * RATIO
    topology = build_topology(counts, indices, rest)
    law = crush(rest, posed, topology, np.zeros_like(rest), np.full(len(rest), WIDTH))
    out = outward(posed, law["normals"])
    assert np.all(out[inner] > 0.999)
    drawn = law["amplitude"] * law["drawn"]
    full = drawn * np.maximum(law["over_room"], 1.0)
    k = np.linalg.norm(law["wave_vector"], axis=1)
    np.testing.assert_allclose(drawn[inner], FOLD_ROOM * radius, rtol=1e-6)
    assert np.all(law["over_room"][inner] > 1.4)
    table = default_slope()
    expected = offset(-1.0 / radius, drawn, full, k, table)
    np.testing.assert_allclose(law["offset"][inner], expected[inner], rtol=1e-9)
    gain = length_at(table, full * k) / length_at(table, drawn * k)
    first = (gain - 1.0) * radius
    assert np.all(first[inner] < DEEPEN_CAP * full[inner])
    np.testing.assert_allclose(law["offset"][inner], first[inner], rtol=1e-9)
    # 1.35 cm with the fold at K = 0.9 (until 2026-12-08): a sharper crest holds the same
    # length lower, so the full fold's length gain over the drawn one is larger
    np.testing.assert_allclose(law["offset"][inner], 0.0140, atol=5e-5)
    assert np.all(law["offset"][inner] > 0)  # along the outward normal: away from the axis
    # uniform around and along: its gradient is nothing
    assert np.abs(law["offset_gradient"][inner]).max() < 1e-5


def test_a_tube_compressed_along_its_axis_is_not_offset():
    """A 2 cm tube pushed to 0.6 of its length: the room binds (it is curved around), but
    the wave runs along the axis, where the tube is straight, so the offset fades to
    nothing there (its last bound, a |kappa| a / FOLD_ROOM)."""
    around, along, length, radius = 96, 21, 1.0, 0.02
    theta = np.arange(around) * 2 * np.pi / around
    x, t = np.meshgrid(np.linspace(0, length, along), theta, indexing="ij")
    rest = np.stack([x.ravel(), radius * np.cos(t).ravel(), radius * np.sin(t).ravel()], 1)
    counts, indices = grid_faces(along, around, wrap_cols=True)
    topology = build_topology(counts, indices, rest)
    law = crush(rest, rest * [0.6, 1.0, 1.0], topology, np.zeros_like(rest),
                np.full(len(rest), 0.3))
    inner = (x.ravel() > 0.2) & (x.ravel() < 0.8)
    assert np.all(law["over_room"][inner] > 1.0)
    assert np.abs(law["offset"][inner]).max() < 1e-6 * law["amplitude"][inner].max()


@pytest.fixture(scope="module")
def cuff_stage(tmp_path_factory):
    rest, counts, indices, inner = cuff()
    stage = point_cache_stage(rest, {1: cuff(RATIO)[0]}, counts, indices, width=WIDTH)
    path = tmp_path_factory.mktemp("cuff") / "cuff.usda"
    stage.GetRootLayer().Export(str(path))
    return path


def test_the_passes_deepen_as_the_numpy_reference(gl_context, cuff_stage):
    """crush.glsl's offset and its DEEPEN_GRADIENT step equal the reference, on the cuff
    and on the curtain sample at frame 24 (its pleats, where the room lowers every fold;
    the offset reaches 4.5 cm there)."""
    from pathlib import Path

    from usdwrinkle.engine import WrinkleEngine

    curtain = Path(__file__).resolve().parents[1] / "sample_stages" / "curtain.usda"
    for stage_path, frame, least in ((cuff_stage, 1, 0.01), (curtain, 24, 0.04)):
        engine = WrinkleEngine(str(stage_path))
        try:
            for f in range(1, frame + 1):
                engine.compute_frame(f)
            (path,) = engine.wrinkled_paths
            record = engine.meshes[path]
            fields = engine.read_fields(path)
            p = record.params
            law = crush(record.rest_points, fields.points.astype(np.float64),
                        record.topology, p.q, p.width, amplitude_scale=p.amplitude_scale,
                        slack=p.slack, hold=p.hold, coarsening=p.coarsening)
        finally:
            engine.release()
        size = np.abs(law["offset"]).max()
        assert size > least, (stage_path, size)
        np.testing.assert_allclose(fields.offset, law["offset"], rtol=0, atol=1e-4 * size)
        slope = np.abs(law["offset_gradient"]).max()
        np.testing.assert_allclose(fields.offset_gradient, law["offset_gradient"], rtol=0,
                                   atol=1e-3 * max(slope, 1e-3))


def test_a_bake_carries_the_offset_and_renders_as_computed(gl_context, tmp_path):
    """The curtain sample at frame 24: the bake writes primvars:wrinkle:offset as the
    passes computed it; a render from that bake (the gradient fitted again from the baked
    offset and the posed points) equals the render that computed it; and a bake without
    the offset (made before it existed) is drawn without it: its heights stay within the
    tallest fold, where the computed frame's pass it. Regular folds (irregularity 0
    authored on a copy): an irregular fold's pixels stand up to IRREGULARITY_FACTOR_MAX
    times its corners' amplitude, so "the tallest fold" is a regular one's."""
    from pathlib import Path

    from pxr import Sdf

    from usdwrinkle.cli.main import main
    from usdwrinkle.engine import WrinkleEngine
    from usdwrinkle.usd import schema

    from helpers import read_exr

    sample = Path(__file__).resolve().parents[1] / "sample_stages" / "curtain.usda"
    curtain = tmp_path / "curtain.usda"
    Sdf.Layer.FindOrOpen(str(sample)).Export(str(curtain))
    regular = Usd.Stage.Open(str(curtain))
    regular.GetPrimAtPath("/World/Curtain/Cloth").CreateAttribute(
        schema.IRREGULARITY, Sdf.ValueTypeNames.Float).Set(0.0)
    regular.Save()
    engine = WrinkleEngine(str(curtain))
    try:
        for frame in range(1, 25):
            engine.compute_frame(frame)
        (path,) = engine.wrinkled_paths
        fields = engine.read_fields(path)
        computed, tallest = fields.offset, float(fields.drawn_amplitude.max())
    finally:
        engine.release()
    layer = tmp_path / "fields.usda"
    assert main(["bake", str(curtain), str(layer), "--frames", "24", "--quiet"]) == 0
    bake = Usd.Stage.Open(str(layer))
    baked = np.asarray(bake.GetPrimAtPath(path).GetAttribute("primvars:wrinkle:offset").Get(24))
    np.testing.assert_array_equal(baked, computed)
    assert np.abs(baked).max() > 0.03
    old = tmp_path / "old.usda"
    copy = Sdf.Layer.FindOrOpen(str(layer))
    copy.Export(str(old))
    stripped = Sdf.Layer.FindOrOpen(str(old))
    spec = stripped.GetPrimAtPath(path)
    del spec.properties["primvars:wrinkle:offset"]
    stripped.Save()
    for source, name in ((curtain, "direct"), (layer, "baked"), (old, "old")):
        assert main(["render", str(source), str(tmp_path / f"{name}.####.exr"), "--frames",
                     "24", "--width", "128", "--quiet"]) == 0
    direct, from_bake, old_bake = (read_exr(tmp_path / f"{name}.0024.exr")
                                   for name in ("direct", "baked", "old"))
    for channel in direct:
        both = np.isinf(direct[channel]) & np.isinf(from_bake[channel])
        with np.errstate(invalid="ignore"):
            assert np.all(both | (np.abs(direct[channel] - from_bake[channel]) <= 1e-5)), \
                channel
    # without the offset no height passes the tallest fold; with it they do
    assert np.abs(old_bake["wrinkle.height"]).max() <= tallest * (1 + 1e-4)
    assert np.abs(direct["wrinkle.height"]).max() > 1.2 * tallest


@pytest.mark.parametrize("radius", [0.05, 0.2])
def test_the_fitted_form_gives_the_normal_curvature_of_a_tube(radius):
    """method/deepen.py fit_form and curvature_along: on a tube of radius R with outward
    normals, the normal curvature around it is -1/R (the surface bends away from its
    normal), along its axis 0, and at 45 degrees -1/(2R) (Euler: k1 cos^2 + k2 sin^2)."""
    from usdwrinkle.method.deepen import curvature_along, fit_form

    around, rows = 48, 12
    angle = np.arange(around) * 2 * np.pi / around
    z = np.arange(rows) * 2 * np.pi * radius / around
    A, Z = np.meshgrid(angle, z)
    points = np.stack([radius * np.cos(A), radius * np.sin(A), Z], -1).reshape(-1, 3)
    counts, indices = grid_faces(rows, around, wrap_cols=True)
    topology = build_topology(counts, indices, points)
    normals = points * np.array([1.0, 1.0, 0.0]) / radius
    tangent = np.stack([-np.sin(A), np.cos(A), 0 * A], -1).reshape(-1, 3)
    axis = np.tile([0.0, 0.0, 1.0], (len(points), 1))
    offsets, neighbours = topology.neighbor_offsets, topology.neighbor_indices
    owner = np.repeat(np.arange(len(points)), np.diff(offsets))
    edges = points[neighbours] - points[owner]
    # tangent coordinates: (around, along) at each point
    coords = np.stack([np.sum(edges * tangent[owner], 1), np.sum(edges * axis[owner], 1)], 1)
    form, fitted = fit_form(coords, np.sum(edges * normals[owner], 1), owner, len(points))
    inner = np.zeros((rows, around), bool)
    inner[2:-2] = True
    inner = inner.ravel()
    assert fitted[inner].all()
    ones = np.ones(len(points))
    around_curvature = curvature_along(form, np.stack([ones, 0 * ones], 1))
    along_curvature = curvature_along(form, np.stack([0 * ones, ones], 1))
    diagonal = curvature_along(form, np.stack([ones, ones], 1))
    assert around_curvature[inner] == pytest.approx(-1 / radius, rel=0.01)
    assert np.abs(along_curvature[inner]).max() < 0.01 / radius
    assert diagonal[inner] == pytest.approx(-0.5 / radius, rel=0.01)
