"""Cutting a triangle by a plane: what the BSP tree and the depth sort do to a polygon that
spans another's plane (FvDFH 15.5.1, 15.5.2).

A triangle whose vertices have signed distances ``d0, d1, d2`` from the plane is walked edge
by edge (Sutherland–Hodgman against one plane, kept on both sides): a vertex on the plane
(``|d| <= eps``) goes to both pieces, an edge whose ends lie on opposite sides gets a new
vertex at ``t = d_a / (d_a - d_b)``. Each piece (3 or 4 vertices) keeps the triangle's
winding and is fanned back into triangles. The new vertex is always computed from the lower
vertex index to the higher, so two triangles that share an edge get the same point, bit for
bit, and the mesh stays watertight.
"""

from __future__ import annotations

import numpy as np
from core.jit import njit


@njit(cache=True, nogil=True)
def side(d, eps):
    """+1 in front of the plane, -1 behind, 0 on it (within ``eps``)."""
    if d > eps:
        return 1
    if d < -eps:
        return -1
    return 0


@njit(cache=True, nogil=True)
def cut_triangle(v, d, eps):
    """The pieces of the triangle with vertex ids ``v`` (3,) and signed distances ``d`` (3,).

    Returns ``(pieces (4, 3), sides (4,), n_pieces, new (2, 3), n_new)``: each piece is a
    triangle of vertex ids on side +1 (front) or -1 (back); an id ``-1 - k`` stands for the
    k-th new vertex, ``P_a + t (P_b - P_a)`` with ``(a, b, t) = new[k]`` (``a < b``).
    """
    front = np.empty(4, np.int64)
    back = np.empty(4, np.int64)
    new = np.empty((2, 3))
    nf = 0
    nb = 0
    n_new = 0
    for k in range(3):
        a, b = v[k], v[(k + 1) % 3]
        da, db = d[k], d[(k + 1) % 3]
        sa, sb = side(da, eps), side(db, eps)
        if sa >= 0:
            front[nf] = a
            nf += 1
        if sa <= 0:
            back[nb] = a
            nb += 1
        if sa * sb < 0:                      # the edge crosses the plane
            if a < b:
                new[n_new, 0], new[n_new, 1], new[n_new, 2] = a, b, da / (da - db)
            else:
                new[n_new, 0], new[n_new, 1], new[n_new, 2] = b, a, db / (db - da)
            front[nf] = -1 - n_new
            nf += 1
            back[nb] = -1 - n_new
            nb += 1
            n_new += 1
    pieces = np.empty((4, 3), np.int64)
    sides = np.empty(4, np.int64)
    n = _fan(front, nf, pieces, 0)
    sides[:n] = 1
    m = _fan(back, nb, pieces, n)
    sides[n:m] = -1
    return pieces, sides, m, new, n_new


@njit(cache=True, nogil=True)
def _fan(polygon, n, out, count):
    """Fan the convex ``polygon`` of ``n`` ids into ``out`` from row ``count``; returns the
    new row count."""
    for k in range(1, n - 1):
        out[count, 0] = polygon[0]
        out[count, 1] = polygon[k]
        out[count, 2] = polygon[k + 1]
        count += 1
    return count


@njit(cache=True, nogil=True)
def grow(a, need):
    """``a``, or a copy at least twice as long when ``need`` rows do not fit (the splits
    of a BSP build or a depth sort add triangles as they go)."""
    if need <= a.shape[0]:
        return a
    # concatenated, not assigned into a slice: numba's array-to-array assignment compiles a
    # shape-mismatch error path with its string formatting (2-3 s in every process)
    more = np.empty((max(need, 2 * a.shape[0]) - a.shape[0],) + a.shape[1:], a.dtype)
    return np.concatenate((a, more))
