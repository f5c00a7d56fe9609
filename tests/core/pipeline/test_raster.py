"""The scan-line z-buffer (core/pipeline/raster.py): fill rule, watertightness, depth, barycentrics.

Coverage is counted with ``count_fragments``, which runs the rasterizer's own kernels with a
counter beside the depth test, so "each pixel exactly once" is a statement about the real code.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from core.pipeline import raster
from core.pipeline.raster import (SUBPIXEL_ONE, VisibilityBuffer, count_fragments,
                         rasterize)


def _draw(points_xy, triangles, width, height, z=None, inv_w=None, **kw):
    points_xy = np.asarray(points_xy, dtype=np.float64)
    n = len(points_xy)
    xy_z = np.column_stack([points_xy, np.full(n, -0.5) if z is None else z])
    inv_w = np.ones(n) if inv_w is None else np.asarray(inv_w, dtype=np.float64)
    return rasterize(xy_z, inv_w, np.asarray(triangles, dtype=np.int64), width, height, **kw)


def _pixels(mask: np.ndarray) -> set[tuple[int, int]]:
    """{(i, j)}: column i, device row j (counted from the bottom) of the True pixels."""
    rows, cols = np.nonzero(mask)
    return {(int(c), int(mask.shape[0] - 1 - r)) for r, c in zip(rows, cols)}


# --- hand-checked cases ----------------------------------------------------------------------

@pytest.mark.parametrize("order", [[0, 1, 2], [0, 2, 1]])
def test_right_triangle_pixel_set_under_top_left_rule(order):
    # Corners on pixel centres: (0.5, 0.5), (4.5, 0.5), (0.5, 4.5). Centres on the left edge
    # x = 0.5 belong (left edge); on the bottom edge y = 0.5 they do not (bottom); on the
    # hypotenuse x + y = 5 they do not (right side). Left: i >= 0; bottom: j >= 1;
    # hypotenuse: (i + .5) + (j + .5) < 5.
    corners = np.array([(0.5, 0.5), (4.5, 0.5), (0.5, 4.5)])[order]
    vis = _draw(corners, [[0, 1, 2]], 8, 6)
    expected = {(0, 1), (1, 1), (2, 1), (0, 2), (1, 2), (0, 3)}
    assert _pixels(vis.tri == 0) == expected
    assert np.all(vis.tri[vis.tri != 0] == -1)


def test_top_edge_is_drawn_bottom_edge_is_not():
    # Horizontal top edge at y = 3.5 (through centres) and apex below at y = 0.5.
    vis = _draw([(0.5, 3.5), (6.5, 3.5), (3.5, 0.5)], [[0, 1, 2]], 8, 5)
    # Row j = 3 (top edge): centres x in [0.5, 6.5): the left end is on the left edge (in),
    # the right end on the right edge (out). Apex row j = 0: the apex itself lies on both
    # the left and the right edge: out (right edge).
    assert {i for i, j in _pixels(vis.tri == 0) if j == 3} == {0, 1, 2, 3, 4, 5}
    assert {i for i, j in _pixels(vis.tri == 0) if j == 0} == set()
    # Flipped upside down the horizontal edge is a bottom edge: row j = 1 stays empty.
    vis = _draw([(0.5, 1.5), (3.5, 4.5), (6.5, 1.5)], [[0, 1, 2]], 8, 6)
    assert {i for i, j in _pixels(vis.tri == 0) if j == 1} == set()
    assert {i for i, j in _pixels(vis.tri == 0) if j == 2} == {1, 2, 3, 4}


def test_shared_edge_written_once():
    # A square with corners on pixel centres, cut along its diagonal: the centres on the
    # diagonal belong to exactly one of the two triangles, and the square's coverage is the
    # fill rule's: left and top edges in, right and bottom edges out.
    pts = [(0.5, 0.5), (3.5, 0.5), (3.5, 3.5), (0.5, 3.5)]
    for tris in ([[0, 1, 2], [0, 2, 3]], [[0, 2, 1], [2, 0, 3]], [[1, 3, 0], [1, 2, 3]]):
        counts = count_fragments(np.column_stack([pts, np.full(4, -0.5)]), np.ones(4),
                                 np.array(tris), 6, 6)
        assert _pixels(counts == 1) == {(i, j) for i in range(3) for j in range(1, 4)}
        assert counts.max() == 1


def test_image_order_row_zero_is_top():
    # A triangle near device y = 0 lands in the bottom rows of the array.
    vis = _draw([(0, 0), (3, 0), (0, 3)], [[0, 1, 2]], 4, 10)
    rows = np.nonzero(vis.tri == 0)[0]
    assert rows.min() >= 7 and rows.max() == 9


def test_nearer_wins_in_either_order():
    square = [(0, 0), (8, 0), (8, 8), (0, 8)]
    pts = square + square
    z = [-0.5] * 4 + [-0.2] * 4                   # second square nearer (larger z)
    tris = [[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]]
    vis = _draw(pts, tris, 8, 8, z=z)
    assert np.all(vis.depth == -0.2) and np.all(vis.tri >= 2)
    vis = _draw(pts, tris[2:] + tris[:2], 8, 8, z=z)
    assert np.all(vis.depth == -0.2) and np.all(vis.tri <= 1)
    # Equal depth: the notes' test z >= zbuffer lets the later triangle win.
    vis = _draw(pts, tris, 8, 8, z=[-0.3] * 8)
    assert np.all(vis.tri >= 2)


def test_interpenetrating_triangles_split_where_depths_cross():
    # Two full-screen triangles: z = -0.5 everywhere, and z rising with x from -1 to 0 over 16
    # pixels: the second is nearer exactly where x > 8.
    pts = [(0, 0), (32, 0), (0, 32), (0, 0), (32, 0), (0, 32)]
    z = [-0.5, -0.5, -0.5, -1.0, 1.0, -1.0]
    vis = _draw(pts, [[0, 1, 2], [3, 4, 5]], 16, 1, z=z)
    # z of the second at pixel centre x: -1 + 2 x / 32.
    x = np.arange(16) + 0.5
    assert np.array_equal(vis.tri[0], np.where(-1 + 2 * x / 32 > -0.5, 1, 0))


def test_barycentrics_and_depth_at_a_pixel():
    # Corners (0, 0), (4, 0), (0, 4); pixel (1, 0) has its centre at (1.5, 0.5): screen-space
    # weights l1 = x / 4 = 0.375, l2 = y / 4 = 0.125, l0 = 0.5.
    pts = [(0, 0), (4, 0), (0, 4)]
    z = [-1.0, -0.5, 0.0]
    vis = _draw(pts, [[0, 1, 2]], 4, 4, z=z)
    row = 4 - 1 - 0
    assert vis.tri[row, 1] == 0
    assert vis.b1[row, 1] == pytest.approx(0.375, abs=1e-15)
    assert vis.b2[row, 1] == pytest.approx(0.125, abs=1e-15)
    # depth is affine in screen space: -1 * 0.5 + -0.5 * 0.375 + 0 * 0.125
    assert vis.depth[row, 1] == pytest.approx(-0.6875, abs=1e-15)
    # Perspective-correct: 1/W = (1, 0.5, 0.25). Weights l_k / W_k renormalised:
    # (0.5, 0.1875, 0.03125) / 0.71875 -> b1 = 6/23, b2 = 1/23. Depth stays screen-affine.
    vis = _draw(pts, [[0, 1, 2]], 4, 4, z=z, inv_w=[1.0, 0.5, 0.25])
    assert vis.b1[row, 1] == pytest.approx(6 / 23, abs=1e-15)
    assert vis.b2[row, 1] == pytest.approx(1 / 23, abs=1e-15)
    assert vis.depth[row, 1] == pytest.approx(-0.6875, abs=1e-15)
    # Empty pixels: depth -inf, tri -1 (their weights are left undefined).
    empty = vis.tri == -1
    assert empty.any()
    assert np.all(vis.depth[empty] == -np.inf)


def test_barycentrics_follow_the_input_vertex_order_for_either_winding():
    pts = np.array([(0, 0), (4, 0), (0, 4)], dtype=float)
    a = _draw(pts, [[0, 1, 2]], 4, 4, inv_w=[1.0, 0.5, 0.25])
    b = _draw(pts, [[0, 2, 1]], 4, 4, inv_w=[1.0, 0.5, 0.25])   # clockwise; 1 and 2 swap
    assert np.array_equal(a.tri, b.tri)
    assert np.allclose(a.b1, b.b2, atol=1e-15) and np.allclose(a.b2, b.b1, atol=1e-15)


def test_zero_area_and_unusable_triangles_draw_nothing():
    pts = [(0, 0), (5, 5), (10, 10), (0, 0), (9, 0), (0, 9)]
    z = np.full(6, -0.5)
    vis = _draw(pts, [[0, 1, 2], [0, 0, 4]], 8, 8, z=z)          # collinear; repeated vertex
    assert np.all(vis.tri == -1)
    bad_z = z.copy()
    bad_z[3] = np.nan
    vis = _draw(pts, [[3, 4, 5]], 8, 8, z=bad_z)                  # NaN vertex
    assert np.all(vis.tri == -1)
    vis = _draw(pts, [[3, 4, 5]], 8, 8, z=z, inv_w=[1, 1, 1, 0.0, 1, 1])   # 1/W = 0
    assert np.all(vis.tri == -1)
    vis = _draw(pts, np.zeros((0, 3)), 8, 8)                      # no triangles at all
    assert np.all(vis.tri == -1)


def test_huge_and_out_of_range_coordinates_are_clamped_not_indexed():
    big = 1e30
    vis = _draw([(-big, -big), (big, -big), (0, big)], [[0, 1, 2]], 8, 8)
    assert np.all(vis.tri == 0)                                   # clamped, still covers all
    vis = _draw([(-50, -50), (-40, -50), (-50, -40), (100, 3), (120, 3), (100, 5)],
                [[0, 1, 2], [3, 4, 5]], 8, 8)
    assert np.all(vis.tri == -1)                                  # wholly outside
    vis = _draw([(-20, -20), (12, -4), (-4, 12)], [[0, 1, 2]], 8, 8)
    assert vis.tri[7, 0] == 0 and vis.tri[0, 7] == -1             # clipped by the box


def test_buffer_is_reused_and_cleared():
    out = VisibilityBuffer.allocate(8, 8)
    vis = _draw([(0, 0), (8, 0), (0, 8)], [[0, 1, 2]], 8, 8, out=out)
    assert vis is out and (out.tri == 0).sum() == 28
    vis = _draw([(8, 8), (4, 8), (8, 4)], [[0, 1, 2]], 8, 8, out=out)
    assert vis is out
    assert (out.tri == 0).sum() == 10 and out.tri[7, 0] == -1 and out.depth[7, 0] == -np.inf
    # Another size: a fresh buffer.
    other = _draw([(0, 0), (8, 0), (0, 8)], [[0, 1, 2]], 9, 8, out=out)
    assert other is not out and other.tri.shape == (8, 9)
    out.clear()
    assert np.all(out.tri == -1) and np.all(out.depth == -np.inf) and np.all(out.b1 == 0)


def test_bad_arguments_raise_value_error():
    with pytest.raises(ValueError, match="xy_z"):
        rasterize(np.zeros((3, 2)), np.ones(3), np.zeros((1, 3), np.int64), 4, 4)
    with pytest.raises(ValueError, match="inv_w"):
        rasterize(np.zeros((3, 3)), np.ones(2), np.zeros((1, 3), np.int64), 4, 4)
    with pytest.raises(ValueError, match="outside 0..2"):
        rasterize(np.zeros((3, 3)), np.ones(3), np.array([[0, 1, 3]]), 4, 4)
    with pytest.raises(ValueError, match="size"):
        rasterize(np.zeros((3, 3)), np.ones(3), np.array([[0, 1, 2]]), 0, 4)


# --- watertightness --------------------------------------------------------------------------

def _split_square(rng, x0, y0, x1, y1, splits):
    """Tessellate [x0, x1] x [y0, y1] (integers in 1/256 pixel) by inserting random interior
    points into random triangles; every point is on the fixed-point grid, so snapping moves
    nothing and no triangle folds over. Returns (points in pixels, triangles)."""
    pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    tris = [(0, 1, 2), (0, 2, 3)]
    p = np.array(pts, dtype=np.int64)

    def area2(a, b, c):
        (ax, ay), (bx, by), (cx, cy) = p[a], p[b], p[c]
        return (bx - ax) * (cy - ay) - (cx - ax) * (by - ay)

    points = list(pts)
    done = 0
    while done < splits:
        k = int(rng.integers(len(tris)))
        a, b, c = tris[k]
        w = rng.dirichlet((1.0, 1.0, 1.0))
        q = np.rint(w[0] * p[a] + w[1] * p[b] + w[2] * p[c]).astype(np.int64)
        p = np.vstack([p, q])
        d = len(p) - 1
        s = np.sign(area2(a, b, c))
        if not all(np.sign(area2(*t)) == s for t in ((a, b, d), (b, c, d), (c, a, d))):
            p = p[:-1]                                  # on an edge after rounding: retry
            continue
        points.append(tuple(q))
        tris[k] = (a, b, d)
        tris += [(b, c, d), (c, a, d)]
        done += 1
    return np.array(points, dtype=np.float64) / SUBPIXEL_ONE, np.array(tris, dtype=np.int64)


@pytest.mark.parametrize("seed", [1, 2])
def test_random_subdivision_of_a_square_covers_each_pixel_once(seed):
    rng = np.random.default_rng(seed)
    # A square with random sub-pixel corners, 40 x 30 pixels, inside a 48 x 40 buffer.
    x0, y0 = (rng.integers(2 * 256, 4 * 256, size=2))
    x1, y1 = x0 + 40 * 256 + rng.integers(256), y0 + 30 * 256 + rng.integers(256)
    pts, tris = _split_square(rng, x0, y0, x1, y1, 2000)
    assert len(tris) > 4000
    tris = tris[rng.permutation(len(tris))]
    flip = rng.random(len(tris)) < 0.5                  # random winding
    tris[flip] = tris[flip][:, ::-1]
    # A perspective-like 1/W and depth across the square (coverage must not care).
    inv_w = 1.0 / (1.0 + pts[:, 0] / 50.0)
    xy_z = np.column_stack([pts, -0.5 + 0.01 * pts[:, 1] * inv_w])
    counts = count_fragments(xy_z, inv_w, tris, 48, 40)
    # Expected: pixel centres with x0 <= cx < x1 and y0 < cy <= y1 (left and top edges in).
    cx = (np.arange(48) * 256 + 128)[None, :]
    cy = (np.arange(40) * 256 + 128)[::-1, None]        # image order: row 0 is the top
    inside = (x0 <= cx) & (cx < x1) & (y0 < cy) & (cy <= y1)
    assert np.array_equal(counts, inside.astype(np.int32))
    vis = rasterize(xy_z, inv_w, tris, 48, 40)
    assert np.array_equal(vis.tri >= 0, inside)


def _perspective_grid(rng, n):
    """A tilted square seen in perspective, tessellated as a jittered n x n grid with random
    diagonals. Returns device xy_z, inv_w, triangles and the projected corners."""
    u = np.linspace(0.0, 1.0, n + 1)
    uu, vv = np.meshgrid(u, u, indexing="ij")
    jitter = rng.uniform(-0.3, 0.3, size=(2, n + 1, n + 1)) / n
    jitter[0, [0, -1], :] = 0.0                          # boundary points stay on the boundary
    jitter[1, :, [0, -1]] = 0.0
    uu, vv = uu + jitter[0], vv + jitter[1]
    # The square in eye space: tilted away, 2.5 .. 4.5 in front of the eye.
    X = -1.0 + 2.0 * uu
    Y = -1.0 + 2.0 * vv
    Z = -3.5 + 0.8 * X + 0.5 * Y
    W = -Z
    dx, dy = rng.uniform(0, 1, size=2)                   # random sub-pixel offset
    x = 48 + dx + 75 * X / W
    y = 40 + dy + 75 * Y / W
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    diag = rng.random(n * n) < 0.5
    t1 = np.where(diag[:, None], np.stack([a, b, c], 1), np.stack([a, b, d], 1))
    t2 = np.where(diag[:, None], np.stack([a, c, d], 1), np.stack([b, c, d], 1))
    tris = np.concatenate([t1, t2])
    corners = np.array([(x[i, j], y[i, j]) for i, j in ((0, 0), (n, 0), (n, n), (0, n))])
    return (np.column_stack([x.ravel(), y.ravel(), (-1.0 + 1.0 / W).ravel()]), 1.0 / W.ravel(),
            tris, corners)


def _signed_distance_inside(corners, px, py):
    """Smallest distance of each point to the convex quad's edges (> 0 inside, CCW quad)."""
    best = np.full(px.shape, np.inf)
    for k in range(4):
        (ax, ay), (bx, by) = corners[k], corners[(k + 1) % 4]
        length = np.hypot(bx - ax, by - ay)
        best = np.minimum(best, ((bx - ax) * (py - ay) - (by - ay) * (px - ax)) / length)
    return best


