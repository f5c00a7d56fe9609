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

from core.pipeline.layers import depth_layers


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
