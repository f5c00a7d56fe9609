"""The course's viewport mapping (the window fills the viewport, stretched) and depth ties.

Hand values: the notes' example view (window -1 17 -1 8, PRP (8, 6, 30), VRP on the house's
front wall) on a 500 x 500 framebuffer. A point on the view plane projects to its own (u, v);
the device x is (u - u_min) / 18 * 500 and y is (v - v_min) / 9 * 500 when the window is
stretched, and y = 125 + (v - v_min) / 9 * 250 when it is letterboxed (rows 125-375).
"""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.view import View, normalizing_transform
from core.pipeline import project
from core.pipeline.raster import rasterize
from core.transforms import apply

NOTES_VIEW = View(vrp=(0, 0, 54), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 8),
                  prp=(8, 6, 30), front=1, back=-23)
# house corners: two on the front wall (the view plane), one on the back wall (z = 30)
FRONT_LEFT, FRONT_RIGHT, BACK_LEFT = (0, 0, 54), (16, 0, 54), (0, 0, 30)


def _device(view, points, projection, size, keep_aspect=False):
    n, _ = normalizing_transform(view, projection)
    vp = project.viewport(view.window, *size, keep_aspect=keep_aspect)
    return project.project_lines(apply(n, np.asarray(points, float))[:, :3], projection, vp)


def test_viewport_fills_the_framebuffer_by_default():
    assert project.viewport((-1, 17, -1, 8), 500, 500) == (0.0, 500.0, 0.0, 500.0)
    assert project.viewport((-1, 17, -1, 8), 500, 500, keep_aspect=True) == (0.0, 500.0, 125.0, 375.0)
    assert project.viewport((-1, 1, -1, 1), 600, 300, keep_aspect=True) == (150.0, 450.0, 0.0, 300.0)


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_house_front_corners_stretched_and_letterboxed(projection):
    stretched = _device(NOTES_VIEW, [FRONT_LEFT, FRONT_RIGHT], projection, (500, 500))
    # (0, 0) -> u = 0, v = 0: x = 1/18 * 500, y = 1/9 * 500; (16, 0): x = 17/18 * 500
    np.testing.assert_allclose(stretched[:, :2], [[500 / 18, 500 / 9], [17 * 500 / 18, 500 / 9]],
                               atol=1e-9)
    boxed = _device(NOTES_VIEW, [FRONT_LEFT, FRONT_RIGHT], projection, (500, 500), True)
    np.testing.assert_allclose(boxed[:, :2], [[500 / 18, 125 + 250 / 9],
                                              [17 * 500 / 18, 125 + 250 / 9]], atol=1e-9)


def test_house_back_corner_in_perspective_by_hand():
    # (0, 0, 30) is (0, 0, -24) in VRC; from PRP (8, 6, 30) the ray meets n = 0 at t = 30/54:
    # u = 8 - 8 * 5/9 = 32/9, v = 6 - 6 * 5/9 = 24/9 -> x = (41/9)/18 * 500, y = (33/9)/9 * 500
    device = _device(NOTES_VIEW, [BACK_LEFT], "perspective", (500, 500))
    np.testing.assert_allclose(device[0, :2], [41 * 500 / 162, 33 * 500 / 81], atol=1e-9)
    # a non-square framebuffer stretches each axis on its own
    device = _device(NOTES_VIEW, [BACK_LEFT], "perspective", (300, 200))
    np.testing.assert_allclose(device[0, :2], [41 * 300 / 162, 33 * 200 / 81], atol=1e-9)


def test_depth_tie_goes_to_the_later_triangle():
    # Two coincident squares (the same four corners, the same depths) drawn as triangles 0, 1
    # (first surface) and 2, 3 (second): the notes' z >= zbuffer lets the second win everywhere.
    corners = np.array([(0.3, 0.2, -0.4), (7.7, 0.2, -0.3), (7.7, 5.9, -0.2), (0.3, 5.9, -0.3)])
    xy_z = np.concatenate([corners, corners])
    tris = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]], np.int64)
    vis = rasterize(xy_z, np.ones(8), tris, 8, 6)
    covered = vis.tri >= 0
    assert covered.all() and set(np.unique(vis.tri[covered])) == {2, 3}
    # drawn the other way round, the first pair (now later) wins
    vis = rasterize(xy_z, np.ones(8), tris[[2, 3, 0, 1]], 8, 6)
    assert set(np.unique(vis.tri[vis.tri >= 0])) == {2, 3}   # indices into the reordered list