@pytest.mark.parametrize("seed", [3, 4])
def test_perspective_tessellation_is_watertight(seed):
    rng = np.random.default_rng(seed)
    xy_z, inv_w, tris, corners = _perspective_grid(rng, 50)
    assert len(tris) == 5000
    tris = tris[rng.permutation(len(tris))]
    counts = count_fragments(xy_z, inv_w, tris, 96, 80)
    assert counts.max() == 1                             # no pixel written twice
    px, py = np.meshgrid(np.arange(96) + 0.5, np.arange(80)[::-1] + 0.5)
    d = _signed_distance_inside(corners, px, py)
    assert np.all(counts[d > 1e-2] == 1)                 # no hole inside
    assert np.all(counts[d < -1e-2] == 0)                # nothing outside
    assert (d > 1e-2).sum() > 1500
    vis = rasterize(xy_z, inv_w, tris, 96, 80)
    covered = vis.tri >= 0
    assert np.all(vis.b1[covered] >= 0) and np.all(vis.b2[covered] >= 0)
    assert np.all(vis.b1[covered] + vis.b2[covered] <= 1 + 1e-12)


# --- order independence and the parallel path ------------------------------------------------

def _random_scene(rng, n, width, height):
    """n random overlapping triangles with random depths and perspective-like 1/W."""
    centres = rng.uniform([0, 0], [width, height], size=(n, 1, 2))
    pts = (centres + rng.normal(scale=0.15 * min(width, height), size=(n, 3, 2))).reshape(-1, 2)
    z = rng.uniform(-1, 0, size=3 * n)
    inv_w = rng.uniform(0.3, 3.0, size=3 * n)
    return np.column_stack([pts, z]), inv_w, np.arange(3 * n).reshape(n, 3)


