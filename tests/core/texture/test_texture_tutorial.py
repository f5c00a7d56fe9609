"""The tutorial's nine-constant texture path equals perspective-correct interpolation.

Random triangles under perspective are rasterized by the project's z-buffer, which leaves
perspective-correct barycentrics per pixel; (u, v) interpolated with them must equal the
tutorial's u = a/c, v = b/c stepped along the scan lines, to 1e-9. The vertices are put on the
rasterizer's 1/256-pixel grid, so both start from the same plane (the rasterizer snaps them).
"""

from __future__ import annotations

import numpy as np
import pytest

from core.pipeline.raster import SUBPIXEL_ONE, rasterize
from core.texture import Texture
from core.texture.tutorial import nine_constants, scan_uv, triangle_constants, tutorial_map

WIDTH, HEIGHT = 160, 120


def _random_triangles(rng, count):
    """Device points (x, y on the 1/256 grid, z in [-1, 0]) with W from 0.5 to 20."""
    xy = np.round(rng.uniform(-20, [WIDTH + 20, HEIGHT + 20], (3 * count, 2)) * SUBPIXEL_ONE)
    device = np.column_stack([xy / SUBPIXEL_ONE, rng.uniform(-1, 0, 3 * count)])
    w = rng.uniform(0.5, 20.0, 3 * count)
    uv = rng.uniform(-2, 3, (3 * count, 2))
    triangles = np.arange(3 * count).reshape(count, 3)
    return device, w, uv, triangles


def _interpolated(vis, triangles, uv):
    t = vis.tri
    inside = t >= 0
    corners = uv[triangles[t[inside]]]                    # (n, 3, 2)
    b1, b2 = vis.b1[inside], vis.b2[inside]
    weights = np.stack([1 - b1 - b2, b1, b2], axis=1)[:, :, None]
    return inside, (weights * corners).sum(axis=1)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_tutorial_uv_equals_perspective_correct_barycentrics(seed):
    rng = np.random.default_rng(seed)
    device, w, uv, triangles = _random_triangles(rng, 12)
    vis = rasterize(device, 1.0 / w, triangles, WIDTH, HEIGHT)
    inside, expected = _interpolated(vis, triangles, uv)
    assert inside.sum() > 2000                           # the test covers real pixels
    device_h = np.column_stack([device * w[:, None], w])
    constants = triangle_constants(device_h, triangles, uv, HEIGHT)
    got = np.empty((HEIGHT, WIDTH, 2))
    scan_uv(vis.tri.astype(np.int64), constants, 1.0, got)
    assert np.isnan(got[~inside]).all()
    error = np.abs(got[inside] - expected)
    assert error.max() < 1e-9, error.max()


def test_nine_constants_are_the_printed_formulas():
    P, M, N = np.array([1.0, 2, 3]), np.array([4.0, 5, 6]), np.array([7.0, 8, 10])
    c = nine_constants(P, M, N)
    assert c[0].tolist() == [7 * 3 - 10 * 1, 4 * 3 - 6 * 1, 6 * 7 - 4 * 10]      # O_a O_b O_c
    assert c[1].tolist() == [10 * 2 - 8 * 3, 6 * 2 - 5 * 3, 5 * 10 - 6 * 8]      # H
    assert c[2].tolist() == [8 * 1 - 7 * 2, 5 * 1 - 4 * 2, 4 * 8 - 5 * 7]        # V
    # as vectors: a = (P x N).r, b = (P x M).r, c = (M x N).r with r = (i, 1, j)
    i, j = 3.0, -2.0
    r = np.array([i, 1.0, j])
    abc = c[0] + c[1] * i + c[2] * j
    np.testing.assert_allclose(abc, [np.cross(P, N) @ r, np.cross(P, M) @ r, np.cross(M, N) @ r])


def test_tutorial_map_copies_the_nearest_texel():
    """A square seen head-on with (u, v) = its corners: one texel per 256/W pixels."""
    size = 64
    img = np.random.default_rng(0).random((size, size, 3))
    tex = Texture.from_array(img, wrap="repeat")
    device = np.array([[0, 0, -0.5], [size, 0, -0.5], [size, size, -0.5], [0, size, -0.5]], float)
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    vis = rasterize(device, np.ones(4), triangles, size, size)
    device_h = np.column_stack([device, np.ones(4)])
    constants = triangle_constants(device_h, triangles, uv, size)
    texels, levels = tex.packed()
    out = np.zeros((size, size, 3))
    tutorial_map(vis.tri.astype(np.int64), constants, texels, levels, np.zeros(3), out)
    # pixel row 0 is the top: v = 1 - ...; texel row 0 is v = 0 (the bottom)
    np.testing.assert_allclose(out, tex.levels[0][::-1, :, :3], atol=0)
