"""A bounding-volume hierarchy over triangles: built with the binned surface-area heuristic,
flattened to arrays, traversed with an explicit stack (numba).

The notes (April 4) answer "the hard part is to determine intersections" with bounding
volumes; a BVH of axis-aligned boxes is that idea applied recursively, so a ray tests
O(log T) boxes and a handful of triangles instead of all T.

Build (:func:`build`), top down, in one numba loop over a stack of pending node ranges:

- each node's triangles are sorted into ``BINS`` equal bins along each axis of their
  centroids' bounds; for every one of the ``BINS − 1`` planes between bins the surface-area
  heuristic ``cost = C_box + C_tri (A_L N_L + A_R N_R) / A`` (Wald 2007) is evaluated from
  prefix sums of the bins' boxes and counts, and the cheapest plane over the three axes wins;
- a node becomes a leaf when it has at most a few triangles, or when no split is cheaper
  than intersecting all its triangles (``C_tri N``) and it has at most a leaf's largest
  number (:data:`TRIANGLE_LEAVES`: a leaf's triangles are tested four at a time, so a
  triangle costs ``C_tri`` = 0.3 box tests and leaves hold up to 16);
- triangles whose centroids coincide (no bin can separate them), and nodes deeper than
  ``SAH_DEPTH``, are split at the median by index, so the tree stays at most ~``MAX_DEPTH``
  deep and the traversal stack (``STACK``) cannot overflow.

Layout (:class:`BVH`): node ``k`` has its box in ``box[k] = (min xyz, max xyz)``, float64
(float32 boxes halve the memory but cost a conversion per bound tested: 10 % of the bunny's
primary rays); an inner node's children are ``first[k]``
and ``first[k] + 1`` (``count[k] == 0``), a leaf holds triangles ``first[k] .. first[k] +
count[k] − 1`` of the BVH's own order. Triangles are stored in that order as columns of
``tri`` ``(9, C)``, whose rows are ``V0, E1, E2`` by component (what Möller–Trumbore reads),
with ``prim`` mapping back to the scene's triangle index: each of a leaf's nine numbers is a
run of memory, what a four-wide load takes. A leaf's run is padded with zero (never hit)
triangles to a multiple of four (``LANES``), so that its test has no one-at-a-time
remainder: three triangles cost 30 ns one at a time and 13 ns as one four-wide step.

Traversal (:func:`closest`, :func:`occluded`): the slab test against the box with the ray's
reciprocal direction (each axis's near and far slab picked once per ray by the direction's
sign), the nearer child first, nodes whose entry lies beyond the best hit so far skipped.
The stack (:func:`new_stack`) keeps each pushed node's entry distance beside it, so a node
popped after a nearer hit is dropped without testing its box again.
A leaf's triangles are tested side by side (:func:`intersect.triangle_run`), their ``t``
into the stack's tail, then read in order: the hit is the one the one-at-a-time loop found,
to the bit. ``occluded`` stops at the first hit (shadow rays). ``closest`` is inlined into
its callers: a numba call that takes the scene's tuple of arrays costs per array, per call.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from core.jit import SimplifiedCompiler, call_compiled, compiled_at, config, njit, prange
from core.raytrace import intersect

BINS = 16
# Leaves: (always a leaf at or below, always split above, one item's test in units of a box
# test). A leaf's triangles are tested four at a time (intersect.triangle_run), so a
# triangle's test costs a box test's fraction, and a leaf of up to four costs one test.
TRIANGLE_LEAVES = (4, 16, 0.3)
LANES = 4              # a leaf's run of triangles is padded to a multiple of this (see build)
ITEM_LEAVES = (2, 8, 1.0)   # the spheres of a BoxTree, one at a time
SAH_DEPTH = 48         # below this depth, median splits only (bounds the tree's depth)
STACK = 128            # traversal stack; >= the deepest tree SAH_DEPTH + log2(2^40) allows


class BVH(NamedTuple):
    """The flattened tree (numba takes it as one argument)."""

    box: np.ndarray      # (nodes, 6) float64: min x, y, z, max x, y, z
    first: np.ndarray    # (nodes,) int64: first child (inner) or first triangle (leaf)
    count: np.ndarray    # (nodes,) int64: 0 for an inner node, else the leaf's columns
    tri: np.ndarray      # (9, C) float64, columns in BVH order: V0, E1 = V1 - V0, E2 = V2 - V0
    prim: np.ndarray     # (C,) int64: the scene triangle in each column (-1: a leaf's padding)


class BuildReport(NamedTuple):
    triangles: int
    nodes: int
    leaves: int
    depth: int
    seconds: float
    bytes: int


# --------------------------------------------------------------------------------------------
# Build


@njit(cache=True)
def _area(bx0, by0, bz0, bx1, by1, bz1):
    """Half the surface area of a box (the factor 2 cancels in the heuristic)."""
    ex, ey, ez = bx1 - bx0, by1 - by0, bz1 - bz0
    if ex < 0.0:                       # an empty box (no triangle grew it)
        return 0.0
    return ex * ey + ey * ez + ez * ex


@njit(cache=True)
def _range_bounds(lo, hi, cent, index, start, end, box, cbox):
    """The box of triangles ``index[start:end]`` and the box of their centroids."""
    for a in range(3):
        box[a], box[a + 3] = np.inf, -np.inf
        cbox[a], cbox[a + 3] = np.inf, -np.inf
    for i in range(start, end):
        t = index[i]
        for a in range(3):
            box[a] = min(box[a], lo[t, a])
            box[a + 3] = max(box[a + 3], hi[t, a])
            cbox[a] = min(cbox[a], cent[t, a])
            cbox[a + 3] = max(cbox[a + 3], cent[t, a])


@njit(cache=True)
def _bin_of(c, c_min, scale):
    b = int((c - c_min) * scale)
    return min(max(b, 0), BINS - 1)


@njit(cache=True)
def _best_split(lo, hi, cent, index, start, end, cbox, bin_box, bin_count, right_area,
                right_count):
    """``(cost, axis, bin)`` of the cheapest SAH plane: the split puts bins ``< bin`` left.

    ``cost`` is ``sum(A_side N_side)``; ``axis = -1`` when the centroids cannot be separated.
    """
    best_cost, best_axis, best_bin = np.inf, -1, 0
    for axis in range(3):
        c_min, extent = cbox[axis], cbox[axis + 3] - cbox[axis]
        if not extent > 0.0:
            continue
        scale = BINS / extent
        for b in range(BINS):
            bin_count[b] = 0
            for a in range(3):
                bin_box[b, a], bin_box[b, a + 3] = np.inf, -np.inf
        for i in range(start, end):
            t = index[i]
            b = _bin_of(cent[t, axis], c_min, scale)
            bin_count[b] += 1
            for a in range(3):
                bin_box[b, a] = min(bin_box[b, a], lo[t, a])
                bin_box[b, a + 3] = max(bin_box[b, a + 3], hi[t, a])
        # Sweep from the right: the area and count of bins b .. BINS-1.
        x0, y0, z0, x1, y1, z1 = np.inf, np.inf, np.inf, -np.inf, -np.inf, -np.inf
        n = 0
        for b in range(BINS - 1, 0, -1):
            x0, y0, z0 = min(x0, bin_box[b, 0]), min(y0, bin_box[b, 1]), min(z0, bin_box[b, 2])
            x1, y1, z1 = max(x1, bin_box[b, 3]), max(y1, bin_box[b, 4]), max(z1, bin_box[b, 5])
            n += bin_count[b]
            right_area[b], right_count[b] = _area(x0, y0, z0, x1, y1, z1), n
        # Sweep from the left, pricing the plane before bin b.
        x0, y0, z0, x1, y1, z1 = np.inf, np.inf, np.inf, -np.inf, -np.inf, -np.inf
        n = 0
        for b in range(1, BINS):
            x0, y0, z0 = min(x0, bin_box[b - 1, 0]), min(y0, bin_box[b - 1, 1]), min(z0, bin_box[b - 1, 2])
            x1, y1, z1 = max(x1, bin_box[b - 1, 3]), max(y1, bin_box[b - 1, 4]), max(z1, bin_box[b - 1, 5])
            n += bin_count[b - 1]
            if n == 0 or right_count[b] == 0:
                continue
            cost = _area(x0, y0, z0, x1, y1, z1) * n + right_area[b] * right_count[b]
            if cost < best_cost:
                best_cost, best_axis, best_bin = cost, axis, b
    return best_cost, best_axis, best_bin


@njit(cache=True)
def _partition(cent, index, start, end, axis, split_bin, c_min, scale):
    """Reorder ``index[start:end]`` so triangles in bins ``< split_bin`` come first."""
    i, j = start, end - 1
    while i <= j:
        if _bin_of(cent[index[i], axis], c_min, scale) < split_bin:
            i += 1
        else:
            index[i], index[j] = index[j], index[i]
            j -= 1
    return i


@njit(cache=True)
def _push(pending, i, node, start, end, depth):
    pending[i, 0], pending[i, 1], pending[i, 2], pending[i, 3] = node, start, end, depth


@njit(cache=True)
def _build(lo, hi, cent, leaves):
    """Nodes ``(box, first, count)``, the triangle order ``index`` and the tree's depth;
    ``leaves``: :data:`TRIANGLE_LEAVES` or :data:`ITEM_LEAVES`."""
    min_split, max_leaf, item_cost = leaves
    n = cent.shape[0]
    max_nodes = max(2 * n - 1, 1)
    box = np.empty((max_nodes, 6))
    first = np.zeros(max_nodes, dtype=np.int64)
    count = np.zeros(max_nodes, dtype=np.int64)
    index = np.arange(n).astype(np.int64)
    cbox = np.empty(6)
    bin_box = np.empty((BINS, 6))
    bin_count = np.zeros(BINS, dtype=np.int64)
    right_area = np.zeros(BINS)
    right_count = np.zeros(BINS, dtype=np.int64)
    # Pending nodes: (node, start, end, depth); at most one per level of the tree is pending.
    pending = np.empty((4 * STACK, 4), dtype=np.int64)
    _push(pending, 0, 0, 0, n, 0)
    top = 1
    used = 1
    depth_max = 0
    while top > 0:
        top -= 1
        node, start, end, depth = pending[top, 0], pending[top, 1], pending[top, 2], pending[top, 3]
        depth_max = max(depth_max, depth)
        _range_bounds(lo, hi, cent, index, start, end, box[node], cbox)
        size = end - start
        first[node], count[node] = start, size
        if size <= min_split:
            continue
        mid = start
        if depth < SAH_DEPTH:
            cost, axis, split_bin = _best_split(lo, hi, cent, index, start, end, cbox, bin_box,
                                                bin_count, right_area, right_count)
            parent_area = _area(box[node, 0], box[node, 1], box[node, 2],
                                box[node, 3], box[node, 4], box[node, 5])
            if axis >= 0:
                leaf_cost = item_cost * size
                split_cost = (1.0 + item_cost * cost / parent_area if parent_area > 0.0
                              else leaf_cost)
                if split_cost >= leaf_cost and size <= max_leaf:
                    continue                          # intersecting them all is cheaper
                scale = BINS / (cbox[axis + 3] - cbox[axis])
                mid = _partition(cent, index, start, end, axis, split_bin, cbox[axis], scale)
        if mid == start or mid == end:               # inseparable centroids, or too deep
            if size <= max_leaf:
                continue
            mid = start + size // 2                   # the median by index
        left = used
        used += 2
        first[node], count[node] = left, 0
        _push(pending, top, left + 1, mid, end, depth + 1)
        _push(pending, top + 1, left, start, mid, depth + 1)
        top += 2
    return box[:used].copy(), first[:used].copy(), count[:used].copy(), index, depth_max


@njit(cache=True)
def _pad_leaves(first, count, lanes):
    """Each leaf's run of triangles padded to a multiple of ``lanes``: the leaves' new first
    columns and counts (in place), and each new column's old BVH position (−1: padding)."""
    total = 0
    for k in range(first.shape[0]):
        if count[k] > 0:
            total += (count[k] + lanes - 1) // lanes * lanes
    column = np.full(total, -1, np.int64)
    used = 0
    for k in range(first.shape[0]):
        if count[k] > 0:
            for j in range(count[k]):
                column[used + j] = first[k] + j
            first[k] = used
            count[k] = (count[k] + lanes - 1) // lanes * lanes
            used += count[k]
    return column