def _sphere_torus(n):
    """A sphere and a torus in device coordinates, seen in perspective (500 x 500)."""
    k = max(4, int(np.sqrt(n / 4)))
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, k, endpoint=False),
                       np.linspace(0, 2 * np.pi, k, endpoint=False), indexing="ij")
    u, v = u.ravel(), v.ravel()
    sphere = np.stack([np.cos(u) * np.sin(v / 2), np.sin(u) * np.sin(v / 2), np.cos(v / 2)], 1)
    ring = 0.8 + 0.3 * np.cos(v)
    torus = np.stack([ring * np.cos(u), 0.6 * ring * np.sin(u) + 0.24 * np.sin(v),
                      0.18 * np.sin(v) - 0.8 * ring * np.sin(u)], 1)
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    a, b = (i * k + j).ravel(), (((i + 1) % k) * k + j).ravel()
    c, d = (((i + 1) % k) * k + (j + 1) % k).ravel(), (i * k + (j + 1) % k).ravel()
    grid = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    p = np.concatenate([0.9 * sphere + [-0.8, 0.3, 0.0], torus + [0.9, -0.5, 0.0]])
    tris = np.concatenate([grid, grid + k * k])
    w = 4.0 - p[:, 2]
    xy_z = np.column_stack([250 + 440 * p[:, 0] / w, 250 + 440 * p[:, 1] / w, -1 + 2 / w])
    return xy_z, 1.0 / w, tris


