"""Watkins' scan-line visible-surface algorithm (FvDFH 15.6), the course's approach 5.

Object precision along each scan line: the pixels of a scan line are cut into *spans* where
the set of polygons under them changes, and the visible polygon of a span is decided once, by
depth evaluated at the span's ends only; no depth buffer is ever read. The tables are the
book's:

* **edge table (ET)**: every non-horizontal polygon edge, bucketed by the scan line where it
  starts (its first pixel centre above the lower end), with its last scan line, its crossing
  with the current scan line and the polygon it belongs to;
* **polygon table (PT)**: per polygon its plane (here the depth as an affine function of the
  device x, y, which is what the perspective-to-parallel divide makes of it), its shading
  attributes (the visibility buffer's perspective-correct weights) and its **in/out flag**;
* **active edge table (AET)**: the edges that cross the current scan line, **sorted in x**.
  Moving up one scan line, edges whose last line was the previous one leave, the others step
  their crossing by the slope, those starting here come in from the ET bucket, and the AET is
  re-sorted by insertion sort: between two scan lines the order barely changes (*edge
  coherence*), so this costs about one comparison per edge.

Walking the AET left to right, each edge flips its polygon's flag: a left edge sets it in, a
right edge out. Between two consecutive crossings the in-polygons are constant: one polygon
needs no depth at all (*span coherence*); several are compared by depth at the span's two end
pixels. Depth is affine along the scan line, so a polygon nearest at both ends is nearest
across the span. When the ends disagree, the two polygons **penetrate** inside the span
(neither can be nearest at one end and farther at the other unless their depths cross): the
span is cut where their depth lines cross and each piece is decided again, the book's "depth
compared at every span change" with the intersection as a new span boundary.

Coverage is the z-buffer's to the pixel: the same fixed-point vertices (8 sub-pixel bits), the
same edge functions with the top-left fill rule, and an edge's crossing kept as an exact
integer quotient and remainder stepped each scan line (:mod:`core.pipeline.raster_scanline`'s
ET entry), so a span's first and last pixels are exactly the centres the edge functions accept.
The depth at a span end is the z-buffer's own expression on the same exact integers, and a tie
goes to the later polygon as the notes' ``z >= zbuffer`` gives it. The pixels of a decided
span are written with the winner's depth (for the effects drawn after: transparency, depth
cueing) and its perspective-correct weights, the z-buffer's expressions, so that the same
shading step colours them.

:func:`rasterize` takes and returns what :func:`core.pipeline.raster.rasterize` does;
``record_row`` keeps the AET and the spans of one scan line for the inspector.
"""

from __future__ import annotations

import numpy as np

from core.jit import njit
from core.pipeline.raster import (INVALID, PIXEL_CENTRE, SUBPIXEL_ONE, VisibilityBuffer,
                                  checked_inputs, snap_vertices, triangle_edges)
from core.pipeline.raster_scanline import (EDGE_A, EDGE_FIELDS, EDGE_FIRST, EDGE_LAST,
                                           edge_bound, edge_entry, step_edge)

# An ET/AET entry: raster_scanline's eight fields, then the polygon the edge belongs to.
EDGE_POLYGON = EDGE_FIELDS
# The polygon table: the three edge functions unbiased (A, B, C: the screen barycentric
# numerators), and in floats the depths z0, z1 - z0, z2 - z0 and 1 / area2. The in/out flag
# lives beside it (``flag``), and 1/W at the corners is read from the projected vertices.
PT_INTS, PT_FLOATS = 9, 4
# frame counters: what the tables held and how many spans needed depth
STATS = ("polygons", "edges", "largest AET", "spans", "one-polygon spans",
         "depth evaluations", "penetration splits")
# how a recorded span was decided
DECIDED = ("one polygon, no depth", "depth at both ends", "cut where two polygons cross")