@njit(cache=True, parallel=True, nogil=True)
def _triangle_arrays(positions, triangles, order, tri):
    """Column k of ``tri``: V0, E1, E2 of triangle ``order[k]``; a degenerate zero triangle
    (never hit) where ``order[k]`` is −1 (a leaf's padding)."""
    for k in prange(order.shape[0]):
        t = order[k]
        if t < 0:
            for row in range(9):
                tri[row, k] = 0.0
            continue
        a, b, c = triangles[t, 0], triangles[t, 1], triangles[t, 2]
        for ax in range(3):
            tri[ax, k] = positions[a, ax]
            tri[3 + ax, k] = positions[b, ax] - positions[a, ax]
            tri[6 + ax, k] = positions[c, ax] - positions[a, ax]


def build(positions: np.ndarray, triangles: np.ndarray) -> tuple[BVH, BuildReport]:
    """The BVH of ``triangles`` ``(T, 3)`` over ``positions`` ``(V, 3)``, and how its build went.

    Degenerate triangles are kept (Möller–Trumbore never reports a hit on them); triangles
    with a non-finite vertex are left out of the tree (no ray can hit them).
    """
    start_time = time.perf_counter()
    positions = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 3)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    corners = positions[triangles]                       # (T, 3, 3)
    finite = np.isfinite(corners).all(axis=(1, 2))
    keep = np.flatnonzero(finite)
    lo = np.ascontiguousarray(corners[keep].min(axis=1))
    hi = np.ascontiguousarray(corners[keep].max(axis=1))
    cent = (lo + hi) * 0.5                                # the box centre: one pass, no division
    del corners
    if len(keep) == 0:                                    # a tree with one empty leaf
        box = np.array([[np.inf, np.inf, np.inf, -np.inf, -np.inf, -np.inf]])
        nodes = (box, np.zeros(1, np.int64), np.zeros(1, np.int64), np.zeros(0, np.int64), 0)
    else:
        nodes = _build(lo, hi, cent, TRIANGLE_LEAVES)
    box, first, count, index, depth = nodes
    column = _pad_leaves(first, count, LANES)
    if len(count) and count.max() > TRIANGLE_LEAVES[1]:     # the traversal's hit buffer
        raise RuntimeError(f"a BVH leaf of {count.max()} columns: at most "
                           f"{TRIANGLE_LEAVES[1]} fit the traversal's buffer")
    order = np.where(column >= 0, keep[index][column], -1).astype(np.int64)
    tri = np.empty((9, len(order)))
    _triangle_arrays(positions, triangles, order, tri)
    bvh = BVH(box, first, count, tri, order)
    seconds = time.perf_counter() - start_time
    size = sum(a.nbytes for a in bvh)
    leaves = int(np.count_nonzero(count > 0)) if len(keep) else 0
    return bvh, BuildReport(len(keep), len(box), leaves, int(depth), seconds, size)