def test_shuffled_order_gives_identical_buffers():
    rng = np.random.default_rng(7)
    xy_z, inv_w, tris = _random_scene(rng, 400, 64, 48)
    a = rasterize(xy_z, inv_w, tris, 64, 48)
    perm = rng.permutation(len(tris))
    b = rasterize(xy_z, inv_w, tris[perm], 64, 48)
    covered = a.tri >= 0
    assert covered.mean() > 0.5
    assert np.array_equal(a.depth, b.depth)
    assert np.array_equal(a.tri, np.where(b.tri >= 0, perm[b.tri], -1))
    assert np.array_equal(a.b1, b.b1) and np.array_equal(a.b2, b.b2)


def test_without_barycentrics_the_depths_and_ids_are_the_same_and_the_weights_untouched():
    rng = np.random.default_rng(9)
    xy_z, inv_w, tris = _random_scene(rng, 400, 64, 48)
    full = rasterize(xy_z, inv_w, tris, 64, 48)
    assert full.barycentrics
    lean = VisibilityBuffer.allocate(64, 48)
    lean.b1.fill(7.0)
    lean = rasterize(xy_z, inv_w, tris, 64, 48, out=lean, barycentrics=False)
    assert not lean.barycentrics
    assert np.array_equal(full.depth, lean.depth) and np.array_equal(full.tri, lean.tri)
    assert (lean.b1 == 7.0).all()                     # not written: flat shading's frame
    again = rasterize(xy_z, inv_w, tris, 64, 48, out=lean)
    covered = again.tri >= 0
    assert again.barycentrics and np.array_equal(again.b1[covered], full.b1[covered])


