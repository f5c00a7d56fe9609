"""Polygon clipping in homogeneous coordinates, before the divide (``--clipper homogeneous``).

FvDFH 6.5.4, the course notes' alternative to clipping in the canonical volume. Called by
:func:`core.pipeline.clip_polygon.clip_triangles` for the triangles its outcodes neither
accept nor reject; same inputs and outputs as its Sutherland–Hodgman kernel.

Each corner (x, y, z) of the canonical volume is taken into clip space by the matrix the
pipeline projects with anyway, FvDFH's perspective-to-parallel M (pipeline.md; the identity
for the parallel volume):

    X = x,  Y = y,  Z = (z - z_min) / (1 + z_min),  W = -z        (W = 1 for parallel)

and Sutherland–Hodgman clips the polygon there against the six planes through the origin of
4D, each written ``e >= 0`` inside:

=====  ==========  ===============================
plane  e(X,Y,Z,W)  canonical perspective plane
=====  ==========  ===============================
above  W - Y       y <= -z
below  W + Y       y >= z
right  W - X       x <= -z
left   W + X       x >= z
back   W + Z       z >= -1
front  -Z          z <= z_min
=====  ==========  ===============================

Nothing is divided by W while clipping, so a polygon crossing the eye plane (W = 0) is cut
like any other; inside every plane W >= 0, so nothing behind the eye survives. Positions
(4D) and attributes are interpolated with the same t; M is linear, so t is the parameter of
the same canonical point. The clipped vertices go back to canonical coordinates exactly
(x = X, y = Y, z = -W; for parallel x = X / W with W = 1) so that the projection stage, which
applies M again, is shared by every clipper. Each crossing is put exactly on its plane in
clip space, computed from the edge's inside end (watertight across shared edges).

A triangle with a NaN or infinite coordinate is dropped, as the default clipper drops it.
"""

from __future__ import annotations

import numpy as np

from core.jit import njit

# The planes, in the outcode bits' order (core.pipeline.clip_polygon): above, below, right,
# left, behind, front. Visited front and back first, as Sutherland–Hodgman visits them.
_ORDER = np.array([5, 4, 0, 1, 2, 3], dtype=np.int64)
MAX_POLYGON = 9  # a triangle clipped by six planes has at most 3 + 6 vertices
MAX_FAN = MAX_POLYGON - 2


@njit(cache=True)
def _to_clip_space(x, y, z, perspective, z_min, h):
    """h = M (x, y, z, 1): the point in homogeneous clip space."""
    h[0] = x
    h[1] = y
    if perspective:
        h[2] = (z - z_min) / (1.0 + z_min)
        h[3] = -z
    else:
        h[2] = z
        h[3] = 1.0


@njit(cache=True)
def _from_clip_space(h, perspective, p):
    """p = the canonical point of clip-space h (the inverse of M, no division for perspective)."""
    if perspective:
        p[0] = h[0]
        p[1] = h[1]
        p[2] = -h[3]
    else:
        p[0] = h[0] / h[3]
        p[1] = h[1] / h[3]
        p[2] = h[2] / h[3]


@njit(cache=True)
def _edge_value(k, h):
    """e_k(X, Y, Z, W): >= 0 inside plane k."""
    if k == 0:
        return h[3] - h[1]
    if k == 1:
        return h[3] + h[1]
    if k == 2:
        return h[3] - h[0]
    if k == 3:
        return h[3] + h[0]
    if k == 4:
        return h[3] + h[2]
    return -h[2]


@njit(cache=True)
def _put_on_plane(k, h):
    """Set the clip-space coordinate plane k fixes (remove the interpolation's rounding)."""
    if k == 0:
        h[1] = h[3]
    elif k == 1:
        h[1] = -h[3]
    elif k == 2:
        h[0] = h[3]
    elif k == 3:
        h[0] = -h[3]
    elif k == 4:
        h[2] = -h[3]
    else:
        h[2] = 0.0


