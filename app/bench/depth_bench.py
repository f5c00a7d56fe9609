"""The bench's depth-complexity case (what overdraw costs): stacks of full-screen layers.

Each layer is a grid of about ``per_layer`` distinct triangles covering the whole frame, at
its own depth; ``n_layers`` of them are stacked front to back (the nearest layer drawn first)
or back to front (the nearest last). A z-buffer that pays every covered pixel of every
triangle costs the layers times one; hierarchical z should cost close to one layer.
The geometry is in device coordinates, for :func:`core.pipeline.raster.rasterize` directly.
"""

from __future__ import annotations

import time

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


def time_layers(n_layers: int, per_layer: int, width: int, height: int, front_to_back: bool,
                frames: int, warmup: int, hierarchical_z: bool = True) -> dict:
    """Median rasterize() time of a stack (ms), and the pixels drawn."""
    from core.pipeline import raster
    xy_z, inv_w, triangles = depth_layers(n_layers, per_layer, width, height, front_to_back)
    saved = raster.HIERARCHICAL_Z
    raster.HIERARCHICAL_Z = hierarchical_z
    try:
        buffer, times = None, []
        for k in range(warmup + frames):
            t0 = time.perf_counter()
            buffer = raster.rasterize(xy_z, inv_w, triangles, width, height, out=buffer)
            if k >= warmup:
                times.append(time.perf_counter() - t0)
    finally:
        raster.HIERARCHICAL_Z = saved
    return {"median": float(np.median(times) * 1e3), "min": float(np.min(times) * 1e3),
            "triangles": int(len(triangles)), "covered": int((buffer.tri >= 0).sum())}
