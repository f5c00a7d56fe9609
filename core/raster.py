"""Scan conversion and the z-buffer (FvDFH 15.4), set up the way Mesa's llvmpipe does it.

Takes triangles already clipped, projected (perspective-to-parallel matrix, divide by W) and
mapped to the device: ``xy_z`` (V, 3) float64 device coordinates (x right, **y up**, pixel
(i, j) has its centre at (i + 0.5, j + 0.5); depth z in [-1, 0] with **larger z = nearer**),
``inv_w`` (V,) float64 = 1/W per vertex (all ones for parallel), ``triangles`` (T, 3) int64.

Returns a :class:`VisibilityBuffer`: ``depth`` (H, W) float64 (-inf where empty), ``tri``
(H, W) int32 (index into ``triangles``; -1 where empty), ``b1``, ``b2`` (H, W) float64, the
perspective-correct barycentric weights of vertex 1 and vertex 2 of that triangle at the pixel
centre (vertex 0's weight is 1 - b1 - b2; both are 0 where empty). All arrays are in image
order: row 0 is the top, so device row j is array row H - 1 - j.

How it works (``lp_setup_tri.c`` / ``lp_rast_tri.c`` in llvmpipe):

* setup snaps each vertex to fixed point with ``SUBPIXEL_BITS`` = 8 sub-pixel bits (int64),
  orients the triangle counter-clockwise (either winding is drawn; zero area draws nothing) and
  writes each edge as an edge function E(x, y) = A x + B y + C whose constant already holds the
  top-left fill rule, so a pixel centre is inside exactly when all three E are >= 0 — one sign
  test (``e0 | e1 | e2 >= 0``). The integer arithmetic is exact: two triangles sharing an edge
  see the same numbers, so the shared edge is neither drawn twice nor left open.
* scan conversion walks the bounding box (clamped to the framebuffer) row by row, stepping the
  edge functions by A per pixel — FvDFH's incremental scan line, in integers.
* depth is interpolated linearly in screen space (after the perspective-to-parallel divide the
  depth is an affine function of x and y, FvDFH 6.5.4) and tested strictly: a pixel is written
  only when nearer. Barycentrics are perspective-corrected with ``inv_w``.
* both cores: the framebuffer is cut into horizontal bands, one task per band; each band walks
  the triangles whose bounding box meets it, in triangle order, so every pixel sees the same
  triangles in the same order as the single-threaded path and the result is bit-identical.

Vertices far outside the framebuffer are safe: coordinates are clamped to ``COORD_LIMIT``
pixels before the fixed-point conversion (so no product overflows int64) and the bounding box
is clamped to the framebuffer. A triangle with a non-finite coordinate or a non-positive or
non-finite ``inv_w`` is skipped (the clipper never produces one).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np
from numba import njit, prange

SUBPIXEL_BITS = 8
SUBPIXEL_ONE = 1 << SUBPIXEL_BITS  # one pixel in fixed point
PIXEL_CENTRE = SUBPIXEL_ONE // 2  # a pixel centre sits half a pixel in
# |x|, |y| are clamped to this many pixels: fixed-point coordinates stay below 2^28, edge
# coefficients below 2^29 and the edge constants below 2^59, all inside int64.
COORD_LIMIT = float(1 << 20)
MAX_SIZE = 1 << 15  # framebuffer width/height limit (keeps A * x inside int64 too)
MAX_BANDS = 16  # band membership is a uint16 bit mask per triangle


@dataclass
class VisibilityBuffer:
    """What the z-buffer saw at each pixel: depth, triangle id and its barycentrics.

    Arrays are (H, W) in image order (row 0 = top). ``tri == -1`` marks an empty pixel.
    Reuse one buffer across frames (``rasterize(..., out=buffer)``) and nothing is allocated.
    """

    depth: np.ndarray  # float64, -inf = empty, larger = nearer
    tri: np.ndarray  # int32, -1 = empty
    b1: np.ndarray  # float64, perspective-correct weight of vertex 1
    b2: np.ndarray  # float64, perspective-correct weight of vertex 2
    # scratch kept between frames so that a frame allocates nothing new
    _fixed: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int32), repr=False)
    _band_mask: np.ndarray = field(default_factory=lambda: np.empty(0, np.uint16), repr=False)

    @classmethod
    def allocate(cls, width: int, height: int) -> "VisibilityBuffer":
        """A cleared buffer of ``height`` rows and ``width`` columns."""
        shape = (int(height), int(width))
        return cls(
            depth=np.full(shape, -np.inf),
            tri=np.full(shape, -1, np.int32),
            b1=np.zeros(shape),
            b2=np.zeros(shape),
        )

    @property
    def width(self) -> int:
        return self.depth.shape[1]

    @property
    def height(self) -> int:
        return self.depth.shape[0]

    def clear(self) -> None:
        """Empty every pixel: depth -inf, tri -1, barycentrics 0."""
        self.depth.fill(-np.inf)
        self.tri.fill(-1)
        self.b1.fill(0.0)
        self.b2.fill(0.0)

    def _scratch(self, n_vertices: int, n_triangles: int) -> tuple[np.ndarray, np.ndarray]:
        """Fixed-point vertices (V, 2) int32 and band masks (T,) uint16, grown on demand."""
        if self._fixed.shape[0] < n_vertices:
            self._fixed = np.empty((max(n_vertices, 2 * self._fixed.shape[0]), 2), np.int32)
        if self._band_mask.shape[0] < n_triangles:
            self._band_mask = np.empty(max(n_triangles, 2 * self._band_mask.shape[0]), np.uint16)
        return self._fixed[:n_vertices], self._band_mask[:n_triangles]


# --------------------------------------------------------------------------------------------
# Setup (lp_setup_tri.c): fixed point, orientation, edge functions with the fill rule folded in

INVALID = np.int32(np.iinfo(np.int32).min)  # fixed x of a vertex that must not be drawn


@njit(cache=True)
def _to_fixed(v):
    """Snap a device coordinate to fixed point (round to nearest 1/256 pixel), clamped."""
    v = min(max(v, -COORD_LIMIT), COORD_LIMIT)
    return np.int32(np.floor(v * SUBPIXEL_ONE + 0.5))


@njit(cache=True)
def _snap_vertex(xy_z, inv_w, fixed, v):
    """Fixed-point x, y of vertex v, or INVALID for a vertex no triangle may use."""
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
def _pixel_box(x0, y0, x1, y1, x2, y2, width, height):
    """Columns i_min..i_max and device rows j_min..j_max whose pixel centres lie in the box."""
    # pixel i's centre is i*256 + 128: first centre >= min, last centre <= max
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
def _triangle_box(triangles, fixed, t, width, height):
    """Vertex ids, fixed-point vertices and pixel box of triangle t.

    Returns (boxed, v0, v1, v2, x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max); ``boxed``
    is False when a vertex is unusable or the box holds no pixel centre of the framebuffer.
    """
    v0 = triangles[t, 0]
    v1 = triangles[t, 1]
    v2 = triangles[t, 2]
    x0 = np.int64(fixed[v0, 0])
    y0 = np.int64(fixed[v0, 1])
    x1 = np.int64(fixed[v1, 0])
    y1 = np.int64(fixed[v1, 1])
    x2 = np.int64(fixed[v2, 0])
    y2 = np.int64(fixed[v2, 1])
    i_min, i_max, j_min, j_max = _pixel_box(x0, y0, x1, y1, x2, y2, width, height)
    valid = (x0 != INVALID) & (x1 != INVALID) & (x2 != INVALID)
    boxed = valid & (i_min <= i_max) & (j_min <= j_max)
    return boxed, v0, v1, v2, x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max


@njit(cache=True)
def _triangle_edges(x0, y0, x1, y1, x2, y2):
    """Twice the area (>= 0) and the three oriented edges (A, B, C, bias) opposite v0, v1, v2.

    E_k is the edge opposite vertex k, so E_k / area2 is vertex k's barycentric weight.
    Zero area2 means a degenerate triangle, which draws nothing.
    """
    area2 = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)  # twice the signed area
    sign = 1 | (area2 >> 63)  # +1 or -1: orient counter-clockwise, either winding is drawn
    edge0 = _edge(x1, y1, x2, y2, sign)
    edge1 = _edge(x2, y2, x0, y0, sign)
    edge2 = _edge(x0, y0, x1, y1, sign)
    return sign * area2, edge0, edge1, edge2


@njit(cache=True)
def _covers_a_centre(edge0, edge1, edge2, i_min, i_max, j_min, j_max):
    """Does any pixel centre of the box pass the edge test? (The scan loop, without writes.)"""
    a0, b0, c0, _ = edge0
    a1, b1, c1, _ = edge1
    a2, b2, c2, _ = edge2
    hit = False
    for j in range(j_min, j_max + 1):
        py = j * SUBPIXEL_ONE + PIXEL_CENTRE
        for i in range(i_min, i_max + 1):
            px = i * SUBPIXEL_ONE + PIXEL_CENTRE
            e0 = a0 * px + b0 * py + c0
            e1 = a1 * px + b1 * py + c1
            e2 = a2 * px + b2 * py + c2
            hit |= (e0 | e1 | e2) >= 0  # no early exit: the box has at most SMALL_BOX pixels
    return hit


SMALL_BOX = 4  # pixel boxes up to this many pixels are tested exactly while binning


@njit(cache=True)
def _bin_triangle(triangles, fixed, width, height, band_scale, band_mask, t):
    """Which bands triangle t draws into, as a bit mask (0: it covers no pixel centre).

    Most triangles of a dense mesh cover one pixel centre or none; testing small boxes here,
    where the vertices are already at hand, keeps the empty ones out of the scan.
    """
    (drawn, v0, v1, v2, x0, y0, x1, y1, x2, y2,
     i_min, i_max, j_min, j_max) = _triangle_box(triangles, fixed, t, width, height)
    if drawn and (i_max - i_min + 1) * (j_max - j_min + 1) <= SMALL_BOX:
        area2, edge0, edge1, edge2 = _triangle_edges(x0, y0, x1, y1, x2, y2)
        drawn = area2 != 0 and _covers_a_centre(edge0, edge1, edge2, i_min, i_max, j_min, j_max)
    mask = 0
    if drawn:
        # bands first..last: j // rows_per_band, as a multiply by band_scale = 2^32 //
        # rows_per_band + 1 (exact while j * rows_per_band < 2^32; rows are < 2^15)
        first = (j_min * band_scale) >> 32
        last = (j_max * band_scale) >> 32
        mask = ((1 << (last + 1)) - 1) ^ ((1 << first) - 1)
    band_mask[t] = mask


@njit(cache=True, parallel=True)
def _setup_parallel(xy_z, inv_w, triangles, width, height, band_scale, fixed, band_mask):
    for v in prange(xy_z.shape[0]):
        _snap_vertex(xy_z, inv_w, fixed, v)
    for t in prange(triangles.shape[0]):
        _bin_triangle(triangles, fixed, width, height, band_scale, band_mask, t)


@njit(cache=True)
def _setup_serial(xy_z, inv_w, triangles, width, height, band_scale, fixed, band_mask):
    for v in range(xy_z.shape[0]):
        _snap_vertex(xy_z, inv_w, fixed, v)
    for t in range(triangles.shape[0]):
        _bin_triangle(triangles, fixed, width, height, band_scale, band_mask, t)


# --------------------------------------------------------------------------------------------
# Rasterization (lp_rast_tri.c): walk the box, sign test, z-buffer test, barycentrics


@njit(cache=True)
def _scan_triangle(xy_z, inv_w, triangles, fixed, t, band_first, band_last, depth, tri, b1, b2,
                   count_fragments, fragments):
    """Scan-convert triangle t into device rows band_first..band_last (FvDFH 15.4)."""
    height, width = depth.shape
    (boxed, v0, v1, v2, x0, y0, x1, y1, x2, y2,
     i_min, i_max, j_min, j_max) = _triangle_box(triangles, fixed, t, width, height)
    j_min = max(j_min, band_first)
    j_max = min(j_max, band_last)
    if not boxed or j_min > j_max:
        return
    area2, edge0, edge1, edge2 = _triangle_edges(x0, y0, x1, y1, x2, y2)
    if area2 == 0:
        return
    a0, b0, c0, bias0 = edge0
    a1, b1_, c1, bias1 = edge1
    a2, b2_, c2, bias2 = edge2
    inv_area = 1.0 / area2
    z0 = xy_z[v0, 2]
    dz1 = xy_z[v1, 2] - z0
    dz2 = xy_z[v2, 2] - z0
    w0 = inv_w[v0]
    w1 = inv_w[v1]
    w2 = inv_w[v2]
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
                if z > depth[row, i]:
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


@njit(cache=True)
def _scan_band(xy_z, inv_w, triangles, fixed, band_mask, band, rows_per_band, depth, tri, b1,
               b2, count_fragments, fragments):
    """Clear one band of rows, then draw into it every triangle that meets it, in order."""
    height, width = depth.shape
    first = band * rows_per_band
    last = min(height, first + rows_per_band) - 1
    for j in range(first, last + 1):
        row = height - 1 - j
        for i in range(width):
            depth[row, i] = -np.inf
            tri[row, i] = -1
            b1[row, i] = 0.0
            b2[row, i] = 0.0
    bit = np.uint16(1 << band)
    for t in range(triangles.shape[0]):
        if band_mask[t] & bit:
            _scan_triangle(xy_z, inv_w, triangles, fixed, t, first, last, depth, tri, b1, b2,
                           count_fragments, fragments)


@njit(cache=True, parallel=True)
def _scan_parallel(xy_z, inv_w, triangles, fixed, band_mask, n_bands, rows_per_band, depth,
                   tri, b1, b2, count_fragments, fragments):
    # one band per task (the caller sets parallel_chunksize(1) so an idle core takes the next)
    for band in prange(n_bands):
        _scan_band(xy_z, inv_w, triangles, fixed, band_mask, band, rows_per_band, depth, tri,
                   b1, b2, count_fragments, fragments)


@njit(cache=True)
def _scan_serial(xy_z, inv_w, triangles, fixed, band_mask, n_bands, rows_per_band, depth, tri,
                 b1, b2, count_fragments, fragments):
    for band in range(n_bands):
        _scan_band(xy_z, inv_w, triangles, fixed, band_mask, band, rows_per_band, depth, tri,
                   b1, b2, count_fragments, fragments)


# --------------------------------------------------------------------------------------------
# Public entry points

_NO_FRAGMENTS = np.zeros((1, 1), np.int32)


def default_bands(height: int) -> int:
    """Bands for the parallel path: a few per core so a core never waits on a busy band."""
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
    if triangles.size and (triangles.min() < 0 or triangles.max() >= xy_z.shape[0]):
        raise ValueError("triangle vertex index out of range")
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
    fixed, band_mask = out._scratch(xy_z.shape[0], triangles.shape[0])
    count = fragments is not None
    frag = fragments if count else _NO_FRAGMENTS
    if parallel:
        _setup_parallel(xy_z, inv_w, triangles, width, height, band_scale, fixed, band_mask)
        # chunk size 1: bands are handed out one at a time, so the cores balance the load
        with numba.parallel_chunksize(1):
            _scan_parallel(xy_z, inv_w, triangles, fixed, band_mask, n_bands, rows_per_band,
                           out.depth, out.tri, out.b1, out.b2, count, frag)
    else:
        _setup_serial(xy_z, inv_w, triangles, width, height, band_scale, fixed, band_mask)
        _scan_serial(xy_z, inv_w, triangles, fixed, band_mask, n_bands, rows_per_band,
                     out.depth, out.tri, out.b1, out.b2, count, frag)
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
    parallel : draw horizontal bands on all cores; ``False`` runs the single-threaded path
        (one band), whose result is bit-identical.
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