class BoxTree(NamedTuple):
    """A BVH over boxes of anything (the analytic spheres): the same nodes as :class:`BVH`,
    a leaf's items ``item[first[k] .. first[k] + count[k] − 1]`` (rows of the caller's table)."""

    box: np.ndarray
    first: np.ndarray
    count: np.ndarray
    item: np.ndarray


def build_boxes(lo: np.ndarray, hi: np.ndarray) -> BoxTree:
    """The tree over items with boxes ``lo``, ``hi`` ``(N, 3)`` (same binned SAH as :func:`build`)."""
    lo = np.ascontiguousarray(lo, dtype=np.float64).reshape(-1, 3)
    hi = np.ascontiguousarray(hi, dtype=np.float64).reshape(-1, 3)
    if len(lo) == 0:
        box = np.array([[np.inf, np.inf, np.inf, -np.inf, -np.inf, -np.inf]])
        return BoxTree(box, np.zeros(1, np.int64), np.zeros(1, np.int64), np.zeros(0, np.int64))
    box, first, count, index, _ = _build(lo, hi, (lo + hi) * 0.5, ITEM_LEAVES)
    return BoxTree(box, first, count, index.astype(np.int64))


# --------------------------------------------------------------------------------------------
# Traversal


@njit(cache=True)
def _reciprocal(d):
    """1/d with 1/0 = a huge number of the right sign: the slab test then needs no branch."""
    if d == 0.0:
        return 1e300
    return 1.0 / d


