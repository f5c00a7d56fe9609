"""Form factors by ray casting (Wallace, Elmquist, Haines 1989), through the ray tracer's BVH.

Receiver-centred, as Wallace's: for each element's centre x (normal n) and the shooting
patch A_p, the form factor from the differential area at x to the patch is

    F(dA_x → A_p) = F_unoccluded(x, A_p) · (visible samples of A_p) / (samples above x's plane)

where ``F_unoccluded`` is the closed form of a point to a polygon (Lambert; FvDFH 16.13.2,
Baum et al. 1989): ``(1 / 2π) Σ_edges γ_k (n · (R_k × R_k+1) / |R_k × R_k+1|)`` over the patch
clipped to the half-space above x's tangent plane, and the visibility is a shadow ray
(:func:`core.raytrace.bvh.occluded`) from x to each of a fixed set of stratified points on the
patch. A patch glows only on its front side. Unlike Wallace's disc approximation the
unoccluded part is exact, so only visibility is sampled.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit, prange
from core.raytrace.bvh import new_stack, occluded


@njit(cache=True)
def _clip_to_plane(tri, x, n, poly):
    """The triangle ``tri`` (3, 3) clipped to (p − x) · n >= 0 into ``poly`` (4, 3); returns
    the number of corners (Sutherland–Hodgman against one plane)."""
    count = 0
    for i in range(3):
        a, b = tri[i], tri[(i + 1) % 3]
        da = (a[0] - x[0]) * n[0] + (a[1] - x[1]) * n[1] + (a[2] - x[2]) * n[2]
        db = (b[0] - x[0]) * n[0] + (b[1] - x[1]) * n[1] + (b[2] - x[2]) * n[2]
        if da >= 0.0:
            for c in range(3):          # not poly[count] = a: numba's array assignment
                poly[count, c] = a[c]   # compiles a shape-error path (2 s per process)
            count += 1
        if (da >= 0.0) != (db >= 0.0):
            t = da / (da - db)
            for c in range(3):
                poly[count, c] = a[c] + t * (b[c] - a[c])
            count += 1
    return count


@njit(cache=True)
def point_to_polygon(x, n, poly, count):
    """Lambert's closed form: F from the differential area at ``x`` (normal ``n``) to the
    polygon ``poly[:count]`` lying above its tangent plane."""
    total = 0.0
    for i in range(count):
        ax, ay, az = poly[i, 0] - x[0], poly[i, 1] - x[1], poly[i, 2] - x[2]
        j = (i + 1) % count
        bx, by, bz = poly[j, 0] - x[0], poly[j, 1] - x[1], poly[j, 2] - x[2]
        la = math.sqrt(ax * ax + ay * ay + az * az)
        lb = math.sqrt(bx * bx + by * by + bz * bz)
        if la == 0.0 or lb == 0.0:
            continue
        cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
        lc = math.sqrt(cx * cx + cy * cy + cz * cz)
        if lc == 0.0:
            continue
        cos_g = (ax * bx + ay * by + az * bz) / (la * lb)
        gamma = math.acos(min(1.0, max(-1.0, cos_g)))
        total += gamma * (n[0] * cx + n[1] * cy + n[2] * cz) / lc
    return abs(total) / (2.0 * math.pi)


@njit(cache=True, parallel=True, nogil=True)
def _to_patch(bvh, points, normals, tri, patch_normal, samples, offset, out):
    for e in prange(points.shape[0]):
        x, n = points[e], normals[e]
        # The patch glows on its front side only: x must lie in front of its plane.
        front = ((x[0] - tri[0, 0]) * patch_normal[0] + (x[1] - tri[0, 1]) * patch_normal[1]
                 + (x[2] - tri[0, 2]) * patch_normal[2])
        out[e] = 0.0
        if front <= 0.0:
            continue
        poly = np.empty((4, 3))
        count = _clip_to_plane(tri, x, n, poly)
        if count < 3:
            continue
        f = point_to_polygon(x, n, poly, count)
        if f == 0.0:
            continue
        stack = new_stack()
        ox, oy, oz = x[0] + offset * n[0], x[1] + offset * n[1], x[2] + offset * n[2]
        seen, tried = 0, 0
        for s in range(samples.shape[0]):
            dx, dy, dz = samples[s, 0] - ox, samples[s, 1] - oy, samples[s, 2] - oz
            if dx * n[0] + dy * n[1] + dz * n[2] <= 0.0:
                continue                            # below x's horizon: not part of the clip
            tried += 1
            if occluded(bvh, ox, oy, oz, dx, dy, dz, 1e-9, 1.0 - 1e-6, stack) < 0:
                seen += 1
        out[e] = f if tried == 0 else f * seen / tried


def sample_points(tri: np.ndarray, k: int = 4) -> np.ndarray:
    """``k²`` stratified points on a triangle (3, 3): the centroids of its regular k x k
    subdivision."""
    from core.radiosity.mesh import subdivide
    pieces, _ = subdivide(tri[None], np.array([k]))
    return pieces.mean(axis=1)


def factors_to_patch(bvh, points, normals, tri, patch_normal, scale: float,
                     samples_per_side: int = 4) -> np.ndarray:
    """``F(dA_x → patch)`` for every receiving point ``points`` (E, 3) with ``normals``."""
    out = np.empty(len(points))
    tri = np.ascontiguousarray(tri, dtype=np.float64)
    _to_patch(bvh, np.ascontiguousarray(points), np.ascontiguousarray(normals), tri,
              np.ascontiguousarray(patch_normal, dtype=np.float64),
              sample_points(tri, samples_per_side), 1e-7 * scale, out)
    return out
