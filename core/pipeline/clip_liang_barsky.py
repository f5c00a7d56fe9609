"""Polygon clipping with Liang–Barsky's parametric plane tests (``--clipper liang-barsky``).

Called by :func:`core.pipeline.clip_polygon.clip_triangles` for the triangles its outcodes
neither accept nor reject; same inputs, same outputs as its Sutherland–Hodgman kernel.

Why not Liang & Barsky's own polygon algorithm (1983; FvDFH 3.14.1's alternative): it is a
2D algorithm. Its "turning vertices" are the window's corners, added when an edge passes
through a corner region. In the canonical volume the corresponding points are where the
polygon's plane crosses the volume's twelve edges: no fixed set of corners, and finding and
ordering them needs the polygon's plane and an angular sort, which is neither Liang and
Barsky's algorithm nor robust for vertices on the planes. So the polygon goes plane by plane
through Sutherland–Hodgman's re-entrant stages (the result is convex, one polygon per
triangle), and what is Liang–Barsky's is the edge test and the arithmetic:

* Every vertex carries its six boundary values ``q[k]`` (how far it is inside plane k; >= 0
  inside, a point on a plane inside), evaluated once for the triangle's corners. An edge
  s -> p is ``s + t (p - s)``; against plane k it is inside where ``t p_k <= q_k`` with
  ``q_k = q_s[k]`` and ``p_k = q_s[k] - q_p[k]`` (Liang–Barsky's p and q, for any plane).
  ``p_k < 0``: the edge enters the half-space at ``t = q_k / p_k``; ``p_k > 0``: it leaves
  there; ``p_k = 0``: parallel, inside or outside as a whole.
* A crossing's own boundary values come from the same t (the q are linear along the edge),
  so no plane is ever evaluated at a new vertex; its own plane's value is set to 0 and its
  coordinate put exactly on the plane.
* The crossing is computed from the edge's inside end (t measured from there, Liang–Barsky's
  t of the reversed edge when the edge enters), so two triangles sharing an edge get
  bit-identical points, as with Sutherland–Hodgman: the mesh stays watertight.

A triangle with a NaN or infinite coordinate is dropped, as the default clipper drops it.
"""

from __future__ import annotations

import numpy as np

from core.jit import njit

# The planes, in the outcode bits' order (core.pipeline.clip_polygon): above, below, right,
# left, behind, front. Visited front and back first, as Sutherland–Hodgman visits them.
N_PLANES = 6
_ORDER = np.array([5, 4, 0, 1, 2, 3], dtype=np.int64)
MAX_POLYGON = 9  # a triangle clipped by six planes has at most 3 + 6 vertices
MAX_FAN = MAX_POLYGON - 2


@njit(cache=True)
def _boundary_values(x, y, z, perspective, z_min, q):
    """q[k]: how far (x, y, z) is inside plane k (>= 0 inside)."""
    high = -z if perspective else 1.0
    low = z if perspective else -1.0
    q[0] = high - y
    q[1] = y - low
    q[2] = high - x
    q[3] = x - low
    q[4] = z + 1.0
    q[5] = (z_min if perspective else 0.0) - z


@njit(cache=True)
def _put_on_plane(k, p, perspective, z_min):
    """Set the coordinate plane k fixes (the crossing lies on it; remove the rounding)."""
    if k == 0:
        p[1] = -p[2] if perspective else 1.0
    elif k == 1:
        p[1] = p[2] if perspective else -1.0
    elif k == 2:
        p[0] = -p[2] if perspective else 1.0
    elif k == 3:
        p[0] = p[2] if perspective else -1.0
    elif k == 4:
        p[2] = -1.0
    else:
        p[2] = z_min if perspective else 0.0


@njit(cache=True)
def _crossing(k, t, inside, outside, in_p, in_a, in_q, out_p, out_a, out_q, n_out,
              perspective, z_min):
    """Vertex n_out of the output: the point at t from vertex ``inside`` towards ``outside``,
    its attributes and boundary values alike."""
    for c in range(3):
        out_p[n_out, c] = in_p[inside, c] + t * (in_p[outside, c] - in_p[inside, c])
    for j in range(in_a.shape[1]):
        out_a[n_out, j] = in_a[inside, j] + t * (in_a[outside, j] - in_a[inside, j])
    for j in range(N_PLANES):
        out_q[n_out, j] = in_q[inside, j] + t * (in_q[outside, j] - in_q[inside, j])
    out_q[n_out, k] = 0.0
    _put_on_plane(k, out_p[n_out], perspective, z_min)