@njit(cache=True, inline="always")
def _box_entry(box, k, ox, oy, oz, ix, iy, iz, near, t_max):
    """Where the ray enters box ``k`` (slab test), or +inf when it misses it before ``t_max``.

    ``near`` (:func:`_sides`): the box's column of the slab the ray meets first on each axis
    (its min where the reciprocal direction is positive, its max where negative), then the
    far ones: each axis costs two products and no min/max. ``i*`` are never 0 or NaN, so no
    product is NaN."""
    nx, ny, nz, fx, fy, fz = near
    k = np.uint64(k)        # unsigned: no wrap-around test for a negative index
    t_enter = max((box[k, nx] - ox) * ix, (box[k, ny] - oy) * iy, (box[k, nz] - oz) * iz, 0.0)
    t_exit = min((box[k, fx] - ox) * ix, (box[k, fy] - oy) * iy, (box[k, fz] - oz) * iz, t_max)
    if t_enter > t_exit:
        return np.inf
    return t_enter


@njit(cache=True)
def _sides(ix, iy, iz):
    """The near and far columns of a box for a ray of reciprocal direction ``i``."""
    nx = 0 if ix >= 0.0 else 3
    ny = 1 if iy >= 0.0 else 4
    nz = 2 if iz >= 0.0 else 5
    return (np.uint64(nx), np.uint64(ny), np.uint64(nz), np.uint64(3 - nx), np.uint64(5 - ny),
            np.uint64(7 - nz))


