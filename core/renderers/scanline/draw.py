"""The scan-line renderer: Watkins' visible-surface algorithm (FvDFH 15.6) in the z-buffer's
pipeline.

``draw(scene, view, settings, frame, context, timer)`` runs the z-buffer renderer's stages
(cull, shade inputs, N, clip, project, shade) with one stage replaced: instead of testing each
triangle's pixels against a depth buffer, :mod:`core.visibility.scanline.watkins` walks the
scan lines with its edge table, polygon table and active edge table, and decides the visible
polygon of each span by depth at the span's ends. What it leaves (the visible triangle and
its weights at every pixel) is shaded by the same shading step, flat, Gouraud or Phong, so
the picture is the z-buffer's wherever the two agree on the visible triangle: everywhere but
where two triangles tie in depth to the last bit.

The frame's ``stats["scan line"]`` holds the tables' counters (polygons, edges, the largest
AET, spans, those of one polygon that needed no depth, depth evaluations, penetration cuts);
the plan's stage shows them. :func:`inspect_pixel` is the z-buffer's pixel record with the
AET of the pixel's scan line and the spans it produced.
"""

from __future__ import annotations

from core.camera.film import sample_viewport
from core.renderers.scanline.plan import STAGE
from core.renderers.zbuffer import draw as zbuffer
from core.visibility.scanline import watkins


class _Watkins:
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
    visible = _Watkins()
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


def scan_line(scene, view, settings, y: int, context=None) -> dict:
    """The AET of image row ``y`` (row 0 at the top) and the spans it produced, for the
    frame ``settings`` draws (one sample per pixel): the scene triangle each entry is of."""
    from core.context import DEFAULT_CONTEXT
    from core.renderers.zbuffer.inspect import Stages, capture
    context = context or DEFAULT_CONTEXT
    cap = capture(scene, view, settings, context, Stages(draw, zbuffer.draw_lines,
                                                         sample_viewport))
    width, height = cap.width, cap.height
    row = cap.side * int(y) + cap.side // 2           # the sample row through the pixel
    arrays = cap.arrays
    out = {"image row": int(row), "device row": height - 1 - row, "aet": [], "spans": []}
    if "clipped_triangles" not in arrays:
        out["message"] = "no triangles are drawn"
        return out
    visible = _Watkins(record_row=height - 1 - row)
    visible(arrays["device_points"], arrays["inv_w"], arrays["clipped_triangles"], width,
            height)
    rec = visible.records[-1]
    source = arrays["source"]
    # each edge's crossing x, and the pixel it bounds: a left edge's first pixel in, a right
    # edge's last (the AET is sorted by the pixel after a right edge, where its polygon is out)
    out["aet"] = [{"triangle": int(source[int(p)]), "edge": "left" if side > 0 else "right",
                   "x": round(float(x), 4), "pixel": int(k) if side > 0 else int(k) - 1}
                  for p, side, x, k in rec.aet]
    out["spans"] = [{"pixels": [int(a), int(b)],
                     "visible triangle": int(source[t]) if t >= 0 else None,
                     "polygons in": int(n), "decided": watkins.DECIDED[int(how)]}
                    for a, b, t, n, how in rec.spans]
    out["counters"] = rec.stats
    return out


def inspect_pixel(scene, view, settings, x, y, context=None) -> dict:
    """The z-buffer's record of pixel (x, y), drawn by this renderer, with its scan line's
    AET and spans (``record["scan line"]``)."""
    from core.renderers.zbuffer.inspect import Stages, pixel_record as record
    settings = settings.replace(rasterizer="edge")     # its weights: perspective-correct
    out = record(scene, view, settings, x, y, context,
                 Stages(draw, zbuffer.draw_lines, sample_viewport))
    out["renderer"] = "scanline"
    out["scan line"] = scan_line(scene, view, settings, y, context)
    return out


def buffers(scene, view, settings, context=None, names=()) -> dict:
    """The buffer views of this frame, as the z-buffer's (depth, normal, triangle id, ...)."""
    from core.renderers.zbuffer.inspect import Stages, buffer_views as views
    return views(scene, view, settings, context,
                 Stages(draw, zbuffer.draw_lines, sample_viewport), names)