@njit(cache=True)
def _build_tables(xy_z, fixed, triangles, width, height, pt_i, pt_f, et, stats):
    """Fill the PT and the ET (unsorted); returns the count of bad vertex indices."""
    n_vertices = fixed.shape[0]
    n_edges = 0
    bad = 0
    for t in range(triangles.shape[0]):
        skip = False
        for k in range(3):
            v = triangles[t, k]
            if v < 0 or v >= n_vertices:
                bad += 1
                skip = True
            elif fixed[v, 0] == INVALID:
                skip = True
        if skip:
            continue
        v0, v1, v2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        x = (np.int64(fixed[v0, 0]), np.int64(fixed[v1, 0]), np.int64(fixed[v2, 0]))
        y = (np.int64(fixed[v0, 1]), np.int64(fixed[v1, 1]), np.int64(fixed[v2, 1]))
        area2, e0, e1, e2 = triangle_edges(x[0], y[0], x[1], y[1], x[2], y[2])
        if area2 == 0:
            continue
        edges = (e0, e1, e2)
        for k in range(3):
            a, b, c, bias = edges[k]
            pt_i[t, 3 * k], pt_i[t, 3 * k + 1], pt_i[t, 3 * k + 2] = a, b, c + bias
            # edge k joins the corners other than k; horizontal edges bound no span
            if a != 0 and edge_entry(et, n_edges, a, b, c, y[(k + 1) % 3], y[(k + 2) % 3],
                                     height):
                et[n_edges, EDGE_POLYGON] = t
                n_edges += 1
        z0 = xy_z[v0, 2]
        pt_f[t, 0], pt_f[t, 1], pt_f[t, 2] = z0, xy_z[v1, 2] - z0, xy_z[v2, 2] - z0
        pt_f[t, 3] = 1.0 / area2
        stats[0] += 1
    stats[1] = n_edges
    return bad, n_edges


@njit(cache=True)
def _bucket(et, n_edges, height, order, row_start):
    """The ET bucketed by first scan line (a counting sort): bucket j is
    ``order[row_start[j]:row_start[j + 1]]``."""
    row_start[:] = 0
    for e in range(n_edges):
        row_start[et[e, EDGE_FIRST] + 1] += 1
    for j in range(height):
        row_start[j + 1] += row_start[j]
    fill = row_start[:height].copy()
    for e in range(n_edges):
        j = et[e, EDGE_FIRST]
        order[fill[j]] = e
        fill[j] += 1


@njit(cache=True)
def _depth_at(pt_i, pt_f, t, px, py):
    """Polygon t's depth at fixed-point (px, py): the z-buffer's expression, bit for bit."""
    l1 = float(pt_i[t, 3] * px + pt_i[t, 4] * py + pt_i[t, 5])
    l2 = float(pt_i[t, 6] * px + pt_i[t, 7] * py + pt_i[t, 8])
    return pt_f[t, 0] + (l1 * pt_f[t, 1] + l2 * pt_f[t, 2]) * pt_f[t, 3]


@njit(cache=True)
def _nearest(inside, n_in, pt_i, pt_f, px, py, stats):
    """The in-polygon nearest at (px, py) (a tie to the later one) and its depth."""
    best, best_z = -1, -np.inf
    for m in range(n_in):
        t = inside[m]
        z = _depth_at(pt_i, pt_f, t, px, py)
        if z > best_z or (z == best_z and t > best):
            best, best_z = t, z
    stats[5] += n_in
    return best, best_z


