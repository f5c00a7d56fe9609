"""The scan-line renderer's pixel record: the z-buffer's, with the pixel's scan line.

:func:`inspect_pixel` is the z-buffer's record (:mod:`core.renderers.zbuffer.inspect`) of the
frame this renderer draws, with the active edge table of the pixel's scan line and the spans
it produced (``record["scan line"]``, :func:`scan_line`); :func:`buffers` are the z-buffer's
buffer views of that frame.
"""

from __future__ import annotations

from core.camera.film import sample_viewport
from core.context import DEFAULT_CONTEXT
from core.renderers.scanline.draw import Watkins, draw
from core.renderers.zbuffer.draw import draw_lines
from core.renderers.zbuffer.inspect import Stages, buffer_views, capture, pixel_record
from core.visibility import watkins

SCANLINE = Stages(draw, draw_lines, sample_viewport)


def scan_line(scene, view, settings, y: int, context=None) -> dict:
    """The AET of image row ``y`` (row 0 at the top) and the spans it produced, for the
    frame ``settings`` draws (one sample per pixel): the scene triangle each entry is of."""
    context = context or DEFAULT_CONTEXT
    cap = capture(scene, view, settings, context, SCANLINE)
    width, height = cap.width, cap.height
    row = cap.side * int(y) + cap.side // 2           # the sample row through the pixel
    arrays = cap.arrays
    out = {"image row": int(row), "device row": height - 1 - row, "aet": [], "spans": []}
    if "clipped_triangles" not in arrays:
        out["message"] = "no triangles are drawn"
        return out
    visible = Watkins(record_row=height - 1 - row)
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
    settings = settings.replace(rasterizer="edge")     # its weights: perspective-correct
    out = pixel_record(scene, view, settings, x, y, context, SCANLINE)
    out["renderer"] = "scanline"
    out["scan line"] = scan_line(scene, view, settings, y, context)
    return out


def buffers(scene, view, settings, context=None, names=()) -> dict:
    """The buffer views of this frame, as the z-buffer's (depth, normal, triangle id, ...)."""
    return buffer_views(scene, view, settings, context, SCANLINE, names)
