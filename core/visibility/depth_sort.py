"""Depth sort (Newell, Newell and Sancha 1972; FvDFH 15.5.1; the notes' approach 3, "sort out
the depth"), on triangles already clipped and projected to the device.

In device space the perspective-to-parallel transformation has made every view a parallel
one along z (larger z nearer, the viewer at z = +inf), and planes are still planes. So:

1. Sort the triangles by their farthest z (smallest z first).
2. Take P, the first of the list. Before painting it, check every Q whose z extent overlaps
   P's (the list is sorted, so the first Q wholly nearer ends the scan). Q is no trouble when
   one of these tests, in this order, says so: (1) their x extents do not overlap, (2) their
   y extents do not overlap, (3) P is wholly on the far side of Q's plane, (4) Q is wholly on
   the near side of P's plane, (5) their projections do not overlap.
3. If all fail, P may hide part of Q. If Q may be painted first (3'. Q wholly on the far side
   of P's plane, or 4'. P wholly on the near side of Q's plane), Q moves to the head of the
   list and is marked. A marked polygon that must move again is in a cycle (the three bars),
   and polygons that pierce each other pass no test at all: then one is split by the plane
   of the other (the one that spans it), and the pieces are put back in the sorted list.
4. Paint P when no Q objected; go on with the next.

When neither polygon of a cycle spans the other's plane, the one in the way is cut along
the other's silhouette (a plane through one of its edges, parallel to z). A polygon may move
at most ``MAX_ROUNDS`` times the list's length in total; past that the rest is painted in
list order and counted as unresolved (never seen on the shipped scenes).

A split vertex is made in device space at parameter ``t`` along an edge; 1/W and depth are
affine there, and the attributes (linear in world space) take the world parameter
``s = t w_b / ((1 - t) w_a + t w_b)`` with ``w = 1/W``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import read_only
from core.jit import njit
from core.visibility.split import cut_triangle, grow

# Counters in the order FvDFH runs the tests, then what was done about failures.
COUNTERS = ("z extents", "x extents", "y extents", "P beyond Q's plane",
            "Q before P's plane", "projections", "reversed tests", "moves", "splits",
            "unresolved")
MAX_ROUNDS = 16
EPSILON = 1e-9


@dataclass
class DepthSorted:
    """Triangles in painting order over ``device`` (V', 3) and ``inv_w`` (V',): the input
    vertices, then one per split (``recipe`` (V' - V, 3): edge ends ``a, b`` and the world
    parameter ``s``). ``triangles`` (F, 3), ``source`` (F,) the input triangle each piece of
    came from; ``counts`` the tests run and the moves and splits made (``COUNTERS``)."""

    device: np.ndarray
    inv_w: np.ndarray
    recipe: np.ndarray
    triangles: np.ndarray
    source: np.ndarray
    counts: dict


def depth_sort(device: np.ndarray, inv_w: np.ndarray, triangles: np.ndarray,
               resolve: bool = True) -> DepthSorted:
    """Newell's order for ``triangles`` (T, 3) over ``device`` (V, 3), ``inv_w`` (V,).

    ``resolve`` False: only step 1, the plain painter's sort by farthest z (wrong wherever
    polygons overlap in z and in the image; the tests show it)."""
    device = np.ascontiguousarray(device, dtype=np.float64).reshape(-1, 3)
    inv_w = np.ascontiguousarray(inv_w, dtype=np.float64).reshape(-1)
    triangles = read_only(np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3))
    scale = float(np.abs(device).max()) + 1.0 if len(device) else 1.0
    out = _depth_sort(device, inv_w, triangles, EPSILON * scale, resolve)
    dev, iw, recipe, tris, source, counts = out
    return DepthSorted(dev, iw, recipe, tris, source,
                       {name: int(c) for name, c in zip(COUNTERS, counts)})


# ------------------------------------------------------------------------------- geometry

@njit(cache=True, nogil=True)
def _facts(device, tri, box, plane, f):
    """Extents ``box[f]`` (x0, x1, y0, y1, z0, z1) and the plane ``plane[f]`` (n, c) oriented
    so that the viewer (z = +inf) is on its positive side; n_z = 0: seen edge-on."""
    p0, p1, p2 = device[tri[0]], device[tri[1]], device[tri[2]]
    for axis in range(3):
        box[f, 2 * axis] = min(p0[axis], p1[axis], p2[axis])
        box[f, 2 * axis + 1] = max(p0[axis], p1[axis], p2[axis])
    n = np.cross(p1 - p0, p2 - p0)
    length = np.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
    if length > 0.0:
        n = n / length
    if n[2] < 0.0:
        n = -n
    plane[f, 0], plane[f, 1], plane[f, 2] = n[0], n[1], n[2]
    plane[f, 3] = n[0] * p0[0] + n[1] * p0[1] + n[2] * p0[2]


@njit(cache=True, nogil=True)
def _distance(device, v, plane, q):
    """Signed distance of vertex ``v`` from ``q``'s plane (positive: the viewer's side)."""
    return (plane[q, 0] * device[v, 0] + plane[q, 1] * device[v, 1] + plane[q, 2] * device[v, 2]
            - plane[q, 3])


@njit(cache=True, nogil=True)
def _distances(device, tri, plane, q):
    d = np.empty(3)
    for k in range(3):
        d[k] = _distance(device, tri[k], plane, q)
    return d


@njit(cache=True, nogil=True)
def _beyond(device, tri, plane, q, eps):
    """Is ``tri`` wholly on the far side of q's plane? (A plane seen edge-on settles nothing.)"""
    if plane[q, 2] <= 0.0:
        return False
    for k in range(3):
        if _distance(device, tri[k], plane, q) > eps:
            return False
    return True


