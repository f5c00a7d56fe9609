"""Barycentric planes (core.pipeline.derivatives): weights and screen derivatives by hand, and
against what the rasterizer stores."""

from __future__ import annotations

import numpy as np

from core.pipeline.derivatives import barycentric_planes, weights_and_derivatives
from core.pipeline.raster import rasterize


def test_a_parallel_right_triangle_by_hand():
    # (0, 0), (10, 0), (0, 10), W = 1: b1 = x / 10, b2 = y / 10 everywhere.
    device = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]])
    planes = barycentric_planes(device, np.ones(3), np.array([[0, 1, 2]]))
    b1, b2, d1x, d1y, d2x, d2y = weights_and_derivatives(planes, 0, 2.5, 4.0)
    assert np.allclose([b1, b2, d1x, d1y, d2x, d2y], [0.25, 0.4, 0.1, 0.0, 0.0, 0.1])


def test_perspective_weights_by_hand():
    # The same triangle with vertex 1 twice as far (1/W = 0.5): at the screen midpoint of edge
    # 0-1, λ = (1/2, 1/2, 0), and b1 = (1/2 · 1/2) / (1/2 + 1/2 · 1/2) = 1/3.
    device = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, 10.0, 0.0]])
    planes = barycentric_planes(device, np.array([1.0, 0.5, 1.0]), np.array([[0, 1, 2]]))
    b1, b2, d1x, *_ = weights_and_derivatives(planes, 0, 5.0, 0.0)
    assert np.isclose(b1, 1 / 3) and np.isclose(b2, 0.0)
    # d b1/dx = d/dx[(x/20) / (1 − x/20)] at x = 5: (1/20) / (3/4)² = 4/45
    assert np.isclose(d1x, 4 / 45)


def test_planes_agree_with_the_rasterizer_and_their_derivatives_with_differences():
    rng = np.random.default_rng(11)
    width = height = 64
    for _ in range(20):
        device = np.column_stack([rng.uniform(-10, 74, (3, 2)), rng.uniform(-1, 0, 3)])
        inv_w = rng.uniform(0.2, 3.0, 3)
        triangles = np.array([[0, 1, 2]])
        vis = rasterize(device, inv_w, triangles, width, height)
        planes = barycentric_planes(device, inv_w, triangles)
        rows, cols = np.nonzero(vis.tri == 0)
        for r, c in zip(rows, cols):
            x, y = c + 0.5, height - 1 - r + 0.5
            b1, b2, d1x, d1y, d2x, d2y = weights_and_derivatives(planes, 0, x, y)
            # The rasterizer snaps vertices to 1/256 pixel: the weights move by about that
            # much times their gradient.
            snap = 4 / 256 * (abs(d1x) + abs(d1y) + abs(d2x) + abs(d2y)) + 1e-12
            assert abs(b1 - vis.b1[r, c]) < snap and abs(b2 - vis.b2[r, c]) < snap
            # The derivatives are those of the weights: a small central difference.
            h = 1e-5
            dx = [(p - m) / (2 * h) for p, m in zip(weights_and_derivatives(planes, 0, x + h, y)[:2],
                                                   weights_and_derivatives(planes, 0, x - h, y)[:2])]
            dy = [(p - m) / (2 * h) for p, m in zip(weights_and_derivatives(planes, 0, x, y + h)[:2],
                                                   weights_and_derivatives(planes, 0, x, y - h)[:2])]
            assert np.allclose([d1x, d2x, d1y, d2y], dx + dy, rtol=1e-5, atol=1e-9)