def test_flat_frames_skip_the_weights_and_inspections_keep_them():
    from core.render import render
    from core.scene.generators import sphere_torus
    from core.settings import RenderSettings
    scene = sphere_torus(triangles=2_000)
    seen = {}
    for shading in ("flat", "gouraud"):
        settings = RenderSettings.for_scene(scene, shading=shading, size=(64, 48))
        plain = render(scene, scene.views[0], settings)
        arrays = {}
        inspected = render(scene, scene.views[0], settings,
                           inspect=lambda stage, a: arrays.update(
                               {stage: {k: np.array(v) for k, v in a.items()}}))
        assert np.array_equal(plain.rgbx, inspected.rgbx)      # the same picture either way
        seen[shading] = arrays["z-buffer"]                     # copies: the buffer is reused
    b1 = seen["flat"]["b1"][seen["flat"]["tri"] >= 0]          # the inspector's weights
    assert np.array_equal(b1, seen["gouraud"]["b1"][seen["gouraud"]["tri"] >= 0])


def test_shuffled_mesh_gives_identical_buffers():
    rng = np.random.default_rng(8)
    xy_z, inv_w, tris = _sphere_torus(20_000)
    a = rasterize(xy_z, inv_w, tris, 500, 500)
    perm = rng.permutation(len(tris))
    b = rasterize(xy_z, inv_w, tris[perm], 500, 500)
    assert np.array_equal(a.depth, b.depth)
    assert np.array_equal(a.tri, np.where(b.tri >= 0, perm[b.tri], -1))


