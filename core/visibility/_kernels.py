"""Small compiled loops the painter's renderers share."""

import numpy as np
from core.jit import njit, prange


@njit(cache=True, nogil=True)
def interpolate_rows(out, start, recipe):
    """Row ``start + i`` of ``out`` = ``(1 - t) out[a] + t out[b]``, ``(a, b, t) = recipe[i]``,
    in order (a row may use one made before it)."""
    for i in range(recipe.shape[0]):
        a, b, t = int(recipe[i, 0]), int(recipe[i, 1]), recipe[i, 2]
        for k in range(out.shape[1]):
            out[start + i, k] = (1.0 - t) * out[a, k] + t * out[b, k]


@njit(cache=True, parallel=True, nogil=True)
def depth_from_barycentrics(tri, b1, b2, triangles, device, inv_w, depth):
    """Each covered pixel's depth: the perspective-correct weights ``b`` over 1/W are the
    screen-linear ones (renormalised), and device depth is screen-linear."""
    for row in prange(tri.shape[0]):
        for col in range(tri.shape[1]):
            t = tri[row, col]
            if t < 0:
                depth[row, col] = -np.inf
                continue
            w1, w2 = b1[row, col], b2[row, col]
            i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            s0 = (1.0 - w1 - w2) / inv_w[i0]
            s1 = w1 / inv_w[i1]
            s2 = w2 / inv_w[i2]
            depth[row, col] = (s0 * device[i0, 2] + s1 * device[i1, 2]
                               + s2 * device[i2, 2]) / (s0 + s1 + s2)
