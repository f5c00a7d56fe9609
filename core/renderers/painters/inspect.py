"""Looking at the painter's renderers' work: writes per pixel, and one pixel's history.

- :func:`overdraw`: ``(H, W)`` int32, how many times each pixel is written (the buffer view,
  through :func:`buffers`);
- :func:`inspect_pixel`: RenderDoc's pixel history for ``bsp`` and ``depth-sort``: every
  triangle painted over the pixel, in painting order, with its colour and depth.

The pixel's history shows the frame as the front door draws it (effects laid over): the
front door hands itself over as ``render`` (:func:`core.inspect.inspect_pixel`), which this
package, below it, does not import.
"""

from __future__ import annotations

import numpy as np

from core.arrays import rgb_picture
from core.pipeline.raster import count_fragments
from core.visibility.paint import (Painting, SimpleFrame, paint, paint_ranks, painting, resolve,
                                   true_depth)


def overdraw(scene, view, settings, context=None) -> np.ndarray:
    """``(H, W)`` int32: how many times each pixel is written: every painted fragment
    covering the pixel centre is a write (``settings.renderer``: bsp or depth-sort)."""
    width, height = settings.size
    p = painting(scene, view, settings, context)
    if p is None:
        return np.zeros((height, width), np.int32)
    xy_z, inv_w, triangles = paint_ranks(p)
    return count_fragments(xy_z, inv_w, triangles, width, height)


def buffers(scene, view, settings, context=None, names=()) -> dict:
    """The painters' buffer view: ``overdraw`` (the others are the z-buffer's)."""
    return {"overdraw": overdraw(scene, view, settings, context)} if "overdraw" in names else {}


def inspect_pixel(scene, view, settings, x: int, y: int, context=None, *, render) -> dict:
    """The pixel's history (RenderDoc's pixel history): every triangle painted over pixel
    ``(x, y)`` (x right, y down, row 0 at the top), in painting order, with its colour; the
    last one is what the frame shows (drawn by ``render``: the front door, handed over by
    :func:`core.inspect.inspect_pixel`)."""
    from core.context import DEFAULT_CONTEXT
    context = context or DEFAULT_CONTEXT
    width, height = settings.size
    frame = render(scene, view, settings.replace(samples=1), context)
    record = {"renderer": settings.renderer, "pixel": [int(x), int(y)],
              "color": [int(c) for c in frame.color[y, x]], "writes": []}
    p = painting(scene, view, settings.replace(samples=1), context)
    if p is None or frame.message:
        record["message"] = frame.message or "no triangles are painted"
        return record
    record["painted triangles"] = int(len(p.triangles))
    record.update({k: v for k, v in frame.stats.items() if k in ("BSP tree", "depth sort")})
    xy_z, inv_w, triangles = paint_ranks(p)
    from core.shading import stages
    covered = count_fragments(xy_z, inv_w, triangles, width, height)
    if covered[y, x] == 0:
        return record
    # which painted triangles cover the pixel: rasterize only the candidates whose box holds it
    px, py = x + 0.5, height - 1 - y + 0.5
    corners = p.device[p.triangles]
    near = np.flatnonzero((corners[:, :, 0].min(1) <= px + 1) & (corners[:, :, 0].max(1) >= px - 1)
                          & (corners[:, :, 1].min(1) <= py + 1)
                          & (corners[:, :, 1].max(1) >= py - 1))
    for rank in near:
        one = stages.rasterize(xy_z[3 * rank:3 * rank + 3], inv_w[3 * rank:3 * rank + 3],
                               np.array([[0, 1, 2]], np.int64), width, height)
        if one.tri[y, x] < 0:
            continue
        single = Painting(p.device, p.inv_w, p.triangles[rank:rank + 1], p.attrs,
                          p.source[rank:rank + 1], p.inputs, {})
        vis = paint(single, width, height, context)
        color = rgb_picture(height, width)
        resolve(single, vis, scene, settings, SimpleFrame(color))
        record["writes"].append({"rank": int(rank), "triangle": int(p.source[rank]),
                                 "color": [int(c) for c in color[y, x]],
                                 "depth": float(true_depth(vis, single)[y, x])})
    return record