@pytest.mark.parametrize("n_bands", [2, 3, 7, 16])
def test_parallel_bands_are_bit_identical_to_serial(n_bands, monkeypatch):
    monkeypatch.setattr(raster, "PARALLEL_SETUP", 0)       # the parallel setup too
    rng = np.random.default_rng(n_bands)
    for xy_z, inv_w, tris, w, h in (_random_scene(rng, 300, 61, 47) + (61, 47),
                                    _sphere_torus(30_000) + (500, 500)):
        # every triangle twice: equal depths, so the ids show the order each pixel saw
        tris = np.concatenate([tris, tris[::-1]])
        serial = rasterize(xy_z, inv_w, tris, w, h, parallel=False)
        banded = rasterize(xy_z, inv_w, tris, w, h, parallel=True, n_bands=n_bands)
        for name in ("depth", "tri", "b1", "b2"):
            assert np.array_equal(getattr(serial, name), getattr(banded, name)), name
        assert np.array_equal(count_fragments(xy_z, inv_w, tris, w, h, parallel=False),
                              count_fragments(xy_z, inv_w, tris, w, h, n_bands=n_bands))


@pytest.mark.parametrize("n_tiles", [1, 2, 3, 4, 7, 64, 425])
def test_the_cores_are_dealt_every_tile_once_from_both_halves(n_tiles):
    """The rast's handout order is a permutation of the tiles, odd counts included, and two
    consecutive handouts lie half the screen apart (by tile index)."""
    order = [raster._dealt(n, n_tiles) for n in range(n_tiles)]
    assert sorted(order) == list(range(n_tiles))
    half = (n_tiles + 1) // 2
    assert order[0::2] == list(range(half)) and order[1::2] == list(range(half, n_tiles))


