"""3D clipping of triangles in the canonical view volumes (FvDFH 3.14.1 and 6.5.3).

Takes canonical-volume points ``(V, 3)`` (after N_per / N_par, before any divide), triangles
``(T, 3)`` and per-vertex attributes ``(V, K)``; returns the visible parts as triangles over an
extended vertex array, with each attribute interpolated at every crossing by the same
parameter t, and ``source`` naming the input triangle each output triangle came from.

1. Outcodes per vertex (:func:`core.clip.outcodes`, the same six bits as the line clipper).
2. Trivial accept (OR of the three codes is 0): the triangle passes through untouched, over
   the input vertices. Trivial reject (AND is not 0): dropped.
3. Only the rest go through Sutherland–Hodgman, plane by plane (only the planes some vertex
   violates), and the convex result is fanned back into triangles.

A point exactly on a plane is inside. Intersections are computed from the inside vertex towards
the outside one, so two triangles sharing an edge get bit-identical crossing points and stay
watertight. A triangle crossing the eye plane is clipped here, before any divide, so no NaN
reaches the projection.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from core.clip import outcodes, planes

# A triangle clipped by six planes has at most 3 + 6 vertices.
MAX_POLYGON = 9


@dataclass
class ClippedTriangles:
    points: np.ndarray      # (V', 3) canonical coordinates; the input points come first
    triangles: np.ndarray   # (T', 3) int64
    attrs: np.ndarray       # (V', K)
    source: np.ndarray      # (T',) int64: the input triangle of each output triangle


@njit(cache=True)
def _sutherland_hodgman(points, attrs, triangles, work, codes_or, pl, out_points, out_attrs,
                        out_triangles, out_source):
    """Clip each triangle ``work[k]`` against the planes in ``codes_or[k]``.

    Writes new vertices into ``out_points`` / ``out_attrs`` and fanned triangles (indexing
    those new vertices) into ``out_triangles``; returns (vertices written, triangles written).
    """
    k_attr = attrs.shape[1]
    poly = np.empty((MAX_POLYGON + 1, 3))
    poly_a = np.empty((MAX_POLYGON + 1, k_attr))
    nxt = np.empty((MAX_POLYGON + 1, 3))
    nxt_a = np.empty((MAX_POLYGON + 1, k_attr))
    nv = 0
    nt = 0
    for k in range(work.shape[0]):
        t = work[k]
        count = 3
        for c in range(3):
            poly[c] = points[triangles[t, c]]
            poly_a[c] = attrs[triangles[t, c]]
        for i in range(6):
            if (codes_or[k] >> i) & 1 == 0 or count == 0:
                continue
            a, b, cc, d = pl[i, 0], pl[i, 1], pl[i, 2], pl[i, 3]
            m = 0
            s = count - 1                               # S: the previous vertex, P: this one
            f_s = a * poly[s, 0] + b * poly[s, 1] + cc * poly[s, 2] + d
            for p in range(count):
                f_p = a * poly[p, 0] + b * poly[p, 1] + cc * poly[p, 2] + d
                if (f_p <= 0.0) != (f_s <= 0.0):        # the edge S-P crosses plane i
                    if f_s <= 0.0:
                        inside, outside, f_in, f_out = s, p, f_s, f_p
                    else:
                        inside, outside, f_in, f_out = p, s, f_p, f_s
                    u = f_in / (f_in - f_out)
                    for c in range(3):
                        nxt[m, c] = poly[inside, c] + u * (poly[outside, c] - poly[inside, c])
                    for c in range(k_attr):
                        nxt_a[m, c] = poly_a[inside, c] + u * (poly_a[outside, c] - poly_a[inside, c])
                    m += 1
                if f_p <= 0.0:
                    nxt[m] = poly[p]
                    nxt_a[m] = poly_a[p]
                    m += 1
                s, f_s = p, f_p
            count = m
            poly[:count] = nxt[:count]
            poly_a[:count] = nxt_a[:count]
        if count < 3:
            continue
        for c in range(count):
            out_points[nv + c] = poly[c]
            out_attrs[nv + c] = poly_a[c]
        for c in range(1, count - 1):                   # fan from the first vertex
            out_triangles[nt, 0] = nv
            out_triangles[nt, 1] = nv + c
            out_triangles[nt, 2] = nv + c + 1
            out_source[nt] = t
            nt += 1
        nv += count
    return nv, nt


def clip_triangles(points: np.ndarray, triangles: np.ndarray, attrs: np.ndarray | None,
                   projection: str, z_min: float = 0.0) -> ClippedTriangles:
    """Clip ``triangles`` over ``points`` to the canonical volume of ``projection``."""
    points = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64).reshape(-1, 3)
    if attrs is None:
        attrs = np.zeros((len(points), 0))
    attrs = np.ascontiguousarray(attrs, dtype=np.float64).reshape(len(points), -1)
    codes = outcodes(points, projection, z_min)[triangles]            # (T, 3)
    code_or = codes[:, 0] | codes[:, 1] | codes[:, 2]
    code_and = codes[:, 0] & codes[:, 1] & codes[:, 2]
    accept = code_or == 0
    if accept.all():
        return ClippedTriangles(points, triangles, attrs, np.arange(len(triangles)))
    work = np.flatnonzero(~accept & (code_and == 0))
    kept = np.flatnonzero(accept)
    if len(work) == 0:
        return ClippedTriangles(points, triangles[kept], attrs, kept)
    new_points = np.empty((len(work) * MAX_POLYGON, 3))
    new_attrs = np.empty((len(work) * MAX_POLYGON, attrs.shape[1]))
    new_triangles = np.empty((len(work) * (MAX_POLYGON - 2), 3), dtype=np.int64)
    new_source = np.empty(len(work) * (MAX_POLYGON - 2), dtype=np.int64)
    nv, nt = _sutherland_hodgman(points, attrs, triangles, work, code_or[work].astype(np.int64),
                                 planes(projection, z_min), new_points, new_attrs,
                                 new_triangles, new_source)
    return ClippedTriangles(
        points=np.concatenate([points, new_points[:nv]]),
        triangles=np.concatenate([triangles[kept], new_triangles[:nt] + len(points)]),
        attrs=np.concatenate([attrs, new_attrs[:nv]]),
        source=np.concatenate([kept, new_source[:nt]]),
    )
