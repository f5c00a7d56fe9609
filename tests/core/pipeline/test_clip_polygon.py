"""Triangle clipping in the canonical volumes (core/pipeline/clip_polygon.py): outcodes, trivial
accept and reject, Sutherland–Hodgman with attributes, and a brute-force property test."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from core.pipeline.clip_polygon import (ABOVE, BEHIND, BELOW, FRONT, LEFT, RIGHT, clip_triangles,
                               outcodes)

Z_MIN = -0.25


def _inside(points, projection, z_min=Z_MIN, tol=0.0):
    """Each point inside the canonical volume, allowing ``tol``."""
    x, y, z = np.asarray(points, dtype=float).T
    if projection == "parallel":
        lo, hi, far, near = -1.0, 1.0, -1.0, 0.0
    else:
        lo, hi, far, near = z, -z, -1.0, z_min
    return ((x >= lo - tol) & (x <= hi + tol) & (y >= lo - tol) & (y <= hi + tol)
            & (z >= far - tol) & (z <= near + tol))


def _used(c):
    return c.points[np.unique(c.triangles)]


# --- outcodes --------------------------------------------------------------------------------

def test_outcode_bits_parallel():
    pts = [(0, 0, -0.5), (0, 2, -0.5), (0, -2, -0.5), (2, 0, -0.5), (-2, 0, -0.5),
           (0, 0, -2), (0, 0, 0.5), (2, 2, 0.5), (1, -1, 0), (-1, 1, -1)]
    assert outcodes(np.array(pts, float), "parallel").tolist() == [
        0, ABOVE, BELOW, RIGHT, LEFT, BEHIND, FRONT, ABOVE | RIGHT | FRONT, 0, 0]


def test_outcode_bits_perspective():
    # At z = -0.5 the sides are x, y = +-0.5; the front plane is z = Z_MIN = -0.25.
    pts = [(0, 0, -0.5), (0, 0.6, -0.5), (0, -0.6, -0.5), (0.6, 0, -0.5), (-0.6, 0, -0.5),
           (0, 0, -1.5), (0, 0, -0.1), (0.5, -0.5, -0.5), (0, 0, Z_MIN), (1, 1, -1),
           (0, 0, 0.0), (0.1, 0, 1.0)]
    codes = outcodes(np.array(pts, float), "perspective", Z_MIN).tolist()
    assert codes[:10] == [0, ABOVE, BELOW, RIGHT, LEFT, BEHIND, FRONT, 0, 0, 0]
    assert codes[10] == FRONT                           # the eye: on all four side planes
    assert codes[11] == ABOVE | BELOW | RIGHT | LEFT | FRONT   # behind the eye


def test_outcodes_of_non_finite_points_are_outside():
    codes = outcodes(np.array([(np.nan, 0, -0.5), (0, 0, np.inf), (np.nan,) * 3]), "parallel")
    assert codes[0] == RIGHT | LEFT and codes[1] == FRONT and codes[2] == 63
    with pytest.raises(ValueError, match="projection"):
        outcodes(np.zeros((1, 3)), "oblique")


# --- trivial accept and reject ---------------------------------------------------------------

@pytest.mark.parametrize("projection", ["parallel", "perspective"])
def test_everything_inside_passes_through_untouched(projection):
    rng = np.random.default_rng(1)
    z = rng.uniform(-0.9, -0.3, 50)
    half_width = 0.9 * (-z if projection == "perspective" else np.ones(50))
    pts = np.column_stack([rng.uniform(-1, 1, (50, 2)) * half_width[:, None], z])
    tris = rng.integers(0, 50, (80, 3))
    attrs = rng.normal(size=(50, 4))
    c = clip_triangles(pts, tris, attrs, projection, Z_MIN)
    assert c.points is pts and c.triangles is tris and c.attrs is attrs   # no copy at all
    assert np.array_equal(c.source, np.arange(80))


def test_accepted_keep_indices_rejected_dropped_crossing_appended():
    pts = np.array([(0, 0, -0.5), (0.5, 0, -0.5), (0, 0.5, -0.5),      # inside
                    (2, 0, -0.5), (3, 0, -0.5), (2, 1, -0.5),          # beyond x = 1
                    (1.5, 0.2, -0.5)])                                  # outside, to cross
    tris = np.array([[3, 4, 5], [0, 1, 2], [0, 1, 6], [2, 1, 0]])
    c = clip_triangles(pts, tris, None, "parallel")
    assert c.attrs.shape == (len(c.points), 0)
    # accepted first, in input order, with their own indices; then the clipped one
    assert c.triangles[:2].tolist() == [[0, 1, 2], [2, 1, 0]]
    assert c.source.tolist()[:2] == [1, 3] and set(c.source[2:].tolist()) == {2}
    assert np.array_equal(c.points[:7], pts)             # input vertices first, unchanged
    assert np.all(_inside(_used(c), "parallel"))
    # the vertices of the crossing triangle that are inside keep their indices
    assert {0, 1} <= set(c.triangles[2:].ravel().tolist())
    assert 6 not in c.triangles


# --- Sutherland–Hodgman ----------------------------------------------------------------------

def test_attributes_interpolated_at_the_crossing_hand_values():
    # Crosses x = 1: on edge v0-v1 at t = 1/2 -> (1, 0, -0.5), attribute 5; on edge v1-v2
    # from (2, 0) to (0, 0.5) at t = 1/2 -> (1, 0.25, -0.5), attribute (10 + 2) / 2 = 6.
    pts = np.array([(0, 0, -0.5), (2, 0, -0.5), (0, 0.5, -0.5)])
    attrs = np.array([[0.0, 1.0], [10.0, 3.0], [2.0, 5.0]])
    c = clip_triangles(pts, [[0, 1, 2]], attrs, "parallel")
    new = {tuple(p): tuple(a) for p, a in zip(c.points[3:], c.attrs[3:])}
    assert new == {(1.0, 0.0, -0.5): (5.0, 2.0), (1.0, 0.25, -0.5): (6.0, 4.0)}
    # a quadrilateral: two triangles, all from triangle 0
    assert len(c.triangles) == 2 and c.source.tolist() == [0, 0]


def _area(c):
    p = c.points[c.triangles]
    return 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()


def test_front_and_back_planes_parallel():
    # A triangle in the plane x = 0 from z = 1 to z = -2: only -1 <= z <= 0 remains.
    pts = np.array([(0, -0.5, 1.0), (0, 0.5, 1.0), (0, 0, -2.0)])
    c = clip_triangles(pts, [[0, 1, 2]], pts[:, 2:].copy(), "parallel")
    assert np.all(np.isfinite(c.points)) and np.all(_inside(_used(c), "parallel"))
    z = _used(c)[:, 2]
    assert z.min() == -1.0 and z.max() == 0.0
    # width at height z is (z + 2) / 3; area of the band between z = -1 and 0: (1/3 + 2/3) / 2
    assert _area(c) == pytest.approx(0.5, abs=1e-12)
    # the attribute carried the z coordinate: it must still equal z
    assert np.allclose(c.attrs[:, 0], c.points[:, 2], atol=1e-12)


def test_front_and_back_planes_perspective():
    pts = np.array([(0, -0.05, -0.1), (0, 0.05, -0.1), (0, 0, -1.5)])
    c = clip_triangles(pts, [[0, 1, 2]], None, "perspective", Z_MIN)
    used = _used(c)
    assert np.all(np.isfinite(c.points)) and np.all(_inside(used, "perspective", tol=1e-9))
    assert used[:, 2].min() == -1.0 and used[:, 2].max() == Z_MIN


def test_triangle_straddling_the_eye_keeps_only_its_visible_part():
    # One corner well in front, two behind the eye (z > 0): no divide, no NaN, and what is
    # left lies in the frustum between the front plane and the far corner.
    pts = np.array([(0.0, 0.0, -0.8), (-0.5, 0.2, 0.6), (0.4, -0.3, 0.9)])
    attrs = pts.copy()
    c = clip_triangles(pts, [[0, 1, 2]], attrs, "perspective", Z_MIN)
    used = _used(c)
    assert len(c.triangles) >= 1
    assert np.all(np.isfinite(c.points)) and np.all(np.isfinite(c.attrs))
    assert np.all(_inside(used, "perspective", tol=1e-9))
    assert used[:, 2].max() == Z_MIN and used[:, 2].min() == pytest.approx(-0.8)
    assert np.allclose(c.attrs, c.points, atol=1e-12)   # attributes moved with the points
    # and it crosses the eye plane z = 0 too: a triangle with corners on both sides of it
    pts = np.array([(0.0, 0.0, -0.8), (0.3, 0.1, 0.5), (-0.2, 0.3, -0.4)])
    c = clip_triangles(pts, [[0, 1, 2]], None, "perspective", Z_MIN)
    assert np.all(_inside(_used(c), "perspective", tol=1e-9))


def test_wholly_behind_the_eye_or_at_it_is_dropped_without_nan():
    pts = np.array([(0, 0, 0.5), (1, 0, 0.5), (0, 1, 0.7),       # behind the eye
                    (0, 0, 0.0), (0.1, 0, 0.0), (0, 0.1, 0.0)])   # all at z = 0
    c = clip_triangles(pts, [[0, 1, 2], [3, 4, 5]], None, "perspective", Z_MIN)
    assert len(c.triangles) == 0


def test_degenerate_and_non_finite_input():
    pts = np.array([(0, 0, -0.5), (3, 0, -0.5), (3, 0, -0.5),   # zero area, crossing x = 1
                    (2, 2, 1), (2, 2, 1), (2, 2, 1),                # a point, outside
                    (0, 0, -0.5), (np.nan, 0, -0.5), (0, 0.5, -0.5),  # NaN corner
                    (0, 0, -0.5), (np.inf, 0, -0.5), (0, 0.5, -0.5)])  # infinite corner
    tris = np.arange(12).reshape(4, 3)
    c = clip_triangles(pts, tris, np.ones((12, 1)), "parallel")
    assert np.all(np.isfinite(_used(c))) and np.all(np.isfinite(c.attrs[len(pts):]))
    assert not set(c.source.tolist()) & {1, 2, 3}


def test_vertex_index_out_of_range_raises():
    pts = np.array([(0, 0, -0.5), (2, 0, -0.5), (0, 0.5, -0.5)])
    with pytest.raises(ValueError, match="outside 0..2"):
        clip_triangles(pts, [[0, 1, 3]], None, "parallel")


@pytest.mark.parametrize("clipper", ["cohen-sutherland", "liang-barsky", "homogeneous"])
def test_shared_edge_gets_identical_crossing_points(clipper):
    # Pairs of triangles sharing an edge that crosses a plane, walked in opposite directions
    # (a-b in one, b-a in the other): the crossing point and its attributes must be
    # bit-identical in both, or the mesh would crack along the clip plane.
    rng = np.random.default_rng(5)
    for projection in ("parallel", "perspective"):
        for _ in range(100):
            a = np.array([rng.uniform(-0.4, 0.4), rng.uniform(-0.4, 0.4), rng.uniform(-0.9, -0.6)])
            b = np.array([rng.uniform(1.2, 3.0), rng.uniform(-0.4, 0.4), rng.uniform(-0.9, -0.6)])
            c = a + [0.1, 0.3, 0.0]
            d = a + [0.1, -0.3, 0.0]
            pts = np.array([a, b, c, d])
            attrs = rng.normal(size=(4, 2))
            out = clip_triangles(pts, [[0, 1, 2], [1, 0, 3]], attrs, projection, Z_MIN,
                                 clipper=clipper)
            first, second = ({tuple(out.points[v]) + tuple(out.attrs[v])
                              for v in out.triangles[out.source == k].ravel()} for k in (0, 1))
            shared = first & second
            # a and the crossing point on a-b (x = 1, or x = -z): both triangles have them
            assert len(shared) == 2, (projection, pts)


# --- property: the clipped triangles cover exactly the part of the triangle in the volume ----

def _barycentric_2d(q, a, b, c):
    """Barycentric coordinates of 2D points q in triangle abc."""
    v0, v1, v2 = b - a, c - a, q - a
    d = v0[0] * v1[1] - v1[0] * v0[1]
    s = (v2[:, 0] * v1[1] - v1[0] * v2[:, 1]) / d
    t = (v0[0] * v2[:, 1] - v2[:, 0] * v0[1]) / d
    return 1 - s - t, s, t


_point = st.tuples(st.floats(-2.5, 2.5), st.floats(-2.5, 2.5), st.floats(-2.0, 1.0))


@settings(max_examples=150, deadline=None)
@given(st.lists(_point, min_size=3, max_size=3), st.sampled_from(["parallel", "perspective"]),
       st.sampled_from(["cohen-sutherland", "liang-barsky", "homogeneous"]))
def test_clipped_region_matches_brute_force(corners, projection, clipper):
    pts = np.array(corners, dtype=float)
    normal = np.cross(pts[1] - pts[0], pts[2] - pts[0])
    if np.linalg.norm(normal) < 1e-3:
        return                                            # (degenerate: covered elsewhere)
    # Carry each vertex's parameter-space position (s, t) as its attributes: the output
    # vertices then say where they are in the triangle, and positions must agree with them.
    st_attrs = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    c = clip_triangles(pts, [[0, 1, 2]], st_attrs, projection, Z_MIN, clipper=clipper)
    assert np.all(np.isfinite(c.points)) and np.all(np.isfinite(c.attrs))
    used = np.unique(c.triangles)
    assert np.all(_inside(c.points[used], projection, tol=1e-9))
    s, t = c.attrs[used, 0], c.attrs[used, 1]
    rebuilt = pts[0] + s[:, None] * (pts[1] - pts[0]) + t[:, None] * (pts[2] - pts[0])
    assert np.allclose(rebuilt, c.points[used], atol=1e-9)
    assert np.all(c.source == 0)
    # Sample the triangle; points clearly inside the volume must be covered by an output
    # triangle (in (s, t) space), points clearly outside must not.
    rng = np.random.default_rng(0)
    u = rng.random((400, 2))
    u = np.where(u.sum(1, keepdims=True) > 1, 1 - u, u)
    samples = pts[0] + u[:, :1] * (pts[1] - pts[0]) + u[:, 1:] * (pts[2] - pts[0])
    deep = _inside(samples, projection, tol=-1e-6)
    out = ~_inside(samples, projection, tol=1e-6)
    covered = np.zeros(len(u), bool)
    for tri in c.triangles:
        a, b, d = c.attrs[tri]
        if abs((b - a)[0] * (d - a)[1] - (d - a)[0] * (b - a)[1]) < 1e-15:
            continue
        w = _barycentric_2d(u, a, b, d)
        covered |= (w[0] >= -1e-9) & (w[1] >= -1e-9) & (w[2] >= -1e-9)
    assert np.all(covered[deep])
    assert not np.any(covered[out])


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_outcodes_on_all_cores_equal_one_pass(projection):
    """From PARALLEL_POINTS points the outcodes are found in chunks on all cores: the same
    codes and the same 'any outside' as one pass, NaN and far points included."""
    from core.pipeline import clip_polygon as cp
    rng = np.random.default_rng(21)
    points = rng.uniform(-1.3, 0.3, size=(cp.PARALLEL_POINTS + 1234, 3))
    points[::997] = np.nan
    perspective = projection == "perspective"
    codes, any_outside = cp._outcodes_and_any(points, perspective, -0.1)
    one = np.empty(len(points), np.uint8)
    assert any_outside == cp._outcodes(points, perspective, -0.1, one, 0, len(points)) != 0
    np.testing.assert_array_equal(codes, one)
    inside = np.zeros((cp.PARALLEL_POINTS, 3)) - 0.5
    assert cp._outcodes_and_any(inside, perspective, -0.1)[1] == 0