@njit(cache=True)
def new_stack():
    """A traversal's scratch: ``STACK`` pairs (node as a float, exact below 2^53; where the
    ray enters it), then room for a leaf's hits (:func:`intersect.triangle_run`)."""
    return np.empty(2 * STACK + TRIANGLE_LEAVES[1])


@njit(cache=True, inline="always")
def _push_nearer(stack, top, left, t_left, t_right):
    """Of two children that the ray enters, push the farther (with its entry) and return the
    nearer one and the new top; ``t = inf`` for a child the ray misses."""
    at = np.uint64(2 * top)
    if t_left <= t_right:
        if t_right != np.inf:
            stack[at], stack[at + np.uint64(1)] = left + 1, t_right
            top += 1
        return left, top
    if t_left != np.inf:
        stack[at], stack[at + np.uint64(1)] = left, t_left
        top += 1
    return left + 1, top


@njit(cache=True, inline="always")
def _pop(stack, top, best_t):
    """The next pushed node the ray enters before ``best_t`` (-1: none) and the new top."""
    while top > 0:
        top -= 1
        at = np.uint64(2 * top)
        if stack[at + np.uint64(1)] <= best_t:
            return np.int64(stack[at]), top
    return -1, 0


@njit(cache=True, inline="always")
def closest(bvh, ox, oy, oz, dx, dy, dz, t_min, t_max, stack):
    """``(k, t, u, v)``: BVH position ``k`` of the nearest triangle hit in ``(t_min, t_max)``
    (``bvh.prim[k]`` is the scene's triangle), or ``k = -1``. ``stack``: :func:`new_stack`.

    The nearer child is visited first and the farther one pushed with its entry distance; a
    popped node that the best hit so far lies in front of is dropped."""
    box, first, count, tri = bvh.box, bvh.first, bvh.count, bvh.tri
    if tri.shape[1] == 0:
        return -1, np.inf, 0.0, 0.0
    ix, iy, iz = _reciprocal(dx), _reciprocal(dy), _reciprocal(dz)
    near = _sides(ix, iy, iz)
    best_k, best_t = -1, t_max
    if _box_entry(box, 0, ox, oy, oz, ix, iy, iz, near, best_t) == np.inf:
        return -1, np.inf, 0.0, 0.0
    node, top = 0, 0
    while node >= 0:
        n = count[np.uint64(node)]
        if n > 0:                                         # a leaf: test its triangles
            f = first[np.uint64(node)]
            hits = stack[2 * STACK:]
            intersect.triangle_run(ox, oy, oz, dx, dy, dz, tri, f, n, t_min, best_t, hits)
            for j in range(n):
                if hits[j] < best_t:
                    best_k, best_t = f + j, hits[j]
        else:
            left = first[np.uint64(node)]
            t_left = _box_entry(box, left, ox, oy, oz, ix, iy, iz, near, best_t)
            t_right = _box_entry(box, left + 1, ox, oy, oz, ix, iy, iz, near, best_t)
            if t_left != np.inf or t_right != np.inf:
                node, top = _push_nearer(stack, top, left, t_left, t_right)
                continue
        node, top = _pop(stack, top, best_t)
    if best_k < 0:
        return -1, np.inf, 0.0, 0.0
    _, u, v = intersect.triangle(ox, oy, oz, dx, dy, dz, tri[0:3, best_k], tri[3:6, best_k],
                                 tri[6:9, best_k], t_min, np.inf)
    return best_k, best_t, u, v