@njit(cache=True)
def _intersect(k, inside_h, inside_a, e_in, outside_h, outside_a, e_out, out_h, out_a):
    """The crossing of edge inside -> outside with plane k, in clip space."""
    t = e_in / (e_in - e_out)  # e_in >= 0 > e_out: 0 <= t < 1, never 0/0
    for c in range(4):
        out_h[c] = inside_h[c] + t * (outside_h[c] - inside_h[c])
    for j in range(inside_a.shape[0]):
        out_a[j] = inside_a[j] + t * (outside_a[j] - inside_a[j])
    _put_on_plane(k, out_h)


@njit(cache=True)
def _clip_against_plane(k, in_h, in_a, in_id, n_in, out_h, out_a, out_id):
    """Sutherland–Hodgman's stage in clip space: the polygon in_* against plane k."""
    n_out = 0
    s = n_in - 1
    e_s = _edge_value(k, in_h[s])
    for p in range(n_in):
        e_p = _edge_value(k, in_h[p])
        if e_p >= 0.0:
            if e_s < 0.0:  # entering: the crossing, computed from the inside end p
                _intersect(k, in_h[p], in_a[p], e_p, in_h[s], in_a[s], e_s, out_h[n_out],
                           out_a[n_out])
                out_id[n_out] = -1
                n_out += 1
            out_h[n_out] = in_h[p]
            out_a[n_out] = in_a[p]
            out_id[n_out] = in_id[p]
            n_out += 1
        elif e_s >= 0.0:  # leaving: the crossing, computed from the inside end s
            _intersect(k, in_h[s], in_a[s], e_s, in_h[p], in_a[p], e_p, out_h[n_out],
                       out_a[n_out])
            out_id[n_out] = -1
            n_out += 1
        s = p
        e_s = e_p
    return n_out


@njit(cache=True)
def homogeneous_polygons(points, triangles, attrs, codes, todo, perspective, z_min):
    """Clip the triangles listed in ``todo``; returns new points, attrs, triangles, sources
    (new vertices numbered from len(points) on; a surviving input vertex keeps its index)."""
    n_attrs = attrs.shape[1]
    n_points = points.shape[0]
    m = todo.shape[0]
    new_points = np.empty((m * MAX_POLYGON, 3))
    new_attrs = np.empty((m * MAX_POLYGON, n_attrs))
    new_triangles = np.empty((m * MAX_FAN, 3), np.int64)
    new_source = np.empty(m * MAX_FAN, np.int64)
    poly_h = np.empty((2, MAX_POLYGON, 4))             # two polygons, swapped after each plane
    poly_a = np.empty((2, MAX_POLYGON, n_attrs))
    poly_id = np.empty((2, MAX_POLYGON), np.int64)
    index = np.empty(MAX_POLYGON, np.int64)
    n_new_points = 0
    n_new_triangles = 0
    for i in range(m):
        t = todo[i]
        finite = True
        for c in range(3):
            v = triangles[t, c]
            _to_clip_space(points[v, 0], points[v, 1], points[v, 2], perspective, z_min,
                           poly_h[0, c])
            poly_a[0, c] = attrs[v]
            poly_id[0, c] = v
            for d in range(3):
                finite &= np.isfinite(points[v, d])
        if not finite:
            continue                                   # nothing sensible to draw
        n = 3
        cur = 0
        for k in _ORDER:                               # every plane: the outcodes are canonical
            if n > 0:
                n = _clip_against_plane(k, poly_h[cur], poly_a[cur], poly_id[cur], n,
                                        poly_h[1 - cur], poly_a[1 - cur], poly_id[1 - cur])
                cur = 1 - cur
        if n < 3:
            continue                                   # gone, or only an edge or a point left
        for j in range(n):
            if poly_id[cur, j] >= 0:
                index[j] = poly_id[cur, j]
            else:
                _from_clip_space(poly_h[cur, j], perspective, new_points[n_new_points])
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
