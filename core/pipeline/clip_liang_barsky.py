"""Polygon clipping with Liang–Barsky's parametric plane tests (``--clipper liang-barsky``).

Called by :func:`core.pipeline.clip_polygon.clip_triangles` for the triangles its outcodes
neither accept nor reject; same inputs, same outputs as its Sutherland–Hodgman kernel. This
module is the clipper's own steps (a corner's row, one plane's stage); the loop over the
triangles and the fan they are emitted as are ``clip_polygon.clip_and_fan``'s.

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

from core.jit import njit

# The planes k, in the outcode bits' order (core.pipeline.clip_polygon, bit 1 << k): above,
# below, right, left, behind, front.
N_PLANES = 6
# A polygon row (core.pipeline.clip_polygon.clip_and_fan): the position, then the six
# boundary values from column Q on (so the row's canonical point is its first three columns,
# as Sutherland–Hodgman's row is).
Q = 3
WIDTH = Q + N_PLANES


@njit(cache=True)
def corner(x, y, z, perspective, z_min, row):
    """A corner's row: (x, y, z) and q[k], how far it is inside plane k (>= 0 inside)."""
    high = -z if perspective else 1.0
    low = z if perspective else -1.0
    row[0] = x
    row[1] = y
    row[2] = z
    row[Q] = high - y
    row[Q + 1] = y - low
    row[Q + 2] = high - x
    row[Q + 3] = x - low
    row[Q + 4] = z + 1.0
    row[Q + 5] = (z_min if perspective else 0.0) - z


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
def _crossing(k, t, inside, outside, in_rows, in_a, out_rows, out_a, n_out, perspective, z_min):
    """Vertex n_out of the output: the point at t from vertex ``inside`` towards ``outside``,
    its attributes and boundary values alike (the q are linear along the edge)."""
    for c in range(WIDTH):
        out_rows[n_out, c] = in_rows[inside, c] + t * (in_rows[outside, c] - in_rows[inside, c])
    for j in range(in_a.shape[1]):
        out_a[n_out, j] = in_a[inside, j] + t * (in_a[outside, j] - in_a[inside, j])
    out_rows[n_out, Q + k] = 0.0
    _put_on_plane(k, out_rows[n_out], perspective, z_min)


@njit(cache=True)
def clip_against_plane(k, in_rows, in_a, in_id, n_in, out_rows, out_a, out_id, perspective,
                       z_min):
    """One stage: the polygon in_* (n_in vertices) against plane k, edge by edge with
    Liang–Barsky's test. Returns the output vertex count; a crossing gets id -1."""
    n_out = 0
    s = n_in - 1
    for p in range(n_in):
        q_k = in_rows[s, Q + k]               # the edge s -> p is inside where t p_k <= q_k
        p_k = q_k - in_rows[p, Q + k]         # < 0 entering, > 0 leaving, 0 parallel
        p_inside = in_rows[p, Q + k] >= 0.0   # p itself (t = 1) passes the test
        if p_k < 0.0 and q_k < 0.0 and p_inside:    # enters at t = q_k / p_k, in (0, 1]
            # computed from p, the inside end: 1 - t = -q_p / p_k
            _crossing(k, -in_rows[p, Q + k] / p_k, p, s, in_rows, in_a, out_rows, out_a, n_out,
                      perspective, z_min)
            out_id[n_out] = -1
            n_out += 1
        if p_inside:
            for c in range(in_rows.shape[1]):     # not out_rows[n_out] = in_rows[p]: see
                out_rows[n_out, c] = in_rows[p, c]   # core.visibility.split.grow
            for c in range(in_a.shape[1]):
                out_a[n_out, c] = in_a[p, c]
            out_id[n_out] = in_id[p]
            n_out += 1
        elif p_k > 0.0 and q_k >= 0.0:  # leaves at t = q_k / p_k, in [0, 1), from s inside
            _crossing(k, q_k / p_k, s, p, in_rows, in_a, out_rows, out_a, n_out, perspective,
                      z_min)
            out_id[n_out] = -1
            n_out += 1
        s = p
    return n_out
