"""What maps/tangents.py reproduces of Blender for --tangent-space mikktspace: its smooth
vertex normals (corner-angle weighted) and mikktspace.c's split of a quad."""
from __future__ import annotations

import numpy as np

from usdwrinkle.maps.tangents import blender_vertex_normals, mikktspace_triangles


def test_vertex_normals_weigh_faces_by_their_corner_angle():
    """A cube's corner: three faces at right angles give (-1, -1, -1)/sqrt(3); stretched so
    that their areas differ threefold, the corner angles and so the normal stay (area
    weights would tilt it); split into triangles, a face's corner angles add up to the
    same; a face left out (a hole) does not count."""
    # a cube's corner: three faces at right angles, each corner angle 90 degrees
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                       [0, 0, 1], [1, 0, 1], [0, 1, 1]], np.float64)
    counts = np.array([4, 4, 4])
    indices = np.array([0, 3, 2, 1,    # bottom, normal -z
                        0, 1, 5, 4,    # front, normal -y
                        0, 4, 6, 3])   # left, normal -x
    normals = blender_vertex_normals(points, counts, indices)
    np.testing.assert_allclose(normals[0], -np.ones(3) / np.sqrt(3), atol=1e-12)
    stretched = points.copy()
    stretched[[1, 2, 5], 0] = 3.0
    np.testing.assert_allclose(blender_vertex_normals(stretched, counts, indices)[0],
                               normals[0], atol=1e-12)
    # split the bottom quad into two triangles: corner 0 keeps 90 degrees in total
    split = blender_vertex_normals(points, np.array([3, 3, 4, 4]),
                                   np.array([0, 3, 2, 0, 2, 1, 0, 1, 5, 4, 0, 4, 6, 3]))
    np.testing.assert_allclose(split[0], normals[0], atol=1e-12)
    # a left-out face (a hole) does not count
    holed = blender_vertex_normals(points, counts, indices, np.array([True, True, False]))
    np.testing.assert_allclose(holed[0], [0, -np.sqrt(0.5), -np.sqrt(0.5)], atol=1e-12)


def test_a_quad_is_split_along_its_shorter_uv_diagonal_then_its_shorter_posed_one():
    """mikktspace.c: the shorter UV diagonal; on a tie (a rectangle) the shorter diagonal
    of the positions. Corner ids are [3t + c] of the triangles (0,1,2), (0,2,3)."""
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    faces = np.array([0, 0])
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float64)
    fan = [[0, 1, 2], [0, 2, 3]]

    def ids(points, quad_uv):
        return mikktspace_triangles(points, triangles, faces,
                                    np.asarray(quad_uv, np.float32)[fan].reshape(-1, 2))

    kept = np.arange(6).reshape(2, 3)
    rectangle = [[0, 0], [2, 0], [2, 1], [0, 1]]
    np.testing.assert_array_equal(ids(square, rectangle), kept)        # a tie, a tie
    longer02 = square.copy()
    longer02[2] = [1.4, 1.4, 0]                                          # 0-2 longer in 3D
    np.testing.assert_array_equal(ids(longer02, rectangle), [[0, 1, 5], [1, 2, 5]])
    skewed_uv = [[0, 0], [1, 0], [1.6, 1], [0, 1]]                       # 0-2 longer in UV
    np.testing.assert_array_equal(ids(square, skewed_uv), [[0, 1, 5], [1, 2, 5]])
    np.testing.assert_array_equal(ids(longer02, [[0, 0], [1, 0], [0.9, 0.9], [0, 1]]), kept)
