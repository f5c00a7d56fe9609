"""Polygon clipping in homogeneous coordinates, before the divide (``--clipper homogeneous``).

FvDFH 6.5.4, the course notes' alternative to clipping in the canonical volume. Called by
:func:`core.pipeline.clip_polygon.clip_triangles` for the triangles its outcodes neither
accept nor reject; same inputs and outputs as its Sutherland–Hodgman kernel. This module is
the clipper's own steps (a corner into clip space, one plane's stage, back to the canonical
point); the loop over the triangles and the fan they are emitted as are
``clip_polygon.clip_and_fan``'s, which clips here against every plane: the outcodes are
found in the canonical volume, not in clip space.

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

from core.jit import njit

# The planes k, in the outcode bits' order (core.pipeline.clip_polygon, bit 1 << k): above,
# below, right, left, behind, front. A polygon row is the point in clip space.
WIDTH = 4


@njit(cache=True)
def corner(x, y, z, perspective, z_min, h):
    """h = M (x, y, z, 1): the corner in homogeneous clip space."""
    h[0] = x
    h[1] = y
    if perspective:
        h[2] = (z - z_min) / (1.0 + z_min)
        h[3] = -z
    else:
        h[2] = z
        h[3] = 1.0


@njit(cache=True)
def position(h, perspective, p):
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
def clip_against_plane(k, in_h, in_a, in_id, n_in, out_h, out_a, out_id, perspective, z_min):
    """Sutherland–Hodgman's stage in clip space: the polygon in_* against plane k (the planes
    are through 4D's origin: ``perspective`` and ``z_min`` are already in M)."""
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
            for c in range(in_h.shape[1]):        # not out_h[n_out] = in_h[p]: see
                out_h[n_out, c] = in_h[p, c]         # core.visibility.split.grow
            for c in range(in_a.shape[1]):
                out_a[n_out, c] = in_a[p, c]
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
