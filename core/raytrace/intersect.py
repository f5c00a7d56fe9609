"""Ray–primitive intersection (the notes of April 4: "In RT, the hard part is to determine
intersections with objects"), one ray and one primitive at a time, in numba.

A ray is ``P(t) = O + t D``; ``D`` need not be unit length (the parameter ``t`` is then in units
of ``|D|``). Every function returns the ray parameter of the hit, or ``NO_HIT`` (+inf) when
there is none in ``(t_min, t_max)``.

- Triangle: Möller–Trumbore (1997), the notes' "plane of the triangle, then inside?" done in
  one step: solve ``O + t D = V0 + u E1 + v E2`` by Cramer's rule, ``E1 = V1 − V0``,
  ``E2 = V2 − V0``; the hit is inside when ``u >= 0, v >= 0, u + v <= 1``. The barycentric
  weights ``(u, v)`` of V1 and V2 come back with ``t``: they interpolate the vertex normals
  exactly as the z-buffer's perspective-correct weights do. A degenerate (zero-area)
  triangle has determinant 0 and is never hit.
- Sphere: the notes' quadratic ``|D|² t² + 2 D·(O − C) t + |O − C|² − r² = 0`` — no real
  root: no hit; two roots: the smaller one in range (the one nearer the ray's origin; from
  inside the sphere the larger one). Solved in the stable form: the discriminant from the
  centre's perpendicular distance to the ray and the second root as ``c / q`` (no
  cancellation when the sphere is far away or tiny).
- Plane ``A x + B y + C z + D = 0``: the notes' ``t = −(A x0 + B y0 + C z0 + D) /
  (A Δx + B Δy + C Δz)``; a denominator of 0 means the ray is parallel to the plane: no hit
  (even when the ray lies in it: a plane seen edge-on covers no area).
"""

from __future__ import annotations

import math

import numpy as np
from core.jit import njit

NO_HIT = np.inf


@njit(cache=True, inline="always")
def triangle(ox, oy, oz, dx, dy, dz, v0, e1, e2, t_min, t_max):
    """``(t, u, v)`` of the ray's hit on triangle ``V0, V0 + E1, V0 + E2`` (Möller–Trumbore);
    ``t = NO_HIT`` when it misses, is parallel, or the triangle is degenerate."""
    # P = D x E2; det = E1 . P (zero: the ray lies in the triangle's plane, or no area).
    px = dy * e2[2] - dz * e2[1]
    py = dz * e2[0] - dx * e2[2]
    pz = dx * e2[1] - dy * e2[0]
    det = e1[0] * px + e1[1] * py + e1[2] * pz
    if det == 0.0 or not math.isfinite(det):
        return NO_HIT, 0.0, 0.0
    inv_det = 1.0 / det
    sx, sy, sz = ox - v0[0], oy - v0[1], oz - v0[2]
    u = (sx * px + sy * py + sz * pz) * inv_det
    if u < 0.0 or u > 1.0:
        return NO_HIT, 0.0, 0.0
    qx = sy * e1[2] - sz * e1[1]
    qy = sz * e1[0] - sx * e1[2]
    qz = sx * e1[1] - sy * e1[0]
    v = (dx * qx + dy * qy + dz * qz) * inv_det
    if v < 0.0 or u + v > 1.0:
        return NO_HIT, 0.0, 0.0
    t = (e2[0] * qx + e2[1] * qy + e2[2] * qz) * inv_det
    if not (t_min < t < t_max):
        return NO_HIT, 0.0, 0.0
    return t, u, v


@njit(cache=True, inline="always")
def triangle_run(ox, oy, oz, dx, dy, dz, tri, first, n, t_min, t_max, hits):
    """:func:`triangle` on columns ``first .. first + n − 1`` of ``tri`` ``(9, T)`` (rows V0,
    E1, E2 by component), each one's ``t`` (or ``NO_HIT``) into ``hits[:n]``. The same
    arithmetic in the same order, so the same ``t`` to the bit (tests/core/raytrace holds
    them together), but written without a branch: the columns are consecutive in
    memory, so LLVM tests four triangles at once in the AVX registers (one at a time, a
    BVH leaf's tests cost about twice as long)."""
    start = np.uint64(first)            # unsigned: no wrap-around test for a negative index
    for j in range(n):
        k = start + np.uint64(j)
        e2x, e2y, e2z = tri[6, k], tri[7, k], tri[8, k]
        px = dy * e2z - dz * e2y
        py = dz * e2x - dx * e2z
        pz = dx * e2y - dy * e2x
        e1x, e1y, e1z = tri[3, k], tri[4, k], tri[5, k]
        det = e1x * px + e1y * py + e1z * pz
        inv_det = np.reciprocal(det)    # 1 / det; ``/`` would test det == 0 and raise (a branch)
        sx, sy, sz = ox - tri[0, k], oy - tri[1, k], oz - tri[2, k]
        u = (sx * px + sy * py + sz * pz) * inv_det
        qx = sy * e1z - sz * e1y
        qy = sz * e1x - sx * e1z
        qz = sx * e1y - sy * e1x
        v = (dx * qx + dy * qy + dz * qz) * inv_det
        t = (e2x * qx + e2y * qy + e2z * qz) * inv_det
        # det 0 or not finite, u or v outside the triangle, t outside the range: no hit
        # (a NaN fails every comparison).
        hit = ((det != 0.0) & (abs(det) < np.inf) & (u >= 0.0) & (u <= 1.0) & (v >= 0.0)
               & (u + v <= 1.0) & (t_min < t) & (t < t_max))
        hits[j] = t if hit else NO_HIT


@njit(cache=True, inline="always")
def sphere(ox, oy, oz, dx, dy, dz, cx, cy, cz, radius, t_min, t_max):
    """The ray parameter of the nearest hit on the sphere inside ``(t_min, t_max)``."""
    a = dx * dx + dy * dy + dz * dz
    if not a > 0.0:
        return NO_HIT
    fx, fy, fz = ox - cx, oy - cy, oz - cz
    half_b = (fx * dx + fy * dy + fz * dz) / a          # (D . (O - C)) / |D|^2
    # Squared distance of the centre from the ray (scaled by |D|^2 below): accurate far away.
    px, py, pz = fx - half_b * dx, fy - half_b * dy, fz - half_b * dz
    disc = radius * radius - (px * px + py * py + pz * pz)
    if disc < 0.0:                                      # no real root: the ray misses
        return NO_HIT
    c = (fx * fx + fy * fy + fz * fz - radius * radius) / a
    q = -(half_b + math.copysign(math.sqrt(disc / a), half_b))
    if q == 0.0:                                        # origin at the centre-grazing point
        t1, t2 = 0.0, 0.0
    else:
        t1, t2 = min(c / q, q), max(c / q, q)
    if t_min < t1 < t_max:
        return t1
    if t_min < t2 < t_max:
        return t2
    return NO_HIT


@njit(cache=True, inline="always")
def plane(ox, oy, oz, dx, dy, dz, a, b, c, d, t_min, t_max):
    """The ray parameter where the ray meets ``a x + b y + c z + d = 0``."""
    denominator = a * dx + b * dy + c * dz
    if denominator == 0.0:                              # the ray and the plane are parallel
        return NO_HIT
    t = -(a * ox + b * oy + c * oz + d) / denominator
    if t_min < t < t_max:
        return t
    return NO_HIT
