"""The painter's renderers: the BSP tree and the depth sort (the notes' approaches 4 and 3).

``draw_bsp`` and ``draw_depth_sort`` have the z-buffer's signature
(``draw(scene, view, settings, frame, context, timer)``) and share its stages: cull, shade
inputs, N, clip, project, the same rasterizer and the same shaders. What differs is how
visibility is decided: they find an order in which to paint the triangles, back to front, and
each later triangle simply covers what was painted before (no depth test):

- ``bsp``: the tree is built once per scene in world space (:mod:`core.visibility.bsp`), kept
  in the render context for every later view, and walked from the eye each frame;
- ``depth-sort``: Newell's sort (:mod:`core.visibility.depth_sort`) each frame, in device
  space after clipping.

Painting (:mod:`core.visibility.paint`) goes through ``core.pipeline.raster.rasterize`` unchanged:
every triangle is given a constant depth equal to its rank in the painting order, so "the nearer
wins" is exactly "the later painted wins", the painter's overwrite. The true depth of each pixel is
computed afterwards from the barycentrics (``frame.depth``, for depth cueing and transparency).

``settings.paint_first`` K paints only the first K triangles of the order (the draw-order
slider). :func:`overdraw` counts the writes per pixel; :func:`inspect_pixel` lists them.
"""

from __future__ import annotations

import numpy as np

from core.camera.film import fill
from core.pipeline import project
from core.pipeline.raster import count_fragments
from core.renderers.zbuffer import _sample_viewport, draw_lines
from core.visibility.paint import (Painting, SimpleFrame, bsp_painting, depth_sorted_painting,
                                   paint, paint_ranks, painting, resolve, true_depth)


# ------------------------------------------------------------------------------ renderers

def draw_bsp(scene, view, settings, frame, context, timer) -> None:
    """The BSP renderer: the scene's tree, walked from the eye, painted back to front."""
    _draw(scene, view, settings, frame, context, timer, bsp_painting)


def draw_depth_sort(scene, view, settings, frame, context, timer) -> None:
    """Newell, Newell and Sancha's depth sort, painted back to front."""
    _draw(scene, view, settings, frame, context, timer, depth_sorted_painting)


def _draw(scene, view, settings, frame, context, timer, painting) -> None:
    height, width = frame.color.shape[:2]
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = _sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    timer.lap("normalize")
    solid = settings.shading != "wireframe" and scene.triangle_count > 0
    if solid:
        p = painting(scene, view, settings, context, timer, n, z_min, vp)
        frame.stats.update(p.stats)
        _update_plan(frame, p.stats)
        vis = paint(p, width, height, context)
        frame.stats["painted"] = int(len(p.triangles))
        timer.lap("paint", depth=vis.depth, tri=vis.tri, b1=vis.b1, b2=vis.b2)
        resolve(p, vis, scene, settings, frame)
        frame.depth = true_depth(vis, p, context)
        timer.lap("shade: pixel step")
    else:
        fill(frame.color, scene.background)
    line_meshes = [m for m in scene.meshes
                   if settings.shading == "wireframe" or not len(m.triangles)]
    if line_meshes:
        draw_lines(frame.color, line_meshes, settings.projection, n, z_min, vp,
                   scene.line_color, context, timer, frame.stats)


def _update_plan(frame, stats) -> None:
    """Put this frame's numbers into the plan's painter stage."""
    from core.plan import Stage
    for i, stage in enumerate(frame.plan):
        if stage.name in ("BSP tree", "depth sort") and stage.runs:
            numbers = ", ".join(f"{k} {v}" for k, v in stats.get(stage.name, {}).items())
            frame.plan[i] = Stage(stage.name, True, f"{stage.reason} ({numbers})")


# ---------------------------------------------------------------- looking at the painting

def overdraw(scene, view, settings, context=None) -> np.ndarray:
    """``(H, W)`` int32: how many times each pixel is written. For bsp and depth-sort every
    painted fragment covering the pixel centre is a write; for the z-buffer (any other
    renderer name) it is the number of fragments scan-converted there, each of which is
    depth-tested (an upper bound on its writes: FvDFH's cost of the z-buffer)."""
    from core.renderers import triangles as stages
    width, height = settings.size
    if settings.renderer in ("bsp", "depth-sort"):
        p = painting(scene, view, settings, context)
        if p is None:
            return np.zeros((height, width), np.int32)
        xy_z, inv_w, triangles = paint_ranks(p)
        return count_fragments(xy_z, inv_w, triangles, width, height)
    kept = {}

    def grab(stage, arrays):
        if stage == "project":
            kept["device"] = arrays["device_points"].copy()
            kept["inv_w"] = arrays["inv_w"].copy()
        if stage == "clip triangles":
            kept["triangles"] = arrays["clipped_triangles"].copy()

    from core.render import render
    render(scene, view, settings.replace(renderer="zbuffer", samples=1), context, inspect=grab)
    if "triangles" not in kept:
        return np.zeros((height, width), np.int32)
    return count_fragments(kept["device"], kept["inv_w"], kept["triangles"], width,
                                  height)


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The pixel's history (RenderDoc's pixel history): every triangle painted over pixel
    ``(x, y)`` (x right, y down, row 0 at the top), in painting order, with its colour; the
    last one is what the frame shows."""
    from core.context import DEFAULT_CONTEXT
    from core.render import render
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
    from core.renderers import triangles as stages
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
        color = np.empty((height, width, 3), np.uint8)
        resolve(single, vis, scene, settings, SimpleFrame(color))
        record["writes"].append({"rank": int(rank), "triangle": int(p.source[rank]),
                                 "color": [int(c) for c in color[y, x]],
                                 "depth": float(true_depth(vis, single)[y, x])})
    return record