@njit(cache=True, nogil=True)
def _before(device, tri, plane, q, eps):
    """Is ``tri`` wholly on the viewer's side of q's plane?"""
    if plane[q, 2] <= 0.0:
        return False
    for k in range(3):
        if _distance(device, tri[k], plane, q) < -eps:
            return False
    return True


@njit(cache=True, nogil=True)
def _spans(d, eps):
    lo, hi = min(d[0], d[1], d[2]), max(d[0], d[1], d[2])
    return lo < -eps and hi > eps


@njit(cache=True, nogil=True)
def _separated_on_edges(device, a, b, eps):
    """Is an edge line of triangle ``a`` a separating axis of the two projections?"""
    for k in range(3):
        p, q = device[a[k]], device[a[(k + 1) % 3]]
        nx, ny = q[1] - p[1], p[0] - q[0]           # the edge's normal in the image
        if nx == 0.0 and ny == 0.0:
            continue
        c = nx * p[0] + ny * p[1]
        r = device[a[(k + 2) % 3]]
        inside = nx * r[0] + ny * r[1] - c          # the third vertex's side
        sign = 1.0 if inside >= 0.0 else -1.0
        tol = eps * (abs(nx) + abs(ny))
        separated = True
        for j in range(3):
            s = device[b[j]]
            if sign * (nx * s[0] + ny * s[1] - c) > tol:
                separated = False
                break
        if separated:
            return True
    return False


@njit(cache=True, nogil=True)
def _projections_overlap(device, a, b, eps):
    """Test 5: the triangles' images share interior (touching along an edge is not overlap)."""
    return not (_separated_on_edges(device, a, b, eps) or _separated_on_edges(device, b, a, eps))


@njit(cache=True, nogil=True)
def _silhouette_plane(device, a, b, eps):
    """A plane parallel to z through an edge of ``a`` that ``b`` spans, as (n, c); n = 0: none."""
    out = np.zeros(4)
    for k in range(3):
        p, q = device[a[k]], device[a[(k + 1) % 3]]
        nx, ny = q[1] - p[1], p[0] - q[0]
        length = np.sqrt(nx * nx + ny * ny)
        if length == 0.0:
            continue
        nx, ny = nx / length, ny / length
        c = nx * p[0] + ny * p[1]
        lo, hi = np.inf, -np.inf
        for j in range(3):
            s = device[b[j]]
            d = nx * s[0] + ny * s[1] - c
            lo, hi = min(lo, d), max(hi, d)
        if lo < -eps and hi > eps:
            out[0], out[1], out[3] = nx, ny, c
            return out
    return out


# ---------------------------------------------------------------------------------- sort