@njit(cache=True)
def _clip_against_plane(k, in_p, in_a, in_q, in_id, n_in, out_p, out_a, out_q, out_id,
                        perspective, z_min):
    """One stage: the polygon in_* (n_in vertices) against plane k, edge by edge with
    Liang–Barsky's test. Returns the output vertex count; a crossing gets id -1."""
    n_out = 0
    s = n_in - 1
    for p in range(n_in):
        q_k = in_q[s, k]                 # the edge s -> p is inside where t p_k <= q_k
        p_k = in_q[s, k] - in_q[p, k]    # < 0 entering, > 0 leaving, 0 parallel
        p_inside = in_q[p, k] >= 0.0     # p itself (t = 1) passes the test
        if p_k < 0.0 and q_k < 0.0 and p_inside:    # enters at t = q_k / p_k, in (0, 1]
            # computed from p, the inside end: 1 - t = -q_p / p_k
            _crossing(k, -in_q[p, k] / p_k, p, s, in_p, in_a, in_q, out_p, out_a, out_q,
                      n_out, perspective, z_min)
            out_id[n_out] = -1
            n_out += 1
        if p_inside:
            out_p[n_out] = in_p[p]
            out_a[n_out] = in_a[p]
            out_q[n_out] = in_q[p]
            out_id[n_out] = in_id[p]
            n_out += 1
        elif p_k > 0.0 and q_k >= 0.0:  # leaves at t = q_k / p_k, in [0, 1), from s inside
            _crossing(k, q_k / p_k, s, p, in_p, in_a, in_q, out_p, out_a, out_q, n_out,
                      perspective, z_min)
            out_id[n_out] = -1
            n_out += 1
        s = p
    return n_out


@njit(cache=True)
def liang_barsky_polygons(points, triangles, attrs, codes, todo, perspective, z_min):
    """Clip the triangles listed in ``todo``; returns new points, attrs, triangles, sources
    (new vertices numbered from len(points) on; a surviving input vertex keeps its index)."""
    n_attrs = attrs.shape[1]
    n_points = points.shape[0]
    m = todo.shape[0]
    new_points = np.empty((m * MAX_POLYGON, 3))
    new_attrs = np.empty((m * MAX_POLYGON, n_attrs))
    new_triangles = np.empty((m * MAX_FAN, 3), np.int64)
    new_source = np.empty(m * MAX_FAN, np.int64)
    poly_p = np.empty((2, MAX_POLYGON, 3))             # two polygons, swapped after each plane
    poly_a = np.empty((2, MAX_POLYGON, n_attrs))
    poly_q = np.empty((2, MAX_POLYGON, N_PLANES))
    poly_id = np.empty((2, MAX_POLYGON), np.int64)
    index = np.empty(MAX_POLYGON, np.int64)
    n_new_points = 0
    n_new_triangles = 0
    for i in range(m):
        t = todo[i]
        finite = True
        crossed = 0                                    # the planes some corner is outside of
        for c in range(3):
            v = triangles[t, c]
            poly_p[0, c] = points[v]
            poly_a[0, c] = attrs[v]
            poly_id[0, c] = v
            crossed |= codes[v]
            for d in range(3):
                finite &= np.isfinite(points[v, d])
            _boundary_values(points[v, 0], points[v, 1], points[v, 2], perspective, z_min,
                             poly_q[0, c])
        if not finite:
            continue                                   # nothing sensible to draw
        n = 3
        cur = 0
        for k in _ORDER:
            if crossed & (1 << k) and n > 0:
                n = _clip_against_plane(k, poly_p[cur], poly_a[cur], poly_q[cur], poly_id[cur], n,
                                        poly_p[1 - cur], poly_a[1 - cur], poly_q[1 - cur],
                                        poly_id[1 - cur], perspective, z_min)
                cur = 1 - cur
        if n < 3:
            continue                                   # gone, or only an edge or a point left
        for j in range(n):
            if poly_id[cur, j] >= 0:
                index[j] = poly_id[cur, j]
            else:
                new_points[n_new_points] = poly_p[cur, j]
                new_attrs[n_new_points] = poly_a[cur, j]
                index[j] = n_points + n_new_points
                n_new_points += 1
        for j in range(1, n - 1):                      # fan the convex polygon from vertex 0
            new_triangles[n_new_triangles, 0] = index[0]
            new_triangles[n_new_triangles, 1] = index[j]
            new_triangles[n_new_triangles, 2] = index[j + 1]
            new_source[n_new_triangles] = t
            n_new_triangles += 1
    return (new_points[:n_new_points], new_attrs[:n_new_points],
            new_triangles[:n_new_triangles], new_source[:n_new_triangles])