@njit(cache=True)
def _fill(t, i0, i1, j, pt_i, pt_f, inv_w, triangles, depth, tri, b1, b2):
    """Write the span i0..i1 of device row j as polygon t's: depth and perspective weights."""
    height = depth.shape[0]
    row = height - 1 - j
    px = i0 * SUBPIXEL_ONE + PIXEL_CENTRE
    py = j * SUBPIXEL_ONE + PIXEL_CENTRE
    l0 = pt_i[t, 0] * px + pt_i[t, 1] * py + pt_i[t, 2]
    l1 = pt_i[t, 3] * px + pt_i[t, 4] * py + pt_i[t, 5]
    l2 = pt_i[t, 6] * px + pt_i[t, 7] * py + pt_i[t, 8]
    w0, w1, w2 = inv_w[triangles[t, 0]], inv_w[triangles[t, 1]], inv_w[triangles[t, 2]]
    z0, dz1, dz2, inv_area = pt_f[t, 0], pt_f[t, 1], pt_f[t, 2], pt_f[t, 3]
    for i in range(i0, i1 + 1):
        f1 = float(l1)
        f2 = float(l2)
        depth[row, i] = z0 + (f1 * dz1 + f2 * dz2) * inv_area
        tri[row, i] = t
        p0 = float(l0) * w0          # perspective correction: weights ~ lambda_k / W_k
        p1 = f1 * w1
        p2 = f2 * w2
        s = 1.0 / (p0 + p1 + p2)
        b1[row, i] = p1 * s
        b2[row, i] = p2 * s
        l0 += SUBPIXEL_ONE * pt_i[t, 0]      # one pixel to the right
        l1 += SUBPIXEL_ONE * pt_i[t, 3]
        l2 += SUBPIXEL_ONE * pt_i[t, 6]


@njit(cache=True)
def _record_span(rec_spans, n_rec, i0, i1, t, n_in, how):
    if n_rec[1] < rec_spans.shape[0]:
        k = n_rec[1]
        rec_spans[k, 0], rec_spans[k, 1], rec_spans[k, 2] = i0, i1, t
        rec_spans[k, 3], rec_spans[k, 4] = n_in, how
        n_rec[1] += 1


@njit(cache=True)
def _span(i0, i1, j, inside, n_in, pt_i, pt_f, inv_w, triangles, depth, tri, b1, b2, stack,
          stats, recording, rec_spans, n_rec):
    """Decide and draw the span i0..i1 of device row j under the ``n_in`` in-polygons."""
    stats[3] += 1
    if n_in == 1:                   # span coherence: one polygon, nothing to compare
        stats[4] += 1
        _fill(inside[0], i0, i1, j, pt_i, pt_f, inv_w, triangles, depth, tri, b1, b2)
        if recording:
            _record_span(rec_spans, n_rec, i0, i1, inside[0], 1, 0)
        return
    py = j * SUBPIXEL_ONE + PIXEL_CENTRE
    top = 0
    stack[0, 0], stack[0, 1], stack[0, 2] = i0, i1, 1
    while top >= 0:
        a, b, how = stack[top, 0], stack[top, 1], stack[top, 2]
        top -= 1
        pa = a * SUBPIXEL_ONE + PIXEL_CENTRE
        pb = b * SUBPIXEL_ONE + PIXEL_CENTRE
        left, z_left = _nearest(inside, n_in, pt_i, pt_f, pa, py, stats)
        right, z_right = _nearest(inside, n_in, pt_i, pt_f, pb, py, stats)
        if left == right:           # nearest at both ends: nearest across (depth is affine)
            _fill(left, a, b, j, pt_i, pt_f, inv_w, triangles, depth, tri, b1, b2)
            if recording:
                _record_span(rec_spans, n_rec, a, b, left, n_in, how)
            continue
        # the two penetrate inside the span: cut it where their depths cross
        stats[6] += 1
        d0 = z_left - _depth_at(pt_i, pt_f, right, pa, py)          # >= 0
        d1 = _depth_at(pt_i, pt_f, left, pb, py) - z_right          # <= 0
        cut = a
        if d0 - d1 > 0.0:
            cut = a + int(np.floor((b - a) * (d0 / (d0 - d1))))
        cut = min(max(cut, a), b - 1)
        stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2] = cut + 1, b, 2
        stack[top + 2, 0], stack[top + 2, 1], stack[top + 2, 2] = a, cut, 2
        top += 2


@njit(cache=True)
def _sort_aet(aet, n_aet, key):
    """Insertion sort of the AET by key (its x): nearly sorted from the last scan line."""
    for m in range(1, n_aet):
        e = aet[m]
        p = m
        while p > 0 and key[aet[p - 1]] > key[e]:
            aet[p] = aet[p - 1]
            p -= 1
        aet[p] = e