# no reference counts: a shadow ray's walk makes no array (see pathtrace.kernel.trace_run)
@njit(cache=True, _nrt=False)
def occluded(bvh, ox, oy, oz, dx, dy, dz, t_min, t_max, stack):
    """BVH position of any triangle hit in ``(t_min, t_max)``, or -1 (the shadow-ray query)."""
    box, first, count, tri = bvh.box, bvh.first, bvh.count, bvh.tri
    if tri.shape[1] == 0:
        return -1
    ix, iy, iz = _reciprocal(dx), _reciprocal(dy), _reciprocal(dz)
    near = _sides(ix, iy, iz)
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        node = np.uint64(stack[np.uint64(2 * top)])
        if _box_entry(box, node, ox, oy, oz, ix, iy, iz, near, t_max) == np.inf:
            continue
        n = count[node]
        if n > 0:
            f = first[node]
            hits = stack[2 * STACK:]
            intersect.triangle_run(ox, oy, oz, dx, dy, dz, tri, f, n, t_min, t_max, hits)
            for j in range(n):
                if hits[j] < t_max:
                    return f + j
            continue
        at = np.uint64(2 * top)
        stack[at] = first[node] + 1
        stack[at + np.uint64(2)] = first[node]
        top += 2
    return -1


DEAL = max(1, config.NUMBA_NUM_THREADS)   # a constant of the compiled code (it is cached)


# numpy's error model, as in the parallel loops that call it with their index: one
# compiled form for both (core.jit.reuse_plain_overloads)
@njit(cache=True, error_model="numpy")
def spread(j, chunks):
    """The chunk that parallel work item ``j`` of ``chunks`` handles, dealt round-robin.

    numba hands each of its ``T`` threads one contiguous block of a prange. Without a deal,
    one core gets the sky and the other the model (measured on the bunny: wall time 1.7x the
    CPU time per core). The deal lists the chunks by their remainder mod ``T``, then in order,
    so each block is the chunks ``r, r + T, r + 2T, …``: spread over the whole picture, yet in
    order, so that neighbouring rays find the tree's nodes still in cache (a scattered deal
    cost the bunny's primary rays 5–12 % more CPU time). ``T`` is the most threads numba
    runs (:data:`DEAL`): with fewer, each thread's block holds several remainders, still in
    order."""
    j, chunks = np.int64(j), np.int64(chunks)     # a prange index may be unsigned
    threads = np.int64(DEAL)
    if threads <= 1 or chunks <= threads:
        return j
    short = chunks // threads                     # every remainder has this many chunks,
    extra = chunks % threads                      # the first ``extra`` remainders one more
    long_span = extra * (short + 1)
    if j < long_span:
        r, i = j // (short + 1), j % (short + 1)
    else:
        r, i = extra + (j - long_span) // short, (j - long_span) % short
    return r + i * threads


def closest_many(bvh, origins, directions, t_min, t_max, prim, t_hit, u_hit, v_hit):
    """:func:`closest` for every ray (in parallel): the scene triangle (-1: none), t, u, v."""
    given = (bvh, origins, directions, t_min, t_max, prim, t_hit, u_hit, v_hit)
    _closest_chunks(*given, compiled_at(_closest_run, given + (0, 0)))


@njit(cache=True, parallel=True, nogil=True)
def _closest_chunks(bvh, origins, directions, t_min, t_max, prim, t_hit, u_hit, v_hit, at):
    """:func:`_closest_run` on chunks of 1,024 rays, in parallel, called by its address
    ``at`` (core.jit.call_compiled): the walk is optimised once, in ``_closest_run``, not
    again inside this loop."""
    n = origins.shape[0]
    chunks = (n + 1023) // 1024
    for j in prange(chunks):
        chunk = spread(j, chunks)
        call_compiled(at, _closest_run, bvh, origins, directions, t_min, t_max, prim, t_hit,
                      u_hit, v_hit, chunk * 1024, min(n, (chunk + 1) * 1024))


