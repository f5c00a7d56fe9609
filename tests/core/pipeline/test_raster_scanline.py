"""The course's scan-line rasterizer (core/pipeline/raster_scanline.py) against the edge one.

- Coverage, depth and the visible triangle are identical to ``core.pipeline.raster`` on many
  random scenes (bit for bit: the same fixed point, fill rule and depth expression).
- Its weights are screen-linear, the edge rasterizer's perspective-correct: on a floor seen at
  a grazing angle the two differ visibly, and each is checked against values worked out by
  hand (2D barycentrics of the pixel centre; the pixel's ray meeting the floor).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from core.camera.view import View, normalizing_transform
from core.pipeline import project, raster, raster_scanline
from core.transforms import apply


def _both(xy_z, inv_w, tris, width, height):
    a = raster.rasterize(xy_z, inv_w, tris, width, height)
    b = raster_scanline.rasterize(xy_z, inv_w, tris, width, height)
    return a, b


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), width=st.integers(1, 48), height=st.integers(1, 48),
       n=st.integers(1, 40), on_grid=st.booleans())
def test_same_coverage_depth_and_triangle_as_the_edge_rasterizer(seed, width, height, n, on_grid):
    rng = np.random.default_rng(seed)
    xy = np.column_stack([rng.uniform(-8, width + 8, 3 * n), rng.uniform(-8, height + 8, 3 * n)])
    if on_grid:                     # corners on pixel centres and edges: the fill rule's cases
        xy = np.round(xy * 2) / 2
    xy_z = np.column_stack([xy, rng.uniform(-1, 0, 3 * n)])
    tris = rng.integers(0, 3 * n, (n, 3))
    inv_w = rng.uniform(0.1, 3.0, 3 * n)
    a, b = _both(xy_z, inv_w, tris, width, height)
    assert np.array_equal(a.tri, b.tri)
    assert np.array_equal(a.depth, b.depth)


def test_a_shared_edge_is_filled_once_and_a_mesh_without_cracks():
    # a 6 x 5 grid of squares split into triangles, corners off the pixel grid: every pixel
    # inside is covered exactly as the edge rasterizer covers it, and none is left empty
    rng = np.random.default_rng(7)
    gx, gy = np.meshgrid(np.linspace(0.3, 29.7, 7), np.linspace(0.3, 24.7, 6))
    pts = np.column_stack([gx.ravel() + rng.uniform(-.2, .2, gx.size),
                           gy.ravel() + rng.uniform(-.2, .2, gy.size), np.full(gx.size, -0.5)])
    pts[[0, 6, 35, 41], :2] = [(0.3, 0.3), (29.7, 0.3), (0.3, 24.7), (29.7, 24.7)]
    tris = []
    for r in range(5):
        for c in range(6):
            k = r * 7 + c
            tris += [(k, k + 1, k + 8), (k, k + 8, k + 7)]
    a, b = _both(pts, np.ones(len(pts)), np.array(tris), 30, 25)
    assert np.array_equal(a.tri, b.tri)
    # edges of the outer square stay straight: every centre from 0.5 to 29.5 x 0.5 to 24.5
    assert (b.tri >= 0).all()


# --------------------------------------------------------------------------- grazing angle

# Eye at (0, 0, 1) looking down -z at the view plane z = 0 (window -1..1), 320 x 256 pixels.
# The floor y = -0.5 carries A (-0.8, -0.5, 0), B (0.8, -0.5, 0) on the view plane and C
# (0, -0.5, -31) far away: 1 / (1 - z) = 1/32 there. On the device (x = (x_p + 1) 160,
# y = (y_p + 1) 128): A (32, 64), B (288, 64), C (160, 126) -- all on the fixed-point grid.
GRAZE_VIEW = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                  prp=(0, 0, 1), front=0.5, back=-40)
A, B, C = np.array([-0.8, -0.5, 0.0]), np.array([0.8, -0.5, 0.0]), np.array([0.0, -0.5, -31.0])
SIZE = (320, 256)


def _graze():
    n, z_min = normalizing_transform(GRAZE_VIEW, "perspective")
    vp = project.viewport(GRAZE_VIEW.window, *SIZE)
    device, inv_w = project.project_triangles(apply(n, np.array([A, B, C]))[:, :3],
                                              "perspective", z_min, vp)
    return device, inv_w


def _screen_weights(i, j):
    """2D barycentrics (of B and C) of pixel centre (i + .5, j + .5) in the device triangle."""
    a, b, c = np.array([32.0, 64.0]), np.array([288.0, 64.0]), np.array([160.0, 126.0])
    p = np.array([i + 0.5, j + 0.5])
    m = np.column_stack([b - a, c - a])
    return np.linalg.solve(m, p - a)


def _floor_weights(i, j):
    """Weights (of B and C) of the floor point the pixel's ray meets: x_p, y_p on the view
    plane; the ray (0, 0, 1) + t (x_p, y_p, -1) meets y = -0.5 at t = -0.5 / y_p."""
    xp, yp = (i + 0.5) / 160 - 1, (j + 0.5) / 128 - 1
    t = -0.5 / yp
    p = np.array([t * xp, -0.5, 1 - t])
    m = np.column_stack([(B - A)[[0, 2]], (C - A)[[0, 2]]])
    return np.linalg.solve(m, (p - A)[[0, 2]])


def test_device_corners_are_the_hand_values():
    device, inv_w = _graze()
    np.testing.assert_allclose(device[:, :2], [(32, 64), (288, 64), (160, 126)], atol=1e-9)
    np.testing.assert_allclose(inv_w[2] / inv_w[0], 1 / 32, rtol=1e-12)   # W = 1 - z, scaled


@pytest.mark.parametrize("pixel", [(160, 70), (160, 100), (150, 120), (170, 90), (100, 68)])
def test_grazing_floor_perspective_correct_and_screen_linear_by_hand(pixel):
    device, inv_w = _graze()
    tris = np.array([[0, 1, 2]])
    edge, scan = _both(device, inv_w, tris, *SIZE)
    i, j = pixel
    row = SIZE[1] - 1 - j
    assert edge.tri[row, i] == 0 and scan.tri[row, i] == 0
    np.testing.assert_allclose([edge.b1[row, i], edge.b2[row, i]], _floor_weights(i, j),
                               atol=1e-12)
    np.testing.assert_allclose([scan.b1[row, i], scan.b2[row, i]], _screen_weights(i, j),
                               atol=1e-12)


def test_grazing_floor_differs_visibly():
    # Gouraud with intensity 0 at A and B and 1 at C: the pixel value is 255 * (C's weight).
    device, inv_w = _graze()
    edge, scan = _both(device, inv_w, np.array([[0, 1, 2]]), *SIZE)
    covered = edge.tri >= 0
    assert np.array_equal(covered, scan.tri >= 0)
    correct = np.round(255 * edge.b2[covered])
    linear = np.round(255 * scan.b2[covered])
    # halfway up the triangle on the screen the floor is only 1/33 of the way to C
    i, j = 160, 95
    row = SIZE[1] - 1 - j
    assert abs(scan.b2[row, i] - 0.5) < 0.01 and edge.b2[row, i] < 0.04
    # measured: 97% of the 7936 pixels differ by more than 2/255, by 78/255 on average and
    # by up to 178/255
    assert np.abs(correct - linear).max() > 150
    assert (np.abs(correct - linear) > 2).mean() > 0.9
    assert np.abs(correct - linear).mean() > 50
