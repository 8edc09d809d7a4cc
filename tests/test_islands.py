"""The wrinkle maps' islands layout (maps/islands.py, bake --map-layout islands): each
face its own island, its first diagonal along s, apart from the others."""
from __future__ import annotations

import numpy as np
import pytest
from pxr import Usd, UsdGeom

from usdwrinkle.cli.main import main
from usdwrinkle.maps.islands import island_layout
from usdwrinkle.scene.topology import build_topology

from conftest import REPO

SAMPLES = REPO / "sample_stages"


def shirt_faces():
    stage = Usd.Stage.Open(str(SAMPLES / "shirt.usda"))
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath("/World/Arm/Sleeve"))
    points = np.array(mesh.GetPointsAttr().Get(), np.float64)
    counts = np.array(mesh.GetFaceVertexCountsAttr().Get())
    indices = np.array(mesh.GetFaceVertexIndicesAttr().Get())
    return points, counts, indices, build_topology(counts, indices, points)


def layout(points, counts, topology, size=2048, padding=8):
    return island_layout(points, topology.triangles, topology.triangle_face,
                         topology.corner_face_vertex, counts, size, padding)


def test_a_quads_diagonal_lies_along_s_and_is_the_shorter_one():
    """Corners 0 and 2 share t, so dP/ds is the posed diagonal in both triangles of
    every quad (one frame over the face in any pose), and MikkTSpace, which splits a
    quad along its shorter UV diagonal, splits it there too."""
    points, counts, indices, topology = shirt_faces()
    uv, padding, typical = layout(points, counts, topology)
    quads = uv.reshape(-1, 4, 2)
    assert np.abs(quads[:, 0, 1] - quads[:, 2, 1]).max() < 1e-6
    d02 = np.sum((quads[:, 2] - quads[:, 0]) ** 2, -1)
    d13 = np.sum((quads[:, 3] - quads[:, 1]) ** 2, -1)
    assert np.all(d02 < d13)
    assert padding == 8 and typical > 64
    # every triangle winds counter-clockwise in UV, as about its normal
    corner = uv[topology.corner_face_vertex]
    e1, e2 = corner[:, 1] - corner[:, 0], corner[:, 2] - corner[:, 0]
    assert np.all(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] > 0)
    # the diagonal keeps its rest length (one scale for the whole mesh)
    scale = np.linalg.norm(quads[:, 2] - quads[:, 0], axis=1) / np.linalg.norm(
        points[indices.reshape(-1, 4)[:, 2]] - points[indices.reshape(-1, 4)[:, 0]], axis=1)
    np.testing.assert_allclose(scale, scale[0], rtol=1e-5)


def test_islands_lie_apart_by_twice_the_padding():
    """No texel within ``padding`` of one island is nearer another: the dilation that fills
    the gutter (maps/raster.padding_plan) never mixes two faces' frames."""
    points, counts, _, topology = shirt_faces()
    size = 1024
    uv, padding, _ = layout(points, counts, topology, size=size)
    boxes = uv.reshape(-1, 4, 2) * size
    lo, hi = boxes.min(axis=1), boxes.max(axis=1)
    assert lo.min() >= padding and hi.max() <= size - padding
    apart = np.maximum(lo[:, None] - hi[None], lo[None] - hi[:, None]).max(axis=-1)
    np.fill_diagonal(apart, np.inf)
    assert apart.min() >= 2 * padding


def test_a_fan_polygon_unfolds_isometrically():
    """A pentagon bent along its diagonals keeps every edge length in UV (each fan
    triangle hinged on the one before)."""
    angles = np.linspace(0, 2 * np.pi, 6)[:-1]
    points = np.stack([np.cos(angles), np.sin(angles), 0.3 * np.cos(2 * angles)], -1)
    counts, indices = np.array([5]), np.arange(5)
    topology = build_topology(counts, indices, points)
    uv, _, _ = layout(points, counts, topology, size=256, padding=4)
    tri = topology.triangles
    for a, b in ((0, 1), (1, 2), (0, 2)):
        rest = np.linalg.norm(points[tri[:, a]] - points[tri[:, b]], axis=1)
        flat = np.linalg.norm(uv[topology.corner_face_vertex[:, a]]
                              - uv[topology.corner_face_vertex[:, b]], axis=1)
        np.testing.assert_allclose(flat / rest, flat[0] / rest[0], rtol=1e-5)


def test_a_dense_mesh_on_a_small_map_keeps_less_padding_or_is_refused():
    points, counts, _, topology = shirt_faces()
    _, padding, typical = layout(points, counts, topology, size=512)
    assert padding < 8 and typical >= 4 * (2 * padding + 1)
    with pytest.raises(ValueError, match="too small to hold wrinkles"):
        layout(points, counts, topology, size=64)


def test_a_mesh_without_uvs_gets_maps_in_islands(gl_context, tmp_path):
    """Issue 23, finding 7: the pillow has no st; the islands layout needs none, and the
    material reads the layout's own primvar."""
    layer = tmp_path / "pillow.usda"
    assert main(["bake", str(SAMPLES / "pillow.usda"), str(layer), "--frames", "24",
                 "--quiet", "--maps", "normal", "--map-size", "1024"]) == 0
    stage = Usd.Stage.Open(str(layer))
    meshes = [p for p in stage.Traverse() if p.IsA(UsdGeom.Mesh)]
    primvar = UsdGeom.PrimvarsAPI(meshes[0]).GetPrimvar("wrinkleMapST")
    assert primvar.GetInterpolation() == "faceVarying"
    assert len(primvar.Get()) == len(UsdGeom.Mesh(meshes[0]).GetFaceVertexIndicesAttr().Get())
    readers = [p for p in stage.Traverse() if p.GetName() == "WrinkleUV"]
    assert readers and readers[0].GetAttribute("inputs:varname").Get() == "wrinkleMapST"
    assert list((tmp_path / "pillow_maps").glob("*.normal.0024.png"))