# numpy's error model, as the parallel loop's body that it was; simplified, as that body was
# (core.jit.SimplifiedCompiler: without it the walk took 1.25x as long)
@njit(cache=True, nogil=True, error_model="numpy", pipeline_class=SimplifiedCompiler)
def _closest_run(bvh, origins, directions, t_min, t_max, prim, t_hit, u_hit, v_hit, start,
                 end):
    """:func:`closest` for rays ``start`` to ``end``."""
    stack = new_stack()
    for i in range(start, end):
        k, t, u, v = closest(bvh, origins[i, 0], origins[i, 1], origins[i, 2],
                             directions[i, 0], directions[i, 1], directions[i, 2],
                             t_min[i], t_max[i], stack)
        prim[i] = bvh.prim[k] if k >= 0 else -1
        t_hit[i], u_hit[i], v_hit[i] = t, u, v


@njit(cache=True, parallel=True, nogil=True)
def occluded_many(bvh, origins, directions, t_min, t_max, hit):
    """:func:`occluded` for every ray (in parallel): true where something is in the way."""
    n = origins.shape[0]
    chunks = (n + 1023) // 1024
    for j in prange(chunks):
        chunk = spread(j, chunks)
        stack = new_stack()
        for i in range(chunk * 1024, min(n, (chunk + 1) * 1024)):
            hit[i] = occluded(bvh, origins[i, 0], origins[i, 1], origins[i, 2],
                              directions[i, 0], directions[i, 1], directions[i, 2],
                              t_min[i], t_max[i], stack) >= 0


def intersect_rays(bvh: BVH, origins, directions, t_min=0.0, t_max=np.inf):
    """Nearest hits of many rays: ``(triangle (N,) int64, -1 none; t; u; v)``."""
    origins = np.ascontiguousarray(origins, dtype=np.float64).reshape(-1, 3)
    directions = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1, 3)
    n = len(origins)
    lo = np.broadcast_to(np.asarray(t_min, dtype=np.float64), (n,)).copy()
    hi = np.broadcast_to(np.asarray(t_max, dtype=np.float64), (n,)).copy()
    prim = np.empty(n, np.int64)
    t, u, v = np.empty(n), np.empty(n), np.empty(n)
    closest_many(bvh, origins, directions, lo, hi, prim, t, u, v)
    return prim, t, u, v


def occluded_rays(bvh: BVH, origins, directions, t_min=0.0, t_max=np.inf) -> np.ndarray:
    """Whether anything lies on each ray inside ``(t_min, t_max)``: ``(N,)`` bool."""
    origins = np.ascontiguousarray(origins, dtype=np.float64).reshape(-1, 3)
    directions = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1, 3)
    n = len(origins)
    lo = np.broadcast_to(np.asarray(t_min, dtype=np.float64), (n,)).copy()
    hi = np.broadcast_to(np.asarray(t_max, dtype=np.float64), (n,)).copy()
    hit = np.empty(n, np.bool_)
    occluded_many(bvh, origins, directions, lo, hi, hit)
    return hit


@njit(cache=True)
def closest_sphere(box, first, count, item, spheres, ox, oy, oz, dx, dy, dz, t_min, t_max,
                   stack):
    """``(row, t)`` of the nearest sphere (rows ``cx, cy, cz, r, …``) a :class:`BoxTree`
    holds, hit in ``(t_min, t_max)``; ``(-1, inf)`` when none is. The walk is
    :func:`closest`'s: the nearer child first, a popped node dropped behind the best hit."""
    best, best_t = -1, t_max
    if item.shape[0] == 0:
        return -1, np.inf
    ix, iy, iz = _reciprocal(dx), _reciprocal(dy), _reciprocal(dz)
    near = _sides(ix, iy, iz)
    if _box_entry(box, 0, ox, oy, oz, ix, iy, iz, near, best_t) == np.inf:
        return -1, np.inf
    node, top = 0, 0
    while node >= 0:
        n = count[node]
        if n > 0:
            for k in range(first[node], first[node] + n):
                i = item[k]
                t = intersect.sphere(ox, oy, oz, dx, dy, dz, spheres[i, 0], spheres[i, 1],
                                     spheres[i, 2], spheres[i, 3], t_min, best_t)
                if t < best_t:
                    best, best_t = i, t
        else:
            left = first[np.uint64(node)]
            t_left = _box_entry(box, left, ox, oy, oz, ix, iy, iz, near, best_t)
            t_right = _box_entry(box, left + 1, ox, oy, oz, ix, iy, iz, near, best_t)
            if t_left != np.inf or t_right != np.inf:
                node, top = _push_nearer(stack, top, left, t_left, t_right)
                continue
        node, top = _pop(stack, top, best_t)
    if best < 0:
        return -1, np.inf
    return best, best_t