# --- an independent reference for the fill rule ----------------------------------------------

def _reference_coverage(corners, width, height):
    """Pixel centres inside the snapped triangle, by Python integers and the top-left rule
    written from its definition (edges walked counter-clockwise in y-up coordinates)."""
    f = [(int(np.floor(x * 256 + 0.5)), int(np.floor(y * 256 + 0.5))) for x, y in corners]
    area = (f[1][0] - f[0][0]) * (f[2][1] - f[0][1]) - (f[2][0] - f[0][0]) * (f[1][1] - f[0][1])
    out = np.zeros((height, width), bool)
    if area == 0:
        return out
    if area < 0:
        f = [f[0], f[2], f[1]]
    for j in range(height):
        for i in range(width):
            cx, cy = i * 256 + 128, j * 256 + 128
            inside = True
            for k in range(3):
                (ax, ay), (bx, by) = f[k], f[(k + 1) % 3]
                e = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
                # counter-clockwise, y up: a left edge runs downwards, a top edge leftwards
                top_left = by < ay or (by == ay and bx < ax)
                if e < 0 or (e == 0 and not top_left):
                    inside = False
            out[height - 1 - j, i] = inside
    return out


# Coordinates on a coarse grid (quarter pixels) so that centres often fall exactly on edges.
_coord = st.integers(-4, 44).map(lambda k: k / 4.0)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(_coord, _coord), min_size=3, max_size=3))
def test_coverage_matches_an_independent_reference(corners):
    vis = _draw(corners, [[0, 1, 2]], 10, 9)
    assert np.array_equal(vis.tri == 0, _reference_coverage(corners, 10, 9))