@njit(cache=True)
def _crossings(et, aet, n_aet, width, key, low, high):
    """Each active edge's key on this scan line: a left edge's first pixel, a right edge's
    last pixel + 1, clamped to the frame; ``low``/``high``: each polygon's pixels here."""
    for m in range(n_aet):
        e = aet[m]
        t = et[e, EDGE_POLYGON]
        bound = edge_bound(et, e)
        if et[e, EDGE_A] > 0:
            low[t] = max(bound, 0)
            key[e] = low[t]
        else:
            high[t] = min(bound, width - 1)
            key[e] = high[t] + 1


@njit(cache=True)
def _walk(j, et, aet, n_aet, key, low, high, flag, inside, where, pt_i, pt_f, inv_w,
          triangles, depth, tri, b1, b2, stack, stats, recording, rec_spans, n_rec):
    """Walk the sorted AET: flip the in/out flags, draw the spans between the crossings."""
    n_in = 0
    x = 0
    for m in range(n_aet):
        e = aet[m]
        t = et[e, EDGE_POLYGON]
        if key[e] > x and n_in > 0:
            _span(x, key[e] - 1, j, inside, n_in, pt_i, pt_f, inv_w, triangles, depth, tri, b1,
                  b2, stack, stats, recording, rec_spans, n_rec)
        x = max(x, key[e])
        if et[e, EDGE_A] > 0:
            if low[t] <= high[t] and not flag[t]:       # a polygon with pixels on this line
                flag[t] = True
                where[t] = n_in
                inside[n_in] = t
                n_in += 1
        elif flag[t]:
            flag[t] = False                   # out: the last in-polygon takes its place
            last = inside[n_in - 1]
            inside[where[t]] = last
            where[last] = where[t]
            n_in -= 1
    for m in range(n_in):               # (every polygon in has met its right edge by now)
        flag[inside[m]] = False


@njit(cache=True)
def _record_aet(et, aet, n_aet, key, yc, rec_aet, n_rec):
    """The AET of the recorded scan line: polygon, side, exact crossing x (pixels), key."""
    for m in range(min(n_aet, rec_aet.shape[0])):
        e = aet[m]
        a, b, c = et[e, EDGE_A], et[e, EDGE_A + 1], et[e, EDGE_A + 2]
        c += 1 if a < 0 else 0                            # the fill rule's bias undone
        rec_aet[m, 0] = et[e, EDGE_POLYGON]
        rec_aet[m, 1] = 1.0 if a > 0 else -1.0
        rec_aet[m, 2] = -(b * yc + c) / (a * float(SUBPIXEL_ONE))
        rec_aet[m, 3] = key[e]
    n_rec[0] = min(n_aet, rec_aet.shape[0])


