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

Two stages, as in llvmpipe (``lp_setup_tri.c`` builds a scene and bins it into tiles,
``lp_rast_tri.c`` rasterizes one tile at a time):

* **setup** snaps each vertex to fixed point with ``SUBPIXEL_BITS`` = 8 sub-pixel bits, finds
  each triangle's box of pixel centres (clamped to the framebuffer) and keeps only triangles
  that can draw something: box not empty, and for boxes of at most 2 x 2 pixels at least one
  centre actually covered (in a dense mesh most triangles cover none). Each kept triangle
  goes into the *scene* (its id, fixed-point corners, depths and 1/W) and into the *bin* of
  every 64 x 64 tile its box meets (a big triangle skips the tiles one of its edges misses),
  with its nearest depth beside it. Setup counts the entries per tile, chunk by chunk of the
  triangle array, then writes them, so that each bin lists its front faces (counter-clockwise
  on the screen) in triangle order and then its back faces in triangle order: in a mesh that
  is not closed (whose back faces are drawn) the near side then lands first, and
  hierarchical z rejects most of the far side without visiting its pixels.
* **rast** draws the frame tile by tile, each with its own slice of the z-buffer (a tile's
  depth and ids stay in the core's cache). It orients each triangle counter-clockwise
  (either winding is drawn) and writes each edge as an edge function E(x, y) = A x + B y + C
  whose constant already holds the top-left fill rule, so a pixel centre is inside exactly
  when all three E are >= 0: one sign test (``e0 | e1 | e2 >= 0``). The integers are exact:
  two triangles sharing an edge see the same numbers, so the edge is neither drawn twice nor
  left open. The box is walked in 8 x 8 blocks, row by row, the edge functions stepped by A
  per pixel (FvDFH's incremental scan line, in integers). Depth is interpolated linearly in
  screen space (after the perspective-to-parallel divide it is an affine function of x and y,
  FvDFH 6.5.4) and tested as the notes write it, ``z >= zbuffer``: on a tie the later
  triangle wins. The rast does not draw in triangle order (front faces first, or last to
  first), so it settles a tie by the triangle ids, the later one winning: the same winner as
  the notes' test in triangle order. Barycentrics are perspective-corrected with 1/W.
* **hierarchical z**: once every pixel of an 8 x 8 block has been written, the block keeps its
  farthest depth (its *coarse z*), and once every block of a tile is full, the tile keeps the
  farthest of those. Depths only grow during a frame, so these stay lower bounds: a triangle
  whose nearest vertex is behind the tile's coarse z is dropped reading its bin entry alone,
  and one behind a block's is not visited in that block. A tile whose later triangles look
  nearer (a back-to-front stream) is drawn last to first (its front faces, then its back
  faces), which picks the same winner at every pixel, ties included, and lets the near
  surface land first.
  So depth complexity costs close to the visible pixels plus a few nanoseconds per hidden
  triangle.
* **early z in setup**: a frame of ``BATCH_FROM`` triangles or more goes in two batches, the
  first 1/64 of the stream and then the rest (a stream whose later triangles look nearer
  starts from its end, every tile drawing last to first). Once the first batch has filled
  tiles, the second batch's setup drops a triangle behind the coarse z of every tile its box
  meets, before it takes a scene slot or a bin entry: in a deep stack the hidden triangles
  cost one box and one comparison each.

Both cores: setup works on chunks of the triangle array, rast on tiles. numba's threading
layers here (OpenMP, and its own workqueue) give each thread one contiguous block of a
``prange``'s items, whatever ``numba.parallel_chunksize`` asks, so the tiles are dealt
(:func:`_dealt`) so that each core's block holds tiles of both halves of the screen. A pixel's
winner depends only on the triangles of its tile's bin, which is the same list whatever the
number of threads, so the result of the single-threaded path
(``parallel=False``) is bit-identical.

**Unsigned indices.** numba lets a signed index count from the end of its axis, as Python
does, and so compares every signed index with zero and corrects it: a compare and a select
per index, per array. The hot loops index with ``np.uint64`` values, which have no negative
form (their arithmetic stays signed: numba would make int64 and uint64 mixed a float). On the
bunny at 500 x 500, one core: setup 0.96x, binning 0.76x, the rast 0.92x as long, the same
buffers.

Vertices far outside the framebuffer are safe: coordinates are clamped to ``COORD_LIMIT``
pixels before the fixed-point conversion (so no product overflows int64) and boxes are clamped
to the framebuffer. A triangle with a non-finite coordinate or a 1/W that is not positive and
finite is skipped (the clipper never produces one); a vertex index out of range raises.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from core.arrays import read_only
from core.jit import njit, prange
from core.prefetch import prefetch

SUBPIXEL_BITS = 8
SUBPIXEL_ONE = 1 << SUBPIXEL_BITS  # one pixel in fixed point
PIXEL_CENTRE = SUBPIXEL_ONE // 2  # a pixel centre sits half a pixel in
# |x|, |y| are clamped to this many pixels: fixed-point coordinates stay below 2^28 (int32),
# edge coefficients below 2^29 and edge constants below 2^59, all inside int64.
COORD_LIMIT = float(1 << 20)
INVALID = np.int32(np.iinfo(np.int32).min)  # fixed x of a vertex no triangle may use
MAX_SIZE = 1 << 15  # framebuffer width and height limit
TILE_BITS = 6
TILE = 1 << TILE_BITS  # 64 x 64 pixel tiles: the unit of parallel work, and its z-buffer fits in L2
BLOCK_BITS = 3
BLOCK = 1 << BLOCK_BITS  # 8 x 8 pixel blocks inside a tile, each with a coarse z
N_BLOCKS = (TILE // BLOCK) ** 2  # blocks per tile; coarse-z entry N_BLOCKS is the tile's
SETUP_CHUNKS = 64  # pieces of the triangle array that setup hands to the cores
PARALLEL_SETUP = 10_000  # fewer triangles than this are set up on one core
HIERARCHICAL_Z = True  # skip hidden triangles by tile and by block (the bench compares both)
# From this many triangles the frame is set up and rasterized in two batches (the first 1/64
# of the triangles, then the rest): once tiles are full, a triangle of the second batch that
# lies behind the coarse z of every tile its box meets is dropped in setup, before it costs a
# scene slot, a bin entry or a second look. Deep stacks of layers then cost close to one.
BATCH_FROM = 200_000
FIRST_BATCH = 64            # the first batch: this fraction (1/64) of the triangles
COUNT_CELLS = 1 << 20  # at most this many (chunk, bin half) counters: huge frames get fewer chunks
PREFETCH = 8           # the rast asks for the scene slot of the bin entry this far ahead


@dataclass
class _Scene:
    """Setup's output, rast's input: the triangles that can draw, and each tile's bin.

    Chunk c covers triangles [c T / n, (c + 1) T / n) and writes its kept triangles from slot
    c T / n on, in triangle order, up to ``chunk_end[c]``. Tile k's bin is
    ``bins[tile_start[k]:tile_start[k + 1]]``: the slots of the triangles that may draw into
    it, in triangle order. Capacity grows on demand and is kept from frame to frame.
    """

    fixed: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int32))  # (V, 2)
    tri: np.ndarray = field(default_factory=lambda: np.empty(0, np.int32))  # triangle id
    xy: np.ndarray = field(default_factory=lambda: np.empty((0, 6), np.int32))  # fixed x0..y2
    zw: np.ndarray = field(default_factory=lambda: np.empty((0, 6)))  # z0, z1, z2, 1/W0..2
    chunk_end: np.ndarray = field(default_factory=lambda: np.empty(SETUP_CHUNKS, np.int64))
    # per chunk, the front faces' depth sum and count, then the back faces': do the front
    # faces lie nearer (a mesh wound one way), so that drawing them first pays?
    sides: np.ndarray = field(default_factory=lambda: np.empty((SETUP_CHUNKS, 4)))
    # (chunk, 2 tile + 1 for a back face): the entries a chunk puts in each half of each bin
    counts: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    tile_start: np.ndarray = field(default_factory=lambda: np.empty(1, np.int64))
    # per tile, the first entry of its bin that is a back face (its front faces come before)
    tile_split: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    tile_rows: np.ndarray = field(default_factory=lambda: np.empty((0, TILE, 2), np.int32))
    bins: np.ndarray = field(default_factory=lambda: np.empty(0, np.int32))
    bin_z: np.ndarray = field(default_factory=lambda: np.empty(0))  # each entry's nearest z
    # per tile, kept from batch to batch: each block's unwritten pixels and coarse z (entry
    # N_BLOCKS: the tile's unfilled blocks and coarse z)
    tile_unfilled: np.ndarray = field(default_factory=lambda: np.empty((0, N_BLOCKS + 1), np.int32))
    tile_zmin: np.ndarray = field(default_factory=lambda: np.empty((0, N_BLOCKS + 1)))
    hidden_in: np.ndarray = field(default_factory=lambda: np.empty(0, np.int32))  # (V,)

    def reserve(self, n_vertices: int, n_triangles: int, n_chunks: int = 1,
                n_tiles: int = 0) -> None:
        if self.fixed.shape[0] < n_vertices:
            self.fixed = np.empty((max(n_vertices, 2 * self.fixed.shape[0]), 2), np.int32)
            self.hidden_in = np.empty(self.fixed.shape[0], np.int32)
        if self.tri.shape[0] < n_triangles:
            n = max(n_triangles, 2 * self.tri.shape[0])
            self.tri = np.empty(n, np.int32)
            self.xy = np.empty((n, 6), np.int32)
            self.zw = np.empty((n, 6))
        if self.counts.shape[0] < n_chunks * 2 * n_tiles:
            self.counts = np.empty(n_chunks * 2 * n_tiles, np.int64)
        if self.tile_start.shape[0] < n_tiles + 1:
            self.tile_start = np.empty(n_tiles + 1, np.int64)
            self.tile_split = np.empty(n_tiles, np.int64)
            self.tile_rows = np.empty((n_tiles, TILE, 2), np.int32)
            self.tile_unfilled = np.empty((n_tiles, N_BLOCKS + 1), np.int32)
            self.tile_zmin = np.empty((n_tiles, N_BLOCKS + 1))

    def reserve_bins(self, n_entries: int) -> None:
        if self.bins.shape[0] < n_entries:
            self.bins = np.empty(max(n_entries, 2 * self.bins.shape[0]), np.int32)
            self.bin_z = np.empty(self.bins.shape[0])


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
    # written (first > last: none; the columns of the boxes drawn in the row). Outside its
    # span a row is empty. The next frame clears only the
    # spans and the resolve shades only them: at 1k triangles most of the 500 x 500 pixels
    # are never touched. ``spans_known`` False (a buffer written by anyone else) makes the
    # next rasterize() clear every row.
    span: np.ndarray | None = None
    spans_known: bool = False
    # False when the last rasterize() was asked not to find b1 and b2 (they hold old values)
    barycentrics: bool = True

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
def _back_face(x0, y0, x1, y1, x2, y2):
    """1 for a triangle clockwise on the screen (y up: a back face of a mesh wound
    counter-clockwise seen from outside), else 0: which half of a bin it goes in."""
    return np.int64((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0) < 0)


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
# Setup (lp_setup_tri.c): fixed point, boxes, culling, binning into tiles


@njit(cache=True)
def _snap_vertices(xy_z, inv_w, fixed, first, end):
    """Fixed-point x, y of vertices first..end-1, or INVALID for one no triangle may use."""
    for v_ in range(first, end):
        v = np.uint64(v_)
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
def _edge_misses_box(a, b, c, i0, i1, j0, j1):
    """Is the (biased) edge function negative at every pixel centre of columns i0..i1, device
    rows j0..j1? It is affine, so its largest value over the box is at a corner."""
    x = (i1 if a > 0 else i0) * SUBPIXEL_ONE + PIXEL_CENTRE
    y = (j1 if b > 0 else j0) * SUBPIXEL_ONE + PIXEL_CENTRE
    return a * x + b * y + c < 0


@njit(cache=True)
def _misses_box(x0, y0, x1, y1, x2, y2, i0, i1, j0, j1):
    """Does the triangle cover no pixel centre of the box (one of its edges misses it all)?

    Conservative: False may still mean no centre is covered."""
    area2, edge0, edge1, edge2 = _triangle_edges(x0, y0, x1, y1, x2, y2)
    return (area2 == 0 or _edge_misses_box(edge0[0], edge0[1], edge0[2], i0, i1, j0, j1)
            or _edge_misses_box(edge1[0], edge1[1], edge1[2], i0, i1, j0, j1)
            or _edge_misses_box(edge2[0], edge2[1], edge2[2], i0, i1, j0, j1))


@njit(cache=True)
def _tile_is_hit(x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max, tx, ty, several):
    """Does a triangle whose box spans ``several`` tiles both ways possibly cover tile (tx, ty)?
    (A long thin diagonal triangle's box holds many tiles it never touches.)"""
    if not several:
        return True
    i0 = max(i_min, tx << TILE_BITS)
    i1 = min(i_max, ((tx + 1) << TILE_BITS) - 1)
    j0 = max(j_min, ty << TILE_BITS)
    j1 = min(j_max, ((ty + 1) << TILE_BITS) - 1)
    return not _misses_box(x0, y0, x1, y1, x2, y2, i0, i1, j0, j1)


@njit(cache=True)
def _behind_tiles(z_near, i_min, i_max, j_min, j_max, n_tiles_x, tile_zmin, later_first):
    """Is a triangle whose depth is at most ``z_near`` hidden in every tile its pixel box
    meets? (A tile's coarse z is -inf until all its pixels are written.)"""
    for ty in range(j_min >> TILE_BITS, (j_max >> TILE_BITS) + 1):
        for tx in range(i_min >> TILE_BITS, (i_max >> TILE_BITS) + 1):
            if not _hidden(z_near, tile_zmin[np.uint64(ty * n_tiles_x + tx), N_BLOCKS],
                           later_first):
                return False
    return True


@njit(cache=True, parallel=True, nogil=True)
def _hidden_vertices(xy_z, fixed, n_tiles_x, width, height, tile_zmin, later_first, margin,
                     hidden_in):
    """Per vertex, the tile it lies in when it is behind that tile's coarse z (else -1). A
    triangle whose three corners are hidden in one tile lies inside it (a tile is convex) and
    is hidden there: its depth bound (:func:`_nearest`) is at most its largest corner depth
    plus ``margin`` (3e-9 times the largest |z| of the frame)."""
    n = xy_z.shape[0]
    for chunk in prange(SETUP_CHUNKS):
        for v_ in range(chunk * n // SETUP_CHUNKS, (chunk + 1) * n // SETUP_CHUNKS):
            v = np.uint64(v_)
            hidden_in[v] = -1
            x, y = np.int64(fixed[v, 0]), np.int64(fixed[v, 1])
            if x == INVALID or x < 0 or y < 0 or x >= width << SUBPIXEL_BITS \
                    or y >= height << SUBPIXEL_BITS:
                continue
            k = (y >> (SUBPIXEL_BITS + TILE_BITS)) * n_tiles_x + (x >> (SUBPIXEL_BITS + TILE_BITS))
            if _hidden(xy_z[v, 2] + margin, tile_zmin[np.uint64(k), N_BLOCKS], later_first):
                hidden_in[v] = k


# numpy's error model, as in the parallel loops that call it with their index: one
# compiled form for both (core.jit.reuse_plain_overloads)
@njit(cache=True, error_model="numpy")
def _setup_chunk(xy_z, inv_w, triangles, width, height, n_tiles_x, fixed, chunk, n_chunks,
                 s_tri, s_xy, s_zw, chunk_end, counts, sides, offset, tile_zmin, early_z,
                 later_first, hidden_in):
    """Put the triangles of one chunk that can draw something into the scene, in order, and
    count how many of them each tile will draw (``counts[chunk, 2 tile]`` the front faces,
    ``counts[chunk, 2 tile + 1]`` the back faces: :func:`_back_face`), and sum each side's
    corner depths (``sides[chunk]``: front sum and count, back sum and count). ``triangles`` is a
    batch starting at triangle ``offset``; with ``early_z`` a triangle behind the coarse z of
    every tile its box meets (the batches before drew there) is dropped here; first, cheaply,
    one whose three corners are hidden in one tile (``hidden_in``, :func:`_hidden_vertices`).

    Returns how many triangles name a vertex that does not exist (they are never drawn).
    """
    n = triangles.shape[0]
    first = chunk * n // n_chunks
    slot = first
    bad = 0
    n_vertices = fixed.shape[0]
    counts[chunk, :] = 0
    front_z = back_z = 0.0
    n_back = 0
    for t_ in range(first, (chunk + 1) * n // n_chunks):
        t = np.uint64(t_)
        v0 = triangles[t, 0]
        v1 = triangles[t, 1]
        v2 = triangles[t, 2]
        if min(v0, v1, v2) < 0 or max(v0, v1, v2) >= n_vertices:
            bad += 1
            continue
        v0, v1, v2 = np.uint64(v0), np.uint64(v1), np.uint64(v2)
        if early_z and hidden_in[v0] >= 0 and hidden_in[v1] == hidden_in[v0] \
                and hidden_in[v2] == hidden_in[v0]:
            continue  # three corners hidden in one tile: the triangle is (the common case)
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
        if early_z and _behind_tiles(_nearest(xy_z[v0, 2], xy_z[v1, 2], xy_z[v2, 2]),
                                     i_min, i_max, j_min, j_max, n_tiles_x, tile_zmin,
                                     later_first):
            continue  # hidden behind what earlier batches drew
        if i_max - i_min <= 1 and j_max - j_min <= 1:
            if not _quad_covers(x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max):
                continue  # a small triangle between pixel centres: most of a dense mesh
        tx0, tx1 = i_min >> TILE_BITS, i_max >> TILE_BITS
        ty0, ty1 = j_min >> TILE_BITS, j_max >> TILE_BITS
        several = tx1 > tx0 and ty1 > ty0
        back = _back_face(x0, y0, x1, y1, x2, y2)
        for ty in range(ty0, ty1 + 1):
            for tx in range(tx0, tx1 + 1):
                if _tile_is_hit(x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max, tx, ty,
                                several):
                    counts[chunk, np.uint64(2 * (ty * n_tiles_x + tx) + back)] += 1
        depth = xy_z[v0, 2] + xy_z[v1, 2] + xy_z[v2, 2]
        front_z += depth * (1 - back)
        back_z += depth * back
        n_back += back
        at = np.uint64(slot)
        s_tri[at] = offset + t_
        s_xy[at, 0] = x0
        s_xy[at, 1] = y0
        s_xy[at, 2] = x1
        s_xy[at, 3] = y1
        s_xy[at, 4] = x2
        s_xy[at, 5] = y2
        s_zw[at, 0] = xy_z[v0, 2]
        s_zw[at, 1] = xy_z[v1, 2]
        s_zw[at, 2] = xy_z[v2, 2]
        s_zw[at, 3] = inv_w[v0]
        s_zw[at, 4] = inv_w[v1]
        s_zw[at, 5] = inv_w[v2]
        slot += 1
    chunk_end[chunk] = slot
    sides[chunk, 0], sides[chunk, 1] = front_z, slot - first - n_back
    sides[chunk, 2], sides[chunk, 3] = back_z, n_back
    return bad


@njit(cache=True)
def _nearest(z0, z1, z2):
    """A bound on the depth the rast interpolates inside a triangle: its nearest vertex's,
    plus more than the rounding of the interpolation."""
    return max(z0, z1, z2) + 1e-9 * (abs(z0) + abs(z1) + abs(z2))


@njit(cache=True, error_model="numpy")
def _bin_chunk(width, height, n_triangles, n_tiles_x, chunk, n_chunks, s_xy, s_zw, chunk_end,
               cursor, bins, bin_z, partition):
    """Append the chunk's scene slots to the bins of the tiles they draw into: the same tiles
    :func:`_setup_chunk` counted, written from the chunk's cursor in each bin. Each entry
    carries the triangle's nearest depth, so that the rast rejects a hidden triangle reading
    the bin alone, in order (its scene slot may be far away in memory). With ``partition``
    the front faces go in the first half of each bin and the back faces in the second."""
    for slot_ in range(chunk * n_triangles // n_chunks, chunk_end[chunk]):
        slot = np.uint64(slot_)
        z_near = _nearest(s_zw[slot, 0], s_zw[slot, 1], s_zw[slot, 2])
        x0 = np.int64(s_xy[slot, 0])
        y0 = np.int64(s_xy[slot, 1])
        x1 = np.int64(s_xy[slot, 2])
        y1 = np.int64(s_xy[slot, 3])
        x2 = np.int64(s_xy[slot, 4])
        y2 = np.int64(s_xy[slot, 5])
        i_min, i_max, j_min, j_max = _pixel_box(x0, y0, x1, y1, x2, y2, width, height)
        tx0, tx1 = i_min >> TILE_BITS, i_max >> TILE_BITS
        ty0, ty1 = j_min >> TILE_BITS, j_max >> TILE_BITS
        several = tx1 > tx0 and ty1 > ty0
        back = _back_face(x0, y0, x1, y1, x2, y2) if partition else 0
        for ty in range(ty0, ty1 + 1):
            for tx in range(tx0, tx1 + 1):
                if _tile_is_hit(x0, y0, x1, y1, x2, y2, i_min, i_max, j_min, j_max, tx, ty,
                                several):
                    k = np.uint64(2 * (ty * n_tiles_x + tx) + back)
                    at = np.uint64(cursor[chunk, k])
                    bins[at] = slot_
                    bin_z[at] = z_near
                    cursor[chunk, k] += 1


@njit(cache=True, nogil=True)
def _bin_offsets(counts, tile_start, tile_split, partition):
    """Turn the per-chunk counts into write cursors, bin by bin, chunk by chunk within a bin,
    so that each bin lists its triangles in triangle order; with ``partition`` its front faces
    and then (from ``tile_split``) its back faces, each half in triangle order. Without, the
    two halves' counts are one, at the front faces' cursor. Returns the total."""
    n_chunks = counts.shape[0]
    n_tiles = counts.shape[1] // 2
    total = 0
    for k in range(n_tiles):
        tile_start[k] = total
        for back in range(2):
            if back:
                tile_split[k] = total
                if not partition:
                    break
            for c in range(n_chunks):
                here = counts[c, 2 * k + back]
                if not partition:
                    here += counts[c, 2 * k + 1]
                counts[c, 2 * k + back] = total
                total += here
    tile_start[n_tiles] = total
    return total


@njit(cache=True, parallel=True, nogil=True)
def _setup_parallel(xy_z, inv_w, triangles, width, height, n_tiles_x, fixed, s_tri, s_xy,
                    s_zw, chunk_end, counts, sides, snap, offset, tile_zmin, early_z,
                    later_first, hidden_in):
    n_chunks = chunk_end.shape[0]
    if snap:                    # (about 1 ms for 500k vertices on one core)
        n_vertices = xy_z.shape[0]
        for chunk in prange(n_chunks):
            _snap_vertices(xy_z, inv_w, fixed, chunk * n_vertices // n_chunks,
                           (chunk + 1) * n_vertices // n_chunks)
    bad = 0
    for chunk in prange(n_chunks):
        bad += _setup_chunk(xy_z, inv_w, triangles, width, height, n_tiles_x, fixed, chunk,
                            n_chunks, s_tri, s_xy, s_zw, chunk_end, counts, sides, offset,
                            tile_zmin, early_z, later_first, hidden_in)
    return bad


@njit(cache=True, nogil=True)
def _setup_serial(xy_z, inv_w, triangles, width, height, n_tiles_x, fixed, s_tri, s_xy,
                  s_zw, chunk_end, counts, sides, snap, offset, tile_zmin, early_z, later_first,
                  hidden_in):
    if snap:
        _snap_vertices(xy_z, inv_w, fixed, 0, xy_z.shape[0])
    bad = 0
    for chunk in range(chunk_end.shape[0]):
        bad += _setup_chunk(xy_z, inv_w, triangles, width, height, n_tiles_x, fixed, chunk,
                            chunk_end.shape[0], s_tri, s_xy, s_zw, chunk_end, counts, sides,
                            offset, tile_zmin, early_z, later_first, hidden_in)
    return bad


@njit(cache=True, parallel=True, nogil=True)
def _bin_parallel(width, height, n_triangles, n_tiles_x, s_xy, s_zw, chunk_end, cursor, bins,
                  bin_z, partition):
    n_chunks = chunk_end.shape[0]
    for chunk in prange(n_chunks):
        _bin_chunk(width, height, n_triangles, n_tiles_x, chunk, n_chunks, s_xy, s_zw,
                   chunk_end, cursor, bins, bin_z, partition)


@njit(cache=True, nogil=True)
def _bin_serial(width, height, n_triangles, n_tiles_x, s_xy, s_zw, chunk_end, cursor, bins,
                bin_z, partition):
    n_chunks = chunk_end.shape[0]
    for chunk in range(n_chunks):
        _bin_chunk(width, height, n_triangles, n_tiles_x, chunk, n_chunks, s_xy, s_zw,
                   chunk_end, cursor, bins, bin_z, partition)


# --------------------------------------------------------------------------------------------
# Rasterization (lp_rast_tri.c): one tile at a time, 8 x 8 blocks with a coarse z each



@njit(cache=True)
def _block_zmin(depth, row_top, row_bottom, i0, i1):
    """The farthest depth in a block (rows row_top..row_bottom, columns i0..i1)."""
    zmin = np.inf
    for row in range(row_top, row_bottom + 1):
        for i in range(i0, i1 + 1):
            zmin = min(zmin, depth[row, i])
    return zmin


@njit(cache=True)
def _block_filled(b, bi, bj, ti1, tj1, depth, zmin, unfilled):
    """Block b has just had its last empty pixel written: its coarse z becomes its farthest
    depth, and once every block of the tile is full, the tile's coarse z ``zmin[N_BLOCKS]``
    the farthest of the blocks'. Later writes only bring pixels nearer, so these values stay
    true lower bounds for the rest of the frame without being recomputed."""
    height = depth.shape[0]
    i0 = bi << BLOCK_BITS
    j0 = bj << BLOCK_BITS
    zmin[b] = _block_zmin(depth, height - 1 - min(j0 + BLOCK - 1, tj1), height - 1 - j0, i0,
                          min(i0 + BLOCK - 1, ti1))
    unfilled[N_BLOCKS] -= 1
    if unfilled[N_BLOCKS] == 0:
        farthest = zmin[0]              # a loop, not zmin.min(): numpy's min would make
        for k in range(1, N_BLOCKS):    # every process import numba.np.arraymath (60 ms)
            farthest = min(farthest, zmin[k])   # to load this kernel from the cache
        zmin[N_BLOCKS] = farthest


@njit(cache=True)
def _hidden(z_near, coarse, later_first):
    """Is a triangle whose depth is at most z_near hidden behind a coarse z? (A tie goes to
    the later triangle: in triangle order a tie draws; when every triangle drawn so far comes
    later, ``later_first``, it does not.)"""
    return z_near < coarse or (later_first and z_near == coarse)


@njit(cache=True)
def _behind_blocks(z_near, i_min, i_max, j_min, j_max, tbi, tbj, zmin, later_first):
    """Is a triangle whose depth is at most ``z_near`` hidden in every 8 x 8 block of its
    pixel box (columns i_min..i_max, device rows j_min..j_max, inside the tile whose first
    block is (tbi, tbj))? Then the rast need not set it up at all: in a scan's far side,
    drawn after its near side, three triangles in four."""
    for bj in range(j_min >> BLOCK_BITS, (j_max >> BLOCK_BITS) + 1):
        for bi in range(i_min >> BLOCK_BITS, (i_max >> BLOCK_BITS) + 1):
            b = np.uint64(((bj - tbj) << (TILE_BITS - BLOCK_BITS)) + bi - tbi)
            if not _hidden(z_near, zmin[b], later_first):
                return False
    return True


@njit(cache=True)
def _entry(n, start, split, end, later_first):
    """The bin entry a tile draws n-th: its front faces (``start .. split``), then its back
    faces (``split .. end``), each half in triangle order or, ``later_first``, last to first."""
    if not later_first:
        return start + n
    if n < split - start:
        return split - 1 - n
    return end - 1 - (n - (split - start))


@njit(cache=True)
def _later_first(bin_z, start, end):
    """Should the tile draw its triangles last to first? Yes when the later ones look nearer
    (a back-to-front stream): then the near surfaces land first and hierarchical z rejects the
    rest. Either order gives the same picture; this only picks the faster one, from a sample
    of 16 triangles of each half of the bin."""
    n = end - start
    if n < 8:
        return False
    half = n // 2
    step = max(1, half // 16)
    early = 0.0
    late = 0.0
    for k in range(0, half, step):
        early += bin_z[start + k]
        late += bin_z[start + half + k]
    return late > early


@njit(cache=True, error_model="numpy")
def _clear_tile(k, ti0, ti1, tj0, tj1, depth, tri, span, tile_rows, unfilled, zmin):
    """Empty what the last frame wrote in tile k, and start its blocks: per 8 x 8 block (and,
    at index N_BLOCKS, the tile) the pixels (blocks) not yet written, and the coarse z, -inf
    until every pixel has been written."""
    height, width = depth.shape
    for j in range(tj0, tj1 + 1):
        row = np.uint64(height - 1 - j)
        for i in range(max(span[row, 0], ti0), min(span[row, 1], ti1) + 1):
            depth[row, np.uint64(i)] = -np.inf
            tri[row, np.uint64(i)] = -1
    tile_rows[k, :, 0] = width
    tile_rows[k, :, 1] = -1
    side = TILE // BLOCK
    zmin[:] = -np.inf
    unfilled[N_BLOCKS] = 0
    for bj in range(side):
        for bi in range(side):
            w = min(BLOCK, max(0, ti1 + 1 - ti0 - bi * BLOCK))
            h = min(BLOCK, max(0, tj1 + 1 - tj0 - bj * BLOCK))
            unfilled[bj * side + bi] = w * h
            unfilled[N_BLOCKS] += w * h > 0
            if w * h == 0:
                zmin[bj * side + bi] = np.inf  # outside the frame: never in the way


@njit(cache=True, error_model="numpy")
def _scan_tile(k, n_tiles_x, bins, bin_z, tile_start, tile_split, s_tri, s_xy, s_zw, depth,
               tri, b1, b2, span, tile_rows, hiz, count_fragments, fragments, first, order,
               tile_unfilled, tile_zmin, barycentrics):
    """Clear one tile, then draw into it every triangle of its bin, 8 x 8 block by block.

    Hierarchical z: a triangle whose nearest vertex lies behind the tile's coarse z, or a
    block's, is not visited there at all. The bin's front faces come first, then its back
    faces (:func:`_entry`); with ``later_first`` each half comes last to first. A tie at a
    pixel goes to the larger triangle id, whatever the order: the same pixel wins as in
    triangle order with ``z >= zbuffer``.

    Only what the last frame wrote is cleared (each row's span; the rest of the row is still
    empty), and only depth and tri: b1 and b2 mean nothing where tri is -1 and nobody reads
    them there. ``tile_rows[k]`` gets, per row of the tile, the columns of the boxes drawn.

    In batches (``first`` false after the first), the tile goes on where the last batch left
    it: nothing is cleared, and its blocks' counts and coarse z live on in
    ``tile_unfilled[k]`` and ``tile_zmin[k]``. ``order``: 0 the bin as given, 1 last to first
    (the whole stream is drawn backwards), -1 the tile decides (one batch).
    ``barycentrics`` False: b1 and b2 are not written (flat shading reads the ids alone)."""
    height, width = depth.shape
    ti0 = (k % n_tiles_x) << TILE_BITS
    tj0 = (k // n_tiles_x) << TILE_BITS
    ti1 = min(ti0 + TILE, width) - 1
    tj1 = min(tj0 + TILE, height) - 1
    unfilled = tile_unfilled[k]
    zmin = tile_zmin[k]
    if first:
        _clear_tile(k, ti0, ti1, tj0, tj1, depth, tri, span, tile_rows, unfilled, zmin)
    start = tile_start[k]
    end = tile_start[k + 1]
    split = tile_split[k]
    if order < 0:           # the front faces decide, when there are enough of them
        later_first = hiz and _later_first(bin_z, start, split if split - start >= 8 else end)
    else:
        later_first = order == 1
    # with both halves, a back face may come later than a front face drawn before it: a
    # tie at a coarse z no longer tells
    ties_hidden = later_first and (split == start or split == end)
    for n in range(end - start):
        entry = _entry(n, start, split, end, later_first)
        at = np.uint64(entry)
        if hiz and _hidden(bin_z[at], zmin[N_BLOCKS], ties_hidden):
            continue  # behind everything in the tile: the common case deep in a stack of layers
        # Scan-convert the triangle into the tile, 8 x 8 block by block. (Written out here,
        # not called: a call passing the arrays costs two atomic reference counts per array
        # per triangle, more than the pixels of a small triangle.)
        ahead = entry - PREFETCH if later_first else entry + PREFETCH
        if start <= ahead < end:        # a gather from megabytes: ask for it early (near
            prefetch(s_xy, bins[ahead])   # the split, maybe for the wrong half: no harm)
            prefetch(s_zw, bins[ahead])
            prefetch(s_tri, bins[ahead])
        slot = np.uint64(bins[at])
        z_near = bin_z[at]
        x0 = np.int64(s_xy[slot, 0])
        y0 = np.int64(s_xy[slot, 1])
        x1 = np.int64(s_xy[slot, 2])
        y1 = np.int64(s_xy[slot, 3])
        x2 = np.int64(s_xy[slot, 4])
        y2 = np.int64(s_xy[slot, 5])
        i_min, i_max, j_min, j_max = _pixel_box(x0, y0, x1, y1, x2, y2, width, height)
        i_min = max(i_min, ti0)
        i_max = min(i_max, ti1)
        j_min = max(j_min, tj0)
        j_max = min(j_max, tj1)
        if j_min > j_max or i_min > i_max:
            continue
        tbi = ti0 >> BLOCK_BITS
        tbj = tj0 >> BLOCK_BITS
        if hiz and _behind_blocks(z_near, i_min, i_max, j_min, j_max, tbi, tbj, zmin,
                                  ties_hidden):
            continue  # behind every block its box meets (a small one: one or two blocks)
        t = s_tri[slot]
        z0 = s_zw[slot, 0]
        z1 = s_zw[slot, 1]
        z2 = s_zw[slot, 2]
        for j in range(j_min, j_max + 1):
            r = np.uint64(j - tj0)
            tile_rows[k, r, 0] = min(tile_rows[k, r, 0], i_min)
            tile_rows[k, r, 1] = max(tile_rows[k, r, 1], i_max)
        area2, edge0, edge1, edge2 = _triangle_edges(x0, y0, x1, y1, x2, y2)
        if area2 == 0:
            continue
        a0, b0, c0, bias0 = edge0
        a1, b1_, c1, bias1 = edge1
        a2, b2_, c2, bias2 = edge2
        inv_area = 1.0 / area2
        dz1 = z1 - z0
        dz2 = z2 - z0
        w0 = s_zw[slot, 3]
        w1 = s_zw[slot, 4]
        w2 = s_zw[slot, 5]
        big = (i_max - i_min > BLOCK) or (j_max - j_min > BLOCK)
        for bj in range(j_min >> BLOCK_BITS, (j_max >> BLOCK_BITS) + 1):
            cj0 = max(j_min, bj << BLOCK_BITS)
            cj1 = min(j_max, ((bj + 1) << BLOCK_BITS) - 1)
            for bi in range(i_min >> BLOCK_BITS, (i_max >> BLOCK_BITS) + 1):
                ci0 = max(i_min, bi << BLOCK_BITS)
                ci1 = min(i_max, ((bi + 1) << BLOCK_BITS) - 1)
                b = np.uint64(((bj - tbj) << (TILE_BITS - BLOCK_BITS)) + bi - tbi)
                if hiz and _hidden(z_near, zmin[b], ties_hidden):
                    continue  # hidden behind everything already in the block
                if big and (_edge_misses_box(a0, b0, c0, ci0, ci1, cj0, cj1)
                            or _edge_misses_box(a1, b1_, c1, ci0, ci1, cj0, cj1)
                            or _edge_misses_box(a2, b2_, c2, ci0, ci1, cj0, cj1)):
                    continue  # the block lies outside one edge
                filled = 0
                px = ci0 * SUBPIXEL_ONE + PIXEL_CENTRE
                for j in range(cj0, cj1 + 1):
                    py = j * SUBPIXEL_ONE + PIXEL_CENTRE
                    e0 = a0 * px + b0 * py + c0
                    e1 = a1 * px + b1_ * py + c1
                    e2 = a2 * px + b2_ * py + c2
                    row = np.uint64(height - 1 - j)  # image order: row 0 is the top
                    entered = False
                    for i_ in range(ci0, ci1 + 1):
                        i = np.uint64(i_)
                        if (e0 | e1 | e2) >= 0:  # inside all three edges, fill rule included
                            entered = True
                            if count_fragments:
                                fragments[row, i] += 1
                            # unbiased edge values: exact integers, the screen-space
                            # barycentrics * area2
                            l1 = float(e1 + bias1)
                            l2 = float(e2 + bias2)
                            # depth is affine in screen space
                            z = z0 + (l1 * dz1 + l2 * dz2) * inv_area
                            old = depth[row, i]
                            # the notes' test z >= zbuffer: a tie goes to the later triangle
                            if z > old or (z == old and t > tri[row, i]):
                                filled += old == -np.inf
                                depth[row, i] = z
                                tri[row, i] = t
                                if barycentrics:
                                    # perspective correction: weights ~ lambda_k / W_k,
                                    # renormalised
                                    p0 = float(e0 + bias0) * w0
                                    p1 = l1 * w1
                                    p2 = l2 * w2
                                    s = 1.0 / (p0 + p1 + p2)
                                    b1[row, i] = p1 * s
                                    b2[row, i] = p2 * s
                        elif entered:
                            break  # a triangle is convex: once the row has left it, it is done
                        e0 += a0 * SUBPIXEL_ONE  # one pixel to the right
                        e1 += a1 * SUBPIXEL_ONE
                        e2 += a2 * SUBPIXEL_ONE
                if filled:
                    unfilled[b] -= filled
                    if unfilled[b] == 0:
                        _block_filled(b, bi, bj, ti1, tj1, depth, zmin, unfilled)


@njit(cache=True)
def _merge_spans(n_tiles_x, tile_rows, span):
    """Each image row's span: the columns the tiles of its tile row drew in it."""
    height = span.shape[0]
    for j in range(height):
        ty = j >> TILE_BITS
        lo = np.int32(1 << 30)
        hi = np.int32(-1)
        for tx in range(n_tiles_x):
            k = ty * n_tiles_x + tx
            lo = min(lo, tile_rows[k, j - (ty << TILE_BITS), 0])
            hi = max(hi, tile_rows[k, j - (ty << TILE_BITS), 1])
        span[height - 1 - j, 0] = lo
        span[height - 1 - j, 1] = hi


@njit(cache=True)
def _dealt(n, n_tiles):
    """The tile that the rast's n-th item draws: the tiles of the screen's top and bottom
    halves (by tile index) alternately, each half in row order. numba hands each of two
    threads one contiguous block of the items, so each core draws rows of tiles from both
    halves of the screen (in row order, one core had the top of a model and the other its
    bottom). On the bunny (2 cores), row order took 1.05-1.06x as long at 500 x 500 and
    1.1-1.16x at 1580 x 1080. A deal with a stride of 1/φ of the screen was as fast on the
    bunny, but took 1.11x as long as row order on a layer that fills the screen."""
    return n // 2 + (n % 2) * ((n_tiles + 1) // 2)


@njit(cache=True, parallel=True, nogil=True)
def _rast_parallel(n_tiles_x, bins, bin_z, tile_start, tile_split, s_tri, s_xy, s_zw, depth,
                   tri, b1, b2, span, tile_rows, hiz, count_fragments, fragments, first, last,
                   order, tile_unfilled, tile_zmin, barycentrics):
    n_tiles = tile_rows.shape[0]
    for n in prange(n_tiles):
        _scan_tile(_dealt(n, n_tiles), n_tiles_x, bins, bin_z, tile_start, tile_split, s_tri,
                   s_xy, s_zw, depth, tri, b1, b2, span, tile_rows, hiz, count_fragments,
                   fragments, first, order, tile_unfilled, tile_zmin, barycentrics)
    if last:
        _merge_spans(n_tiles_x, tile_rows, span)


@njit(cache=True, nogil=True)
def _rast_serial(n_tiles_x, bins, bin_z, tile_start, tile_split, s_tri, s_xy, s_zw, depth,
                 tri, b1, b2, span, tile_rows, hiz, count_fragments, fragments, first, last,
                 order, tile_unfilled, tile_zmin, barycentrics):
    for k in range(tile_rows.shape[0]):
        _scan_tile(k, n_tiles_x, bins, bin_z, tile_start, tile_split, s_tri, s_xy, s_zw,
                   depth, tri, b1, b2, span, tile_rows, hiz, count_fragments, fragments, first,
                   order, tile_unfilled, tile_zmin, barycentrics)
    if last:
        _merge_spans(n_tiles_x, tile_rows, span)


# --------------------------------------------------------------------------------------------
# Public entry points

_NO_FRAGMENTS = np.zeros((1, 1), np.int32)


def _checked(xy_z, inv_w, triangles, width, height):
    width, height = int(width), int(height)
    if not (1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE):
        raise ValueError(f"framebuffer size {width}x{height} outside 1..{MAX_SIZE}")
    xy_z = np.ascontiguousarray(xy_z, dtype=np.float64)
    inv_w = np.ascontiguousarray(inv_w, dtype=np.float64)
    triangles = read_only(np.ascontiguousarray(triangles, dtype=np.int64))   # one kernel type
    if xy_z.ndim != 2 or xy_z.shape[1] != 3:
        raise ValueError(f"xy_z must be (V, 3), got {xy_z.shape}")
    if inv_w.shape != (xy_z.shape[0],):
        raise ValueError(f"inv_w must be ({xy_z.shape[0]},), got {inv_w.shape}")
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise ValueError(f"triangles must be (T, 3), got {triangles.shape}")
    return xy_z, inv_w, triangles, width, height


def _run(xy_z, inv_w, triangles, width, height, out, parallel, fragments, barycentrics=True):
    xy_z, inv_w, triangles, width, height = _checked(xy_z, inv_w, triangles, width, height)
    if out is None or out.depth.shape != (height, width):
        out = VisibilityBuffer.allocate(width, height)
    n_tiles_x = -(-width // TILE)
    n_tiles = n_tiles_x * -(-height // TILE)
    n_triangles = triangles.shape[0]
    count = fragments is not None
    # counting visits every covered pixel, hidden or not: no hierarchical z
    hiz = HIERARCHICAL_Z and not count
    order = -1                              # one batch: each tile picks its order
    batches = [(0, n_triangles)]
    if hiz and n_triangles >= BATCH_FROM:
        order = int(_stream_runs_backwards(xy_z, triangles))
        batches = _batches(n_triangles, backwards=order == 1)
    largest = max(end - start for start, end in batches)
    # Below PARALLEL_SETUP triangles setup takes well under a millisecond: waking a second
    # core would cost more than it saves. The bins are the same either way (triangle order).
    parallel_setup = parallel and largest >= PARALLEL_SETUP
    n_chunks = max(1, min(SETUP_CHUNKS, COUNT_CELLS // (2 * n_tiles))) if parallel_setup else 1
    scene = out._scene
    scene.reserve(xy_z.shape[0], largest, n_chunks, n_tiles)
    if not out.spans_known or out.span is None or out.span.shape != (height, 2):
        out.forget_spans()
    out.spans_known = False                 # until the rast has run to its end
    for b, (start, end) in enumerate(batches):
        _batch(xy_z, inv_w, triangles[start:end], start, width, height, n_tiles_x, n_tiles,
               n_chunks, scene, out, parallel, parallel_setup, hiz, count,
               fragments if count else _NO_FRAGMENTS, b == 0, b == len(batches) - 1, order,
               barycentrics)
    out.spans_known = True
    out.barycentrics = barycentrics
    return out


def _batches(n: int, backwards: bool) -> list[tuple[int, int]]:
    """``(start, end)`` of the two batches in drawing order, the first small so that its
    coarse z can reject much of the rest; a backwards stream starts at its end."""
    cut = n // FIRST_BATCH
    return [(n - cut, n), (0, n - cut)] if backwards else [(0, cut), (cut, n)]


def _stream_runs_backwards(xy_z, triangles) -> bool:
    """Do the later triangles look nearer than the first ones (a back-to-front stream)? Then
    the batches go last to first, each tile's bin too, so that the near surfaces land first.
    Either order gives the same picture (ties go to the later triangle both ways)."""
    n = triangles.shape[0]
    sample, step = max(1, n // 64), max(1, n // 64 // 256)
    last = len(xy_z) - 1                       # (a bad index is setup's to refuse)
    head = xy_z[np.clip(triangles[:sample:step], 0, last), 2].max(axis=1)
    tail = xy_z[np.clip(triangles[n - sample::step], 0, last), 2].max(axis=1)
    finite = np.isfinite(head).all() and np.isfinite(tail).all()
    return bool(finite and tail.mean() > head.mean())


def _fronts_nearer(sides) -> bool:
    """Do the front faces lie nearer than the back faces, on average? Then each bin draws
    its front faces first (a mesh wound one way, open somewhere, so its back faces are not
    culled: the near side lands first and hierarchical z rejects most of the far side);
    else, in triangle order: a surface of mixed windings (whose two sides lie at one depth,
    to within a thousandth) would only fill its blocks later."""
    front_z, front_n, back_z, back_n = sides.sum(axis=0)
    if front_n == 0 or back_n == 0:
        return False
    front, back = front_z / front_n, back_z / back_n
    return bool(front - back > 1e-3 * (abs(front) + abs(back)))


def _batch(xy_z, inv_w, triangles, offset, width, height, n_tiles_x, n_tiles, n_chunks, scene,
           out, parallel, parallel_setup, hiz, count, frag, first, last, order, barycentrics):
    """Set up, bin and rasterize one batch of triangles (triangle ``offset`` on)."""
    fixed = scene.fixed[:xy_z.shape[0]]
    chunk_end = scene.chunk_end[:n_chunks]
    counts = scene.counts[:n_chunks * 2 * n_tiles].reshape(n_chunks, 2 * n_tiles)
    tile_start = scene.tile_start[:n_tiles + 1]
    tile_split = scene.tile_split[:n_tiles]
    tile_rows = scene.tile_rows[:n_tiles]
    tile_unfilled = scene.tile_unfilled[:n_tiles]
    tile_zmin = scene.tile_zmin[:n_tiles]
    setup = _setup_parallel if parallel_setup else _setup_serial
    bin_ = _bin_parallel if parallel_setup else _bin_serial
    rast = _rast_parallel if parallel else _rast_serial
    # early z only once some tile is full (else it would test every triangle for nothing)
    early_z = hiz and not first and bool(np.isfinite(tile_zmin[:, N_BLOCKS]).any())
    hidden_in = scene.hidden_in[:xy_z.shape[0]]
    if early_z:
        margin = 3e-9 * float(np.abs(xy_z[:, 2]).max())
        _hidden_vertices(xy_z, fixed, n_tiles_x, width, height, tile_zmin, order == 1,
                         margin if np.isfinite(margin) else np.inf, hidden_in)
    sides = scene.sides[:n_chunks]
    bad = setup(xy_z, inv_w, triangles, width, height, n_tiles_x, fixed, scene.tri, scene.xy,
                scene.zw, chunk_end, counts, sides, first, offset, tile_zmin, early_z,
                order == 1, hidden_in)
    if bad:
        raise ValueError(f"{bad} triangles name a vertex outside 0..{xy_z.shape[0] - 1}")
    partition = hiz and _fronts_nearer(sides)
    scene.reserve_bins(_bin_offsets(counts, tile_start, tile_split, partition))
    bin_(width, height, triangles.shape[0], n_tiles_x, scene.xy, scene.zw, chunk_end, counts,
         scene.bins, scene.bin_z, partition)
    rast(n_tiles_x, scene.bins, scene.bin_z, tile_start, tile_split, scene.tri, scene.xy,
         scene.zw, out.depth, out.tri, out.b1, out.b2, out.span, tile_rows, hiz, count, frag,
         first, last, order, tile_unfilled, tile_zmin, barycentrics)


def rasterize(xy_z, inv_w, triangles, width, height, out: VisibilityBuffer | None = None,
              parallel: bool = True, n_bands: int | None = None,
              barycentrics: bool = True) -> VisibilityBuffer:
    """Scan-convert ``triangles`` into a z-buffer of ``width`` x ``height`` pixels.

    Parameters
    ----------
    xy_z : (V, 3) float64 device coordinates (x right, y up, z larger = nearer).
    inv_w : (V,) float64, 1/W per vertex (ones for a parallel projection); must be > 0.
    triangles : (T, 3) int64 vertex indices; either winding is drawn.
    out : a buffer to reuse (cleared here); a new one is allocated if it is None or its size
        differs, so always use the returned buffer.
    parallel : use all cores; ``False`` runs the single-threaded path, whose result is
        bit-identical.
    n_bands : accepted for the banded rasterizer's callers and ignored: the frame is cut into
        64 x 64 tiles, which the cores share (:func:`_dealt`).
    barycentrics : False leaves ``b1`` and ``b2`` as they were (``out.barycentrics`` says so):
        flat shading reads only the triangle ids, and at 1580 x 1080 the weights of the bunny's
        fragments are a quarter of the rast's time.
    """
    return _run(xy_z, inv_w, triangles, width, height, out, parallel, None, barycentrics)


def count_fragments(xy_z, inv_w, triangles, width, height, parallel: bool = True,
                    n_bands: int | None = None) -> np.ndarray:
    """How many triangles cover each pixel centre, ignoring depth: (H, W) int32, image order.

    Runs exactly the code of :func:`rasterize` (same setup, same edge tests) with a counter
    beside the depth test and the hierarchical z test off (it would skip hidden pixels); the
    tests use it to show the fill rule is watertight.
    """
    fragments = np.zeros((int(height), int(width)), np.int32)
    _run(xy_z, inv_w, triangles, width, height, None, parallel, fragments)
    return fragments


# The setup other visible-surface algorithms share with this one, so that they cover exactly
# the same pixel centres and compute the same depths (Watkins' algorithm:
# core.visibility.watkins).
snap_vertices = _snap_vertices
triangle_edges = _triangle_edges
pixel_box = _pixel_box
checked_inputs = _checked
