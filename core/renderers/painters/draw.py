"""The painter's renderers' drawing: the BSP tree and the depth sort (the notes' approaches 4
and 3).

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

``paint_first`` K (the painters' options, :mod:`core.renderers.painters.options`) paints only
the first K triangles of the order (the draw-order slider). :mod:`core.renderers.painters.inspect`
counts the writes per pixel and lists them.
"""

from __future__ import annotations

from core.camera.film import fill, sample_viewport
from core.pipeline import project
from core.renderers.zbuffer.draw import draw_lines
from core.stages import (CLIP_LINES, CLIP_TRIANGLES, CULL, DECIDED_BY_THE_SHADER, DEPTH_BUFFER,
                         NORMALIZE, PROJECT, SCAN_CONVERSION, Facts, ran)
from core.visibility.paint import bsp_painting, depth_sorted_painting, paint, resolve, true_depth


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
    vp = sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    timer.lap("normalize")
    ran(frame.stats, NORMALIZE, PROJECT)        # N and the viewport: every frame
    facts = Facts.of(scene, settings)           # the z-buffer's stages decide, as there
    if CLIP_TRIANGLES.runs(facts):
        p = painting(scene, view, settings, context, timer, n, z_min, vp)
        frame.stats.update(p.stats)
        _ran_painting(frame.stats, p)
        _update_plan(frame, p.stats)
        vis = paint(p, width, height, context)
        frame.stats["painted"] = int(len(p.triangles))
        timer.lap("paint", depth=vis.depth, tri=vis.tri, b1=vis.b1, b2=vis.b2)
        resolve(p, vis, scene, settings, frame)
        frame.depth = true_depth(vis, p, context)
        timer.lap("shade: pixel step")
    else:
        fill(frame.color, scene.background)
    if CLIP_LINES.runs(facts):
        line_meshes = [m for m in scene.meshes
                       if settings.shading == "wireframe" or not len(m.triangles)]
        draw_lines(frame.color, line_meshes, settings.projection, n, z_min, vp,
                   scene.line_color, context, timer, frame.stats, settings.clipper,
                   settings.antialias_lines)


def _ran_painting(stats: dict, p) -> None:
    """Name the stages the painting ran (its order's stage by its name in the plan)."""
    ordering = [name for name in ("BSP tree", "depth sort") if name in p.stats]
    ran(stats, *([CULL] if "culled" in p.stats else []),
        *(name for name in p.inputs.computed if name in DECIDED_BY_THE_SHADER),
        *ordering, CLIP_TRIANGLES, DEPTH_BUFFER, SCAN_CONVERSION)


def _update_plan(frame, stats) -> None:
    """Put this frame's numbers into the plan's painter stage."""
    from core.plan import Stage
    for i, stage in enumerate(frame.plan):
        if stage.name in ("BSP tree", "depth sort") and stage.runs:
            numbers = ", ".join(f"{k} {v}" for k, v in stats.get(stage.name, {}).items())
            frame.plan[i] = Stage(stage.name, True, f"{stage.reason} ({numbers})")