@njit(cache=True)
def scan(xy_z, inv_w, triangles, fixed, depth, tri, b1, b2, record_row, rec_aet, rec_spans,
         n_rec, stats):
    """The whole algorithm over one frame; returns the count of bad vertex indices."""
    height, width = depth.shape
    n_tri = triangles.shape[0]
    depth[:, :] = -np.inf
    tri[:, :] = -1
    pt_i = np.zeros((n_tri, PT_INTS), np.int64)
    pt_f = np.zeros((n_tri, PT_FLOATS))
    et = np.zeros((3 * n_tri, EDGE_FIELDS + 1), np.int64)
    bad, n_edges = _build_tables(xy_z, fixed, triangles, width, height, pt_i, pt_f, et, stats)
    if bad:
        return bad
    order = np.empty(n_edges, np.int64)
    row_start = np.zeros(height + 1, np.int64)
    _bucket(et, n_edges, height, order, row_start)
    aet = np.empty(n_edges, np.int64)
    key = np.zeros(n_edges, np.int64)
    low = np.zeros(n_tri, np.int64)
    high = np.zeros(n_tri, np.int64)
    flag = np.zeros(n_tri, np.bool_)
    inside = np.empty(n_tri, np.int64)
    where = np.zeros(n_tri, np.int64)
    stack = np.empty((width + 2, 3), np.int64)
    n_aet = 0
    for j in range(height):
        for k in range(row_start[j], row_start[j + 1]):      # the ET bucket comes in
            aet[n_aet] = order[k]
            n_aet += 1
        stats[2] = max(stats[2], n_aet)
        _crossings(et, aet, n_aet, width, key, low, high)
        _sort_aet(aet, n_aet, key)
        recording = j == record_row
        if recording:
            _record_aet(et, aet, n_aet, key, j * SUBPIXEL_ONE + PIXEL_CENTRE, rec_aet, n_rec)
        _walk(j, et, aet, n_aet, key, low, high, flag, inside, where, pt_i, pt_f, inv_w,
              triangles, depth, tri, b1, b2, stack, stats, recording, rec_spans, n_rec)
        kept = 0                        # edges ending here leave; the rest step up one line
        for m in range(n_aet):
            e = aet[m]
            if et[e, EDGE_LAST] > j:
                step_edge(et, e)
                aet[kept] = e
                kept += 1
        n_aet = kept
    return 0


class ScanlineRecord:
    """What the algorithm did on one frame: ``stats`` (named by :data:`STATS`), and for the
    recorded scan line (device row) ``aet`` (n, 4): polygon, side (+1 left edge, -1 right),
    exact crossing x in pixels, the pixel key it sorts by; ``spans`` (m, 5): first and last
    pixel, the visible polygon, how many polygons were in, how it was decided (:data:`DECIDED`)."""

    def __init__(self, stats, aet=None, spans=None, row=-1):
        self.stats = {name: int(v) for name, v in zip(STATS, stats)}
        self.row = row
        self.aet = aet if aet is not None else np.empty((0, 4))
        self.spans = spans if spans is not None else np.empty((0, 5), np.int64)


def rasterize(xy_z, inv_w, triangles, width, height, out: VisibilityBuffer | None = None,
              parallel: bool = True, n_bands: int | None = None, record_row: int = -1,
              record: list | None = None) -> VisibilityBuffer:
    """The visible polygon of every pixel by Watkins' algorithm, as a visibility buffer.

    The arguments are :func:`core.pipeline.raster.rasterize`'s (``parallel`` and ``n_bands``
    accepted and ignored: the scan lines are walked in order, on one core). ``record_row``: a
    device row (y up) whose AET and spans go into a :class:`ScanlineRecord` appended to
    ``record`` (the frame's counters are appended there in any case).
    """
    xy_z, inv_w, triangles, width, height = checked_inputs(xy_z, inv_w, triangles, width, height)
    if out is None or out.depth.shape != (height, width):
        out = VisibilityBuffer.allocate(width, height)
    fixed = np.empty((xy_z.shape[0], 2), np.int32)
    snap_vertices(xy_z, inv_w, fixed, 0, xy_z.shape[0])
    n_tri = triangles.shape[0]
    rec_aet = np.zeros((3 * n_tri if record_row >= 0 else 0, 4))
    rec_spans = np.zeros((width + 3 * n_tri if record_row >= 0 else 0, 5), np.int64)
    n_rec = np.zeros(2, np.int64)
    stats = np.zeros(len(STATS), np.int64)
    bad = scan(xy_z, inv_w, triangles, fixed, out.depth, out.tri, out.b1, out.b2,
               int(record_row), rec_aet, rec_spans, n_rec, stats)
    if bad:
        raise ValueError(f"{bad} triangles name a vertex outside 0..{xy_z.shape[0] - 1}")
    out.forget_spans()                      # every row may be written: the next frame clears all
    if record is not None:
        record.append(ScanlineRecord(stats, rec_aet[:n_rec[0]], rec_spans[:n_rec[1]],
                                     int(record_row)))
    return out