@njit(cache=True, nogil=True)
def _depth_sort(device_in, inv_w_in, triangles, eps, resolve):
    counts = np.zeros(len(COUNTERS), np.int64)
    n_in = device_in.shape[0]
    device = device_in.copy()
    inv_w = inv_w_in.copy()
    recipe = np.empty((16, 3))
    n_points = n_in
    tris = triangles.copy()
    source = np.arange(triangles.shape[0])
    n_tris = triangles.shape[0]
    box = np.empty((max(n_tris, 1), 6))
    plane = np.empty((max(n_tris, 1), 4))
    for f in range(n_tris):
        _facts(device, tris[f], box, plane, f)
    # 1. the list, farthest z first
    lst = np.argsort(box[:n_tris, 4], kind="mergesort").astype(np.int64)
    n_list = n_tris
    marked = np.zeros(max(n_tris, 1), np.bool_)
    if not resolve:
        return device, inv_w, recipe[:0], tris[lst], source[lst], counts
    budget = MAX_ROUNDS * (n_tris + 1)
    head = 0
    while head < n_list:
        P = lst[head]
        action, Q, j = 0, -1, head + 1        # 0 paint P, 1 move Q, 2 split
        while j < n_list:
            Q = lst[j]
            j += 1
            counts[0] += 1
            if box[Q, 4] >= box[P, 5] - eps:   # Q wholly nearer: so is the rest of the list
                break
            counts[1] += 1
            if box[Q, 0] >= box[P, 1] - eps or box[P, 0] >= box[Q, 1] - eps:
                continue
            counts[2] += 1
            if box[Q, 2] >= box[P, 3] - eps or box[P, 2] >= box[Q, 3] - eps:
                continue
            counts[3] += 1
            if _beyond(device, tris[P], plane, Q, eps):
                continue
            counts[4] += 1
            if _before(device, tris[Q], plane, P, eps):
                continue
            counts[5] += 1
            if not _projections_overlap(device, tris[P], tris[Q], eps):
                continue
            counts[6] += 1                     # 3'. and 4'.: may Q be painted first?
            q_first = _beyond(device, tris[Q], plane, P, eps) or _before(device, tris[P], plane,
                                                                         Q, eps)
            action = 1 if q_first and not marked[Q] else 2
            j -= 1
            break
        if action == 0 or budget <= 0:
            if action != 0:
                counts[9] += 1
            head += 1
            continue
        budget -= 1
        if action == 1:                        # Q to the head of the list, marked
            counts[7] += 1
            marked[Q] = True
            for k in range(j, head, -1):
                lst[k] = lst[k - 1]
            lst[head] = Q
            continue
        # 2. split: the one that spans the other's plane, else along the silhouette
        counts[8] += 1
        p_from_q = _distances(device, tris[P], plane, Q)
        q_from_p = _distances(device, tris[Q], plane, P)
        if _spans(p_from_q, eps):
            victim, at, cut, d = P, head, plane[Q], p_from_q
        elif _spans(q_from_p, eps):
            victim, at, cut, d = Q, j, plane[P], q_from_p
        else:
            cut = _silhouette_plane(device, tris[P], tris[Q], eps)
            victim, at = Q, j
            if cut[0] == 0.0 and cut[1] == 0.0:
                cut = _silhouette_plane(device, tris[Q], tris[P], eps)
                victim, at = P, head
            if cut[0] == 0.0 and cut[1] == 0.0:     # nothing to cut along: paint P as it is
                counts[8] -= 1
                counts[9] += 1
                head += 1
                continue
            d = np.empty(3)
            for k in range(3):
                p = device[tris[victim][k]]
                d[k] = cut[0] * p[0] + cut[1] * p[1] + cut[2] * p[2] - cut[3]
        pieces, sides, n_pieces, new, n_new = cut_triangle(tris[victim], d, eps)
        device = grow(device, n_points + n_new)
        inv_w = grow(inv_w, n_points + n_new)
        recipe = grow(recipe, n_points + n_new - n_in)
        for k in range(n_new):
            a, b, t = int(new[k, 0]), int(new[k, 1]), new[k, 2]
            for c in range(3):           # component by component: see split.grow
                device[n_points, c] = device[a, c] + t * (device[b, c] - device[a, c])
            inv_w[n_points] = (1.0 - t) * inv_w[a] + t * inv_w[b]
            row = n_points - n_in
            recipe[row, 0], recipe[row, 1] = a, b
            recipe[row, 2] = t * inv_w[b] / ((1.0 - t) * inv_w[a] + t * inv_w[b])
            n_points += 1
        # the victim leaves the list, its pieces go back in by farthest z
        for k in range(at, n_list - 1):
            lst[k] = lst[k + 1]
        n_list -= 1
        tris = grow(tris, n_tris + n_pieces)
        source = grow(source, n_tris + n_pieces)
        box = grow(box, n_tris + n_pieces)
        plane = grow(plane, n_tris + n_pieces)
        marked = grow(marked, n_tris + n_pieces)
        lst = grow(lst, n_list + n_pieces)
        for k in range(n_pieces):
            for c in range(3):
                v = pieces[k, c]
                tris[n_tris, c] = v if v >= 0 else n_points - n_new + (-1 - v)
            source[n_tris] = source[victim]
            marked[n_tris] = False
            _facts(device, tris[n_tris], box, plane, n_tris)
            at = head
            while at < n_list and box[lst[at], 4] <= box[n_tris, 4]:
                at += 1
            for m in range(n_list, at, -1):
                lst[m] = lst[m - 1]
            lst[at] = n_tris
            n_list += 1
            n_tris += 1
    order = lst[:n_list]
    return (device[:n_points], inv_w[:n_points], recipe[:n_points - n_in], tris[order],
            source[order], counts)
