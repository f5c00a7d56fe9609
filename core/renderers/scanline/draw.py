"""The scan-line renderer: Watkins' visible-surface algorithm (FvDFH 15.6) in the z-buffer's
pipeline.

``draw(scene, view, settings, frame, context, timer)`` runs the z-buffer renderer's stages
(cull, shade inputs, N, clip, project, shade) with one stage replaced: instead of testing each
triangle's pixels against a depth buffer, :mod:`core.visibility.watkins` walks the
scan lines with its edge table, polygon table and active edge table, and decides the visible
polygon of each span by depth at the span's ends. What it leaves (the visible triangle and
its weights at every pixel) is shaded by the same shading step, flat, Gouraud or Phong, so
the picture is the z-buffer's wherever the two agree on the visible triangle: everywhere but
where two triangles tie in depth to the last bit.

The frame's ``stats["scan line"]`` holds the tables' counters (polygons, edges, the largest
AET, spans, those of one polygon that needed no depth, depth evaluations, penetration cuts);
the plan's stage shows them (:mod:`core.renderers.scanline.plan` puts the stage in the plan;
:mod:`core.renderers.scanline.inspect` records a pixel's scan line).
"""

from __future__ import annotations

from core.renderers.scanline.plan import STAGE
from core.renderers.zbuffer import draw as zbuffer
from core.visibility import watkins


class Watkins:
    """Watkins' algorithm with the rasterizer's signature, keeping each frame's record."""

    name = "watkins"
    stage = STAGE

    def __init__(self, record_row: int = -1):
        self.record_row = record_row
        self.records: list = []

    def __call__(self, xy_z, inv_w, triangles, width, height, out=None):
        return watkins.rasterize(xy_z, inv_w, triangles, width, height, out,
                                 record_row=self.record_row, record=self.records)


def draw(scene, view, settings, frame, context, timer) -> None:
    """The z-buffer's pipeline with Watkins' algorithm deciding visibility."""
    visible = Watkins()
    zbuffer.draw(scene, view, settings, frame, context, timer, rasterize=visible)
    if visible.records:
        frame.stats["scan line"] = visible.records[-1].stats
        _update_plan(frame, visible.records[-1].stats)


def _update_plan(frame, stats) -> None:
    """Put this frame's counters into the plan's scan-line stage."""
    from core.plan import Stage
    plan = getattr(frame, "plan", None) or []           # (an inspector's frame has none)
    for i, stage in enumerate(plan):
        if stage.name == STAGE and stage.runs:
            numbers = ", ".join(f"{k} {v}" for k, v in stats.items())
            plan[i] = Stage(stage.name, True, f"{stage.reason} ({numbers})")
