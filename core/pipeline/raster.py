"""Scan conversion and the z-buffer (FvDFH 15.4), set up the way Mesa's llvmpipe does it.

Takes triangles already clipped, projected (perspective-to-parallel matrix, divide by W) and
mapped to the device: ``xy_z`` (V, 3) float64 device coordinates (x right, **y up**, pixel
(i, j) has its centre at (i + 0.5, j + 0.5); depth z in [-1, 0] with **larger z = nearer**),
``inv_w`` (V,) float64 = 1/W per vertex (all ones for parallel), ``triangles`` (T, 3) int64.

Returns a :class:`VisibilityBuffer`: ``depth`` (H, W) float64 (-inf where empty), ``tri``
(H, W) int32 (index into ``triangles``; -1 where empty), ``b1``, ``b2`` (H, W) float64, the
perspective-correct barycentric weights of vertex 1 and vertex 2 of that triangle at the pixel
centre (vertex 0's weight is 1 - b1 - b2; undefined where empty). All arrays are in image
order: row 0 is the top, so device row j is array row H - 1 - j.

Two stages, as in llvmpipe (``lp_setup_tri.c`` builds a scene, ``lp_rast_tri.c`` consumes it):

* **setup** snaps each vertex to fixed point with ``SUBPIXEL_BITS`` = 8 sub-pixel bits, finds
  each triangle's box of pixel centres (clamped to the framebuffer) and keeps only triangles
  that can draw something: box not empty, and for boxes of at most 2 x 2 pixels at least one
  centre actually covered (in a dense mesh most triangles cover none). Each kept
  triangle goes into the *scene*: its id, the horizontal bands it meets, its fixed-point
  corners, depths and 1/W, packed so that the scan reads it in order.
* **rast** orients each triangle counter-clockwise (either winding is drawn) and writes each
  edge as an edge function E(x, y) = A x + B y + C whose constant already holds the top-left
  fill rule, so a pixel centre is inside exactly when all three E are >= 0: one sign test
  (``e0 | e1 | e2 >= 0``). The integers are exact: two triangles sharing an edge see the same
  numbers, so the edge is neither drawn twice nor left open. The box is walked row by row,
  the edge functions stepped by A per pixel (FvDFH's incremental scan line, in integers).
  Depth is interpolated linearly in screen space (after the perspective-to-parallel divide it
  is an affine function of x and y, FvDFH 6.5.4) and tested as the notes write it,
  ``z >= zbuffer``: on a tie the later triangle wins. Barycentrics are perspective-corrected with 1/W.

Both cores: setup works on chunks of the triangle array, rast on horizontal bands of the
framebuffer, handed out one at a time. Each band draws the scene's triangles that meet it in
triangle order, so every pixel sees the same triangles in the same order as the single-threaded
path (``parallel=False``) and the result is bit-identical.

Vertices far outside the framebuffer are safe: coordinates are clamped to ``COORD_LIMIT``
pixels before the fixed-point conversion (so no product overflows int64) and boxes are clamped
to the framebuffer. A triangle with a non-finite coordinate or a 1/W that is not positive and
finite is skipped (the clipper never produces one); a vertex index out of range raises.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
from numba import njit, prange

SUBPIXEL_BITS = 8
SUBPIXEL_ONE = 1 << SUBPIXEL_BITS  # one pixel in fixed point
PIXEL_CENTRE = SUBPIXEL_ONE // 2  # a pixel centre sits half a pixel in
# |x|, |y| are clamped to this many pixels: fixed-point coordinates stay below 2^28 (int32),
# edge coefficients below 2^29 and edge constants below 2^59, all inside int64.
COORD_LIMIT = float(1 << 20)
INVALID = np.int32(np.iinfo(np.int32).min)  # fixed x of a vertex no triangle may use
MAX_SIZE = 1 << 15  # framebuffer width and height limit
MAX_BANDS = 16  # a triangle's bands are a uint16 bit mask
SETUP_CHUNKS = 64  # pieces of the triangle array that setup hands to the cores
PARALLEL_SETUP = 10_000  # fewer triangles than this are set up on one core


@dataclass
class _Scene:
    """Setup's output, rast's input: the triangles that can draw, chunk by chunk.

    Chunk c covers triangles [c T / n, (c + 1) T / n) and writes its kept triangles from slot
    c T / n on, in triangle order, up to ``chunk_end[c]``. Capacity grows on demand and is
    kept from frame to frame.
    """

    fixed: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int32))  # (V, 2)
    tri: np.ndarray = field(default_factory=lambda: np.empty(0, np.int32))  # triangle id
    bands: np.ndarray = field(default_factory=lambda: np.empty(0, np.uint16))  # band mask
    xy: np.ndarray = field(default_factory=lambda: np.empty((0, 6), np.int32))  # fixed x0..y2
    zw: np.ndarray = field(default_factory=lambda: np.empty((0, 6)))  # z0, z1, z2, 1/W0..2
    chunk_end: np.ndarray = field(default_factory=lambda: np.empty(SETUP_CHUNKS, np.int64))

    def reserve(self, n_vertices: int, n_triangles: int) -> None:
        if self.fixed.shape[0] < n_vertices:
            self.fixed = np.empty((max(n_vertices, 2 * self.fixed.shape[0]), 2), np.int32)
        if self.tri.shape[0] < n_triangles:
            n = max(n_triangles, 2 * self.tri.shape[0])
            self.tri = np.empty(n, np.int32)
            self.bands = np.empty(n, np.uint16)
            self.xy = np.empty((n, 6), np.int32)
            self.zw = np.empty((n, 6))


@dataclass
class VisibilityBuffer:
    """What the z-buffer saw at each pixel: depth, triangle id and its barycentrics.

    Arrays are (H, W) in image order (row 0 = top). ``tri == -1`` marks an empty pixel.
    Reuse one buffer across frames (``rasterize(..., out=buffer)``) and nothing is allocated.
    """

    depth: np.ndarray  # float64, -inf = empty, larger = nearer
    tri: np.ndarray  # int32, -1 = empty
    b1: np.ndarray  # float64, perspective-correct weight of vertex 1 (undefined where tri -1)
    b2: np.ndarray  # float64, perspective-correct weight of vertex 2 (undefined where tri -1)
    _scene: _Scene = field(default_factory=_Scene, repr=False)
    # (T, 3, 3) barycentric planes of the triangles drawn (core.pipeline.derivatives), set by
    # the renderer when a shader needs screen derivatives; None otherwise.
    planes: np.ndarray | None = None
    # (H, 2) int32: per image row, the first and last column the last rasterize() may have
    # written (first > last: none; the columns of the boxes drawn in the row's band). Outside its span a row is empty. The next frame clears only the
    # spans and the resolve shades only them: at 1k triangles most of the 500 x 500 pixels
    # are never touched. ``spans_known`` False (a buffer written by anyone else) makes the
    # next rasterize() clear every row.
    span: np.ndarray | None = None
    spans_known: bool = False

    @classmethod
    def allocate(cls, width: int, height: int) -> "VisibilityBuffer":
        """A cleared buffer of ``height`` rows and ``width`` columns."""
        shape = (int(height), int(width))
        buffer = cls(depth=np.full(shape, -np.inf), tri=np.full(shape, -1, np.int32),
                     b1=np.zeros(shape), b2=np.zeros(shape))
        buffer.forget_spans()
        return buffer

    def forget_spans(self) -> None:
        """Say that something other than :func:`rasterize` wrote into the buffer (or may
        have): every row counts as written, so the next frame clears it whole."""
        self.span = np.empty((self.height, 2), np.int32)
        self.span[:, 0] = 0
        self.span[:, 1] = self.width - 1
        self.spans_known = False

    @property
    def width(self) -> int:
        return self.depth.shape[1]

    @property
    def height(self) -> int:
        return self.depth.shape[0]

    def clear(self) -> None:
        """Empty every pixel: depth -inf, tri -1 (and the barycentrics 0)."""
        self.depth.fill(-np.inf)
        self.tri.fill(-1)
        self.b1.fill(0.0)
        self.b2.fill(0.0)
        self.forget_spans()
        self.span[:, 0] = self.width          # every row empty
        self.span[:, 1] = -1
        self.spans_known = True


# --------------------------------------------------------------------------------------------
# Fixed point and edge functions, shared by setup and rast


@njit(cache=True)
def _to_fixed(v):
    """Snap a device coordinate to fixed point (nearest 1/256 pixel), clamped."""
    v = min(max(v, -COORD_LIMIT), COORD_LIMIT)
    return np.int32(np.floor(v * SUBPIXEL_ONE + 0.5))


@njit(cache=True)
def _pixel_box(x0, y0, x1, y1, x2, y2, width, height):
    """Columns i_min..i_max and device rows j_min..j_max whose pixel centres lie in the box."""
    # pixel i's centre is i*256 + 128: the first centre >= min, the last centre <= max
    i_min = (min(x0, x1, x2) - PIXEL_CENTRE + SUBPIXEL_ONE - 1) >> SUBPIXEL_BITS
    i_max = (max(x0, x1, x2) - PIXEL_CENTRE) >> SUBPIXEL_BITS
    j_min = (min(y0, y1, y2) - PIXEL_CENTRE + SUBPIXEL_ONE - 1) >> SUBPIXEL_BITS
    j_max = (max(y0, y1, y2) - PIXEL_CENTRE) >> SUBPIXEL_BITS
    return max(i_min, 0), min(i_max, width - 1), max(j_min, 0), min(j_max, height - 1)


@njit(cache=True)
def _edge(xa, ya, xb, yb, sign):
    """Edge function of the directed edge a->b, E(x, y) = A x + B y + C, oriented by ``sign``.

    Returns (A, B, C_biased, bias). With the triangle counter-clockwise (sign = +1 for CCW,
    -1 for CW input) the interior is E > 0 on all three edges. Top-left rule: a centre exactly
    on an edge belongs to the triangle only if the edge is a left edge (interior to its right:
    A > 0) or a top edge (horizontal, interior below: A == 0 and B < 0). The other edges get
    bias 1 subtracted from C, so that "E >= 0" after the bias means "E > 0" there.
    """
    a = sign * (ya - yb)
    b = sign * (xb - xa)
    c = -(a * xa + b * ya)
    top_left = (a > 0) | ((a == 0) & (b < 0))  # no short circuit: a select, not a branch
    bias = 1 - np.int64(top_left)
    return a, b, c - bias, bias


@njit(cache=True)
def _triangle_edges(x0, y0, x1, y1, x2, y2):
    """Twice the area (>= 0) and the three oriented edges (A, B, C, bias) opposite v0, v1, v2.

    E_k is the edge opposite vertex k, so E_k / area2 is vertex k's barycentric weight.
    area2 == 0 means a degenerate triangle, which draws nothing.
    """
    area2 = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)  # twice the signed area
    sign = 1 | (area2 >> 63)  # +1 or -1: orient counter-clockwise, either winding is drawn
    edge0 = _edge(x1, y1, x2, y2, sign)
    edge1 = _edge(x2, y2, x0, y0, sign)
    edge2 = _edge(x0, y0, x1, y1, sign)
    return sign * area2, edge0, edge1, edge2


# --------------------------------------------------------------------------------------------
# Setup (lp_setup_tri.c): fixed point, boxes, culling, binning into bands


@njit(cache=True)
def _snap_vertices(xy_z, inv_w, fixed):
    """Fixed-point x, y of every vertex, or INVALID for one no triangle may use."""
    for v in range(xy_z.shape[0]):
        x = xy_z[v, 0]
        y = xy_z[v, 1]
        w = inv_w[v]
        s = x + y + xy_z[v, 2] + w
        if s - s == 0.0 and w > 0.0:  # all finite (NaN and inf make s - s NaN), W in front
            fixed[v, 0] = _to_fixed(x)
            fixed[v, 1] = _to_fixed(y)
        else:
            fixed[v, 0] = INVALID
            fixed[v, 1] = 0


@njit(cache=True)
def _quad_covers(x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max):
    """Does the triangle cover a pixel centre of its box, a box of at most 2 x 2 pixels?

    The rast's edge test on the four centres of a quad (the edge functions stepped by A to
    the right and by B upwards), masked to the box, with no branch: in a dense mesh this
    answer is a coin toss that a branch would mispredict.
    """
    area2, edge0, edge1, edge2 = _triangle_edges(x0, y0, x1, y1, x2, y2)
    a0, b0, c0, _ = edge0
    a1, b1, c1, _ = edge1
    a2, b2, c2, _ = edge2
    px = i_min * SUBPIXEL_ONE + PIXEL_CENTRE
    py = j_min * SUBPIXEL_ONE + PIXEL_CENTRE
    e0 = a0 * px + b0 * py + c0
    e1 = a1 * px + b1 * py + c1
    e2 = a2 * px + b2 * py + c2
    right0, right1, right2 = a0 * SUBPIXEL_ONE, a1 * SUBPIXEL_ONE, a2 * SUBPIXEL_ONE
    up0, up1, up2 = b0 * SUBPIXEL_ONE, b1 * SUBPIXEL_ONE, b2 * SUBPIXEL_ONE
    wide = i_max > i_min
    tall = j_max > j_min
    hit = (e0 | e1 | e2) >= 0
    hit |= wide & (((e0 + right0) | (e1 + right1) | (e2 + right2)) >= 0)
    hit |= tall & (((e0 + up0) | (e1 + up1) | (e2 + up2)) >= 0)
    hit |= wide & tall & (((e0 + right0 + up0) | (e1 + right1 + up1) | (e2 + right2 + up2))
                          >= 0)
    return hit & (area2 != 0)


@njit(cache=True)
def _setup_chunk(xy_z, inv_w, triangles, width, height, band_scale, fixed, chunk, n_chunks,
                 s_tri, s_bands, s_xy, s_zw, chunk_end):
    """Put the triangles of one chunk that can draw something into the scene, in order.

    Returns how many triangles name a vertex that does not exist (they are never drawn).
    """
    n_vertices = fixed.shape[0]
    n = triangles.shape[0]
    first = chunk * n // n_chunks
    slot = first
    bad = 0
    for t in range(first, (chunk + 1) * n // n_chunks):
        v0 = triangles[t, 0]
        v1 = triangles[t, 1]
        v2 = triangles[t, 2]
        if min(v0, v1, v2) < 0 or max(v0, v1, v2) >= n_vertices:
            bad += 1
            continue
        x0 = np.int64(fixed[v0, 0])
        y0 = np.int64(fixed[v0, 1])
        x1 = np.int64(fixed[v1, 0])
        y1 = np.int64(fixed[v1, 1])
        x2 = np.int64(fixed[v2, 0])
        y2 = np.int64(fixed[v2, 1])
        if x0 == INVALID or x1 == INVALID or x2 == INVALID:
            continue
        i_min, i_max, j_min, j_max = _pixel_box(x0, y0, x1, y1, x2, y2, width, height)
        if i_min > i_max or j_min > j_max:
            continue  # no pixel centre of the framebuffer in its box
        if i_max - i_min <= 1 and j_max - j_min <= 1:
            if not _quad_covers(x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max):
                continue  # a small triangle between pixel centres: most of a dense mesh
        # bands first..last: j // rows_per_band, as a multiply by band_scale = 2^32 //
        # rows_per_band + 1 (exact while j * rows_per_band < 2^32; rows are < 2^15)
        band_first = (j_min * band_scale) >> 32
        band_last = (j_max * band_scale) >> 32
        s_tri[slot] = t
        s_bands[slot] = ((1 << (band_last + 1)) - 1) ^ ((1 << band_first) - 1)
        s_xy[slot, 0] = x0
        s_xy[slot, 1] = y0
        s_xy[slot, 2] = x1
        s_xy[slot, 3] = y1
        s_xy[slot, 4] = x2
        s_xy[slot, 5] = y2
        s_zw[slot, 0] = xy_z[v0, 2]
        s_zw[slot, 1] = xy_z[v1, 2]
        s_zw[slot, 2] = xy_z[v2, 2]
        s_zw[slot, 3] = inv_w[v0]
        s_zw[slot, 4] = inv_w[v1]
        s_zw[slot, 5] = inv_w[v2]
        slot += 1
    chunk_end[chunk] = slot
    return bad


@njit(cache=True, parallel=True, nogil=True)
def _setup_parallel(xy_z, inv_w, triangles, width, height, band_scale, fixed, s_tri, s_bands,
                    s_xy, s_zw, chunk_end):
    # Snapping is one cheap pass (about 1 ms for 500k vertices); a parallel region of its
    # own would cost a core's wake-up, and on a loaded machine a scheduler tick, each frame.
    _snap_vertices(xy_z, inv_w, fixed)
    n_chunks = chunk_end.shape[0]
    bad = 0
    for chunk in prange(n_chunks):
        bad += _setup_chunk(xy_z, inv_w, triangles, width, height, band_scale, fixed, chunk,
                            n_chunks, s_tri, s_bands, s_xy, s_zw, chunk_end)
    return bad


@njit(cache=True, nogil=True)
def _setup_serial(xy_z, inv_w, triangles, width, height, band_scale, fixed, s_tri, s_bands,
                  s_xy, s_zw, chunk_end):
    _snap_vertices(xy_z, inv_w, fixed)
    bad = 0
    for chunk in range(chunk_end.shape[0]):
        bad += _setup_chunk(xy_z, inv_w, triangles, width, height, band_scale, fixed, chunk,
                            chunk_end.shape[0], s_tri, s_bands, s_xy, s_zw, chunk_end)
    return bad


# --------------------------------------------------------------------------------------------
# Rasterization (lp_rast_tri.c): walk the box, sign test, z-buffer test, barycentrics


@njit(cache=True)
def _scan_triangle(s_xy, s_zw, slot, t, band_first, band_last, depth, tri, b1, b2,
                   count_fragments, fragments):
    """Scan-convert triangle t (scene slot ``slot``) into the device rows of one band.

    Returns the columns of its box (first > last when it drew nothing)."""
    height, width = depth.shape
    x0 = np.int64(s_xy[slot, 0])
    y0 = np.int64(s_xy[slot, 1])
    x1 = np.int64(s_xy[slot, 2])
    y1 = np.int64(s_xy[slot, 3])
    x2 = np.int64(s_xy[slot, 4])
    y2 = np.int64(s_xy[slot, 5])
    i_min, i_max, j_min, j_max = _pixel_box(x0, y0, x1, y1, x2, y2, width, height)
    j_min = max(j_min, band_first)
    j_max = min(j_max, band_last)
    area2, edge0, edge1, edge2 = _triangle_edges(x0, y0, x1, y1, x2, y2)
    if area2 == 0 or j_min > j_max:
        return width, -1
    a0, b0, c0, bias0 = edge0
    a1, b1_, c1, bias1 = edge1
    a2, b2_, c2, bias2 = edge2
    inv_area = 1.0 / area2
    z0 = s_zw[slot, 0]
    dz1 = s_zw[slot, 1] - z0
    dz2 = s_zw[slot, 2] - z0
    w0 = s_zw[slot, 3]
    w1 = s_zw[slot, 4]
    w2 = s_zw[slot, 5]
    px = i_min * SUBPIXEL_ONE + PIXEL_CENTRE
    for j in range(j_min, j_max + 1):
        py = j * SUBPIXEL_ONE + PIXEL_CENTRE
        e0 = a0 * px + b0 * py + c0
        e1 = a1 * px + b1_ * py + c1
        e2 = a2 * px + b2_ * py + c2
        row = height - 1 - j  # image order: row 0 is the top
        entered = False
        for i in range(i_min, i_max + 1):
            if (e0 | e1 | e2) >= 0:  # inside all three edges, fill rule included
                entered = True
                if count_fragments:
                    fragments[row, i] += 1
                # unbiased edge values: exact integers, the screen-space barycentrics * area2
                l1 = float(e1 + bias1)
                l2 = float(e2 + bias2)
                z = z0 + (l1 * dz1 + l2 * dz2) * inv_area  # depth is affine in screen space
                if z >= depth[row, i]:  # the notes' test: a tie goes to the later triangle
                    depth[row, i] = z
                    tri[row, i] = t
                    # perspective correction: weights ~ lambda_k / W_k, renormalised
                    p0 = float(e0 + bias0) * w0
                    p1 = l1 * w1
                    p2 = l2 * w2
                    s = 1.0 / (p0 + p1 + p2)
                    b1[row, i] = p1 * s
                    b2[row, i] = p2 * s
            elif entered:
                break  # a triangle is convex: once the scan line has left it, it is done
            e0 += a0 * SUBPIXEL_ONE  # one pixel to the right
            e1 += a1 * SUBPIXEL_ONE
            e2 += a2 * SUBPIXEL_ONE
    return i_min, i_max


@njit(cache=True)
def _scan_band(band, rows_per_band, n_triangles, s_tri, s_bands, s_xy, s_zw, chunk_end, depth,
               tri, b1, b2, span, count_fragments, fragments):
    """Clear one band of rows, then draw into it every scene triangle that meets it, in order.

    Only what the last frame wrote is cleared (each row's span; the rest of the row is still
    empty), and only depth and tri: b1 and b2 mean nothing where tri is -1 and nobody reads
    them there. The band's new span is the columns of the boxes drawn in it: two registers
    per band, nothing per pixel."""
    height, width = depth.shape
    first = band * rows_per_band
    last = min(height, first + rows_per_band) - 1
    for j in range(first, last + 1):
        row = height - 1 - j
        for i in range(max(span[row, 0], 0), min(span[row, 1], width - 1) + 1):
            depth[row, i] = -np.inf
            tri[row, i] = -1
        span[row, 0] = width
        span[row, 1] = -1
    bit = np.uint16(1 << band)
    n_chunks = chunk_end.shape[0]
    lo = width
    hi = -1
    for chunk in range(n_chunks):
        for slot in range(chunk * n_triangles // n_chunks, chunk_end[chunk]):
            if s_bands[slot] & bit:
                i_min, i_max = _scan_triangle(s_xy, s_zw, slot, s_tri[slot], first, last,
                                              depth, tri, b1, b2, count_fragments, fragments)
                lo = min(lo, i_min)
                hi = max(hi, i_max)
    for j in range(first, last + 1):
        span[height - 1 - j, 0] = lo
        span[height - 1 - j, 1] = hi


@njit(cache=True, parallel=True, nogil=True)
def _rast_parallel(n_bands, rows_per_band, n_triangles, s_tri, s_bands, s_xy, s_zw, chunk_end,
                   depth, tri, b1, b2, span, count_fragments, fragments):
    for band in prange(n_bands):
        _scan_band(band, rows_per_band, n_triangles, s_tri, s_bands, s_xy, s_zw, chunk_end,
                   depth, tri, b1, b2, span, count_fragments, fragments)


@njit(cache=True, nogil=True)
def _rast_serial(n_bands, rows_per_band, n_triangles, s_tri, s_bands, s_xy, s_zw, chunk_end,
                 depth, tri, b1, b2, span, count_fragments, fragments):
    for band in range(n_bands):
        _scan_band(band, rows_per_band, n_triangles, s_tri, s_bands, s_xy, s_zw, chunk_end,
                   depth, tri, b1, b2, span, count_fragments, fragments)


# --------------------------------------------------------------------------------------------
# Public entry points

_NO_FRAGMENTS = np.zeros((1, 1), np.int32)


def default_bands(height: int) -> int:
    """Bands for the parallel path: a few per core, so that no core waits on a busy band."""
    return max(1, min(MAX_BANDS, 4 * numba.get_num_threads(), height))


def _checked(xy_z, inv_w, triangles, width, height):
    width, height = int(width), int(height)
    if not (1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE):
        raise ValueError(f"framebuffer size {width}x{height} outside 1..{MAX_SIZE}")
    xy_z = np.ascontiguousarray(xy_z, dtype=np.float64)
    inv_w = np.ascontiguousarray(inv_w, dtype=np.float64)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    if xy_z.ndim != 2 or xy_z.shape[1] != 3:
        raise ValueError(f"xy_z must be (V, 3), got {xy_z.shape}")
    if inv_w.shape != (xy_z.shape[0],):
        raise ValueError(f"inv_w must be ({xy_z.shape[0]},), got {inv_w.shape}")
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise ValueError(f"triangles must be (T, 3), got {triangles.shape}")
    return xy_z, inv_w, triangles, width, height


def _run(xy_z, inv_w, triangles, width, height, out, parallel, n_bands, fragments):
    xy_z, inv_w, triangles, width, height = _checked(xy_z, inv_w, triangles, width, height)
    if out is None or out.depth.shape != (height, width):
        out = VisibilityBuffer.allocate(width, height)
    if n_bands is None:
        n_bands = default_bands(height) if parallel else 1
    n_bands = max(1, min(int(n_bands), MAX_BANDS, height))
    rows_per_band = -(-height // n_bands)
    n_bands = -(-height // rows_per_band)  # no empty band at the end
    band_scale = (1 << 32) // rows_per_band + 1
    n_triangles = triangles.shape[0]
    scene = out._scene
    scene.reserve(xy_z.shape[0], n_triangles)
    fixed = scene.fixed[:xy_z.shape[0]]
    count = fragments is not None
    frag = fragments if count else _NO_FRAGMENTS
    # Below PARALLEL_SETUP triangles setup takes well under a millisecond: waking a second
    # core would cost more than it saves. (Either way the scene is the same.)
    setup = _setup_parallel if parallel and n_triangles >= PARALLEL_SETUP else _setup_serial
    rast = _rast_parallel if parallel else _rast_serial
    # chunk size 1: chunks and bands are handed out one at a time, so the cores share the
    # load even when a few bands hold most of the triangles
    with numba.parallel_chunksize(1):
        bad = setup(xy_z, inv_w, triangles, width, height, band_scale, fixed, scene.tri,
                    scene.bands, scene.xy, scene.zw, scene.chunk_end)
        if bad:
            raise ValueError(f"{bad} triangles name a vertex outside 0..{xy_z.shape[0] - 1}")
        if not out.spans_known or out.span is None or out.span.shape != (height, 2):
            out.forget_spans()
        out.spans_known = False             # until the rast has run to its end
        rast(n_bands, rows_per_band, n_triangles, scene.tri, scene.bands, scene.xy, scene.zw,
             scene.chunk_end, out.depth, out.tri, out.b1, out.b2, out.span, count, frag)
        out.spans_known = True
    return out


def rasterize(xy_z, inv_w, triangles, width, height, out: VisibilityBuffer | None = None,
              parallel: bool = True, n_bands: int | None = None) -> VisibilityBuffer:
    """Scan-convert ``triangles`` into a z-buffer of ``width`` x ``height`` pixels.

    Parameters
    ----------
    xy_z : (V, 3) float64 device coordinates (x right, y up, z larger = nearer).
    inv_w : (V,) float64, 1/W per vertex (ones for a parallel projection); must be > 0.
    triangles : (T, 3) int64 vertex indices; either winding is drawn.
    out : a buffer to reuse (cleared here); a new one is allocated if it is None or its size
        differs, so always use the returned buffer.
    parallel : use all cores; ``False`` runs the single-threaded path (one band), whose
        result is bit-identical.
    n_bands : number of horizontal bands (default: a few per core; at most 16).
    """
    return _run(xy_z, inv_w, triangles, width, height, out, parallel, n_bands, None)


def count_fragments(xy_z, inv_w, triangles, width, height, parallel: bool = True,
                    n_bands: int | None = None) -> np.ndarray:
    """How many triangles cover each pixel centre, ignoring depth: (H, W) int32, image order.

    Runs exactly the code of :func:`rasterize` (same setup, same edge tests) with a counter
    beside the depth test; the tests use it to show the fill rule is watertight.
    """
    fragments = np.zeros((int(height), int(width)), np.int32)
    _run(xy_z, inv_w, triangles, width, height, None, parallel, n_bands, fragments)
    return fragments
