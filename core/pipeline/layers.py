"""Stacked full-frame layers of triangles in device coordinates, for the rasterizer.

Layer k is a grid of triangles over the whole frame at its own depth: the most overdraw a
frame can have, and the case the hierarchical z rejects best when drawn nearest first. The
tile tests, the depth bench and the warm-up (the rasterizer's batched path) draw them.
"""

from __future__ import annotations

import numpy as np


def depth_layers(n_layers: int, per_layer: int, width: int, height: int,
                 front_to_back: bool = True):
    """(xy_z, inv_w, triangles) of ``n_layers`` full-frame grids at distinct depths."""
    nx = max(1, int(round(np.sqrt(per_layer / 2 * width / height))))
    ny = max(1, per_layer // (2 * nx))
    gx, gy = np.meshgrid(np.linspace(0, width, nx + 1), np.linspace(0, height, ny + 1))
    points = np.column_stack([gx.ravel(), gy.ravel()])
    idx = np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    a, b = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel()
    c, d = idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    grid = np.concatenate([np.column_stack([a, b, d]), np.column_stack([a, d, c])])
    # layer k at depth -0.1 (nearest) .. -0.9; drawn nearest first or nearest last
    depths = -0.1 - 0.8 * np.arange(n_layers) / max(1, n_layers - 1)
    if not front_to_back:
        depths = depths[::-1]
    xy_z = np.concatenate([np.column_stack([points, np.full(len(points), z)]) for z in depths])
    triangles = np.concatenate([grid + k * len(points) for k in range(n_layers)])
    return xy_z, np.ones(len(xy_z)), triangles.astype(np.int64)
