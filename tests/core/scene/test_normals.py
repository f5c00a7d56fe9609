"""Face and vertex normals (core/scene/normals.py): the notes' averaging rule, its weighted variants,
the degenerate vertex whose face normals cancel, and orienting a randomly wound soup."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from core.scene.normals import (face_normals, orient_consistently, vertex_normals,
                          vertex_normals_from_faces)
from core.scene.model import Mesh

CORNERS = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))      # index = 4x + 2y + z


def cube(diagonal_through_even_corners: bool = True) -> np.ndarray:
    """The 12 triangles of the cube [-1, 1]^3, counter-clockwise seen from outside.

    Each square face is split along a diagonal. With ``diagonal_through_even_corners`` every
    diagonal joins the two corners with an even number of +1 coordinates, so each corner
    meets the same number of triangles (2 or 1) from each of its three faces; otherwise each
    face is split from its lowest-numbered corner, and the counts differ.
    """
    triangles = []
    for axis in range(3):
        for side in (-1.0, 1.0):
            quad = [i for i, c in enumerate(CORNERS) if c[axis] == side]
            # order the 4 corners counter-clockwise seen from outside
            centre = np.zeros(3)
            centre[axis] = side
            a, b = [k for k in range(3) if k != axis]
            ang = [np.arctan2(CORNERS[i][b], CORNERS[i][a]) for i in quad]
            ring = [quad[k] for k in np.argsort(ang)]
            normal = np.zeros(3)
            normal[axis] = side
            e1, e2 = CORNERS[ring[1]] - CORNERS[ring[0]], CORNERS[ring[2]] - CORNERS[ring[0]]
            if np.dot(np.cross(e1, e2), normal) < 0:
                ring = ring[::-1]
            if diagonal_through_even_corners:
                start = next(k for k in range(4) if (CORNERS[ring[k]] > 0).sum() % 2 == 0)
            else:
                start = int(np.argmin(ring))
            r = ring[start:] + ring[:start]
            triangles += [(r[0], r[1], r[2]), (r[0], r[2], r[3])]
    return np.array(triangles)


def test_face_normals_and_areas():
    p = np.array([[0, 0, 0], [2, 0, 0], [0, 3, 0], [5, 5, 5]], float)
    unit, double_area = face_normals(p, np.array([[0, 1, 2], [0, 2, 1], [3, 3, 3]]))
    np.testing.assert_array_equal(unit, [[0, 0, 1], [0, 0, -1], [0, 0, 0]])
    np.testing.assert_array_equal(double_area, [6.0, 6.0, 0.0])


@pytest.mark.parametrize("weighting", ["mean", "area", "angle"])
def test_cube_corner_normal_is_the_diagonal(weighting):
    normals = vertex_normals_from_faces(CORNERS, cube(True), weighting)
    np.testing.assert_allclose(normals, CORNERS / np.sqrt(3.0), atol=1e-15)


def test_angle_weighting_does_not_depend_on_how_faces_are_split():
    # Split from the lowest corner, the unweighted mean leans towards the face that
    # contributes two triangles; the angle-weighted average (90° per face) does not.
    triangles = cube(False)
    np.testing.assert_allclose(vertex_normals_from_faces(CORNERS, triangles, "angle"),
                               CORNERS / np.sqrt(3.0), atol=1e-15)
    mean = vertex_normals_from_faces(CORNERS, triangles, "mean")
    assert np.max(np.abs(mean - CORNERS / np.sqrt(3.0))) > 0.1


def test_vertex_whose_face_normals_cancel_is_finite():
    # Two triangles of equal area share only vertex 0 and face opposite ways: the average is 0.
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [-1, 0, 0]], float)
    t = np.array([[0, 1, 2], [0, 3, 4]])
    np.testing.assert_array_equal(face_normals(p, t)[0], [[0, 0, 1], [0, 0, -1]])
    for weighting in ("mean", "area", "angle"):
        normals = vertex_normals_from_faces(p, t, weighting)
        assert np.all(np.isfinite(normals))
        # fallback: the largest incident face; on a tie the first one
        np.testing.assert_array_equal(normals[0], [0, 0, 1])
    # The larger face wins.
    p[3:] *= 2.0
    np.testing.assert_array_equal(vertex_normals_from_faces(p, t)[0], [0, 0, -1])


def test_zero_area_faces_contribute_nothing():
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0], [7, 7, 7]], float)
    t = np.array([[0, 1, 2], [0, 1, 3], [4, 4, 4]])                    # the last two: area 0
    normals = vertex_normals_from_faces(p, t)
    np.testing.assert_array_equal(normals[:3], [[0, 0, 1]] * 3)
    np.testing.assert_array_equal(normals[3:], [[0, 0, 0], [0, 0, 0]])   # only degenerate faces


def uv_sphere(n_lat=12, n_lon=24):
    lat = np.linspace(0, np.pi, n_lat + 1)[1:-1]
    lon = np.linspace(0, 2 * np.pi, n_lon, endpoint=False)
    th, ph = np.meshgrid(lat, lon, indexing="ij")
    ring = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], -1)
    points = np.concatenate([[(0, 0, 1)], ring.reshape(-1, 3), [(0, 0, -1)]])

    def idx(i, j):
        return 1 + i * n_lon + j % n_lon
    bottom = len(points) - 1
    tris = [(0, idx(0, j), idx(0, j + 1)) for j in range(n_lon)]
    tris += [(bottom, idx(n_lat - 2, j + 1), idx(n_lat - 2, j)) for j in range(n_lon)]
    for i in range(n_lat - 2):
        for j in range(n_lon):
            tris += [(idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)),
                     (idx(i, j), idx(i + 1, j + 1), idx(i, j + 1))]
    return points, np.array(tris)


def test_sphere_vertex_normals_point_outwards():
    points, tris = uv_sphere()
    assert np.all(np.einsum("ij,ij->i", face_normals(points, tris)[0],
                            points[tris].mean(axis=1)) > 0)          # wound outwards
    for weighting in ("mean", "area", "angle"):
        normals = vertex_normals_from_faces(points, tris, weighting)
        assert np.min(np.einsum("ij,ij->i", normals, points)) > 0.99


def test_orient_consistently_repairs_a_randomly_wound_soup():
    points, tris = uv_sphere()
    rng = np.random.default_rng(3)
    flipped = rng.random(len(tris)) < 0.5
    soup = tris.copy()
    soup[flipped] = soup[flipped][:, [0, 2, 1]]
    oriented = orient_consistently(soup)
    # All faces agree with face 0; face 0 kept its winding, so all of them are outward or
    # all inward.
    outward = np.einsum("ij,ij->i", face_normals(points, oriented)[0], points[oriented].mean(axis=1)) > 0
    assert outward.all() or (~outward).all()
    assert outward[0] == (not flipped[0])
    # Averaging the raw soup cancels normals; the oriented soup gives the sphere's normals
    # (up to one sign), which is what vertex_normals does for a mesh that is not closed.
    raw = vertex_normals_from_faces(points, soup)
    assert np.min(np.abs(np.einsum("ij,ij->i", raw, points))) < 0.9
    normals = vertex_normals(Mesh(positions=points, triangles=soup, closed=False))
    assert np.min(np.abs(np.einsum("ij,ij->i", normals, points))) > 0.99
    signs = np.sign(np.einsum("ij,ij->i", normals, points))
    assert np.all(signs == signs[0])


def test_orient_consistently_keeps_separate_pieces_and_non_manifold_edges():
    # Two separate triangles, and a fan of three faces on one edge (non-manifold): nothing
    # links across a non-manifold edge, and no face is lost.
    t = np.array([[0, 1, 2], [3, 4, 5], [6, 7, 8], [6, 7, 9], [7, 6, 10]])
    out = orient_consistently(t)
    assert out.shape == t.shape
    assert np.array_equal(out, t)          # already consistent: every face as it was
    assert orient_consistently(np.zeros((0, 3), np.int64)).shape == (0, 3)


def test_vertex_normals_prefers_the_files_normals():
    points, tris = uv_sphere(6, 8)
    given = np.tile([0.0, 0.0, 2.0], (len(points), 1))
    given[3] = 0.0                                      # missing: replaced by the computed one
    mesh = Mesh(positions=points, triangles=tris, normals=given, closed=True)
    normals = vertex_normals(mesh)
    np.testing.assert_array_equal(np.delete(normals, 3, axis=0), [[0, 0, 1]] * (len(points) - 1))
    np.testing.assert_allclose(normals[3], vertex_normals_from_faces(points, tris)[3])


def test_unknown_weighting_is_refused():
    with pytest.raises(ValueError, match="weighting"):
        vertex_normals_from_faces(CORNERS, cube(), "median")


@pytest.mark.parametrize("n, vertices", [(0, 1), (1, 1), (7, 3), (5000, 40), (60_000, 20_000)])
def test_edge_order_is_lexsorts_order(n, vertices):
    """The crease split and the orienting sort edges with one stable integer key: the same
    order as ``np.lexsort((high, low))``, ties (a shared edge) in their own order."""
    from core.scene.normals import _edge_order
    rng = np.random.default_rng(n)
    a, b = rng.integers(0, vertices, n), rng.integers(0, vertices, n)
    low, high = np.minimum(a, b), np.maximum(a, b)
    assert np.array_equal(_edge_order(low, high), np.lexsort((high, low)))


def test_edge_order_falls_back_where_the_key_would_not_be_one_to_one():
    from core.scene.normals import _edge_order
    low, high = np.array([-1, 3, 2, -1]), np.array([4, 5, 6, 2])
    assert np.array_equal(_edge_order(low, high), np.lexsort((high, low)))
