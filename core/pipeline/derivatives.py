"""Barycentric planes: each triangle's weights and their screen derivatives (llvmpipe's dadx/dady).

After the divide by W, a triangle's screen-space barycentrics λ_k(x, y) are affine in device
x and y, and so are ``q_k = λ_k / W_k`` (FvDFH's incremental interpolation is exactly this).
The perspective-correct weights the z-buffer stores are ``b_k = q_k / (q_0 + q_1 + q_2)``.
Setup therefore keeps, per triangle, three planes ``q_k = a0 + dadx·x + dady·y``; from them a
shader gets at any pixel the weights *and* their derivatives in x and y (quotient rule) — what
a MIP level (the footprint of (u, v) on the texture) or a bump map's offsets need.

- :func:`barycentric_planes` ``(device (V, 3), inv_w (V,), triangles (T, 3)) -> (T, 3, 3)``:
  rows k = 0, 1, 2 hold ``(a0, dadx, dady)`` of ``q_k``; degenerate triangles get zeros.
- :func:`weights_and_derivatives` (numba): ``(b1, b2, db1/dx, db1/dy, db2/dx, db2/dy)`` at a
  device point (x right, **y up**; pixel (i, j)'s centre is (i + 0.5, j + 0.5)). An image row
  r is device row ``H − 1 − r``, so d/d(image row) = −d/dy.

They agree with the rasterizer's ``b1``, ``b2`` to the rounding of the fixed-point snap
(1/256 pixel; ``tests/core/pipeline/test_derivatives.py``). Computed only when a shader asks
for them (``Shader.needs_derivatives``): flat, Gouraud and Phong do not.
"""

from __future__ import annotations

import numpy as np
from core.jit import njit


def barycentric_planes(device: np.ndarray, inv_w: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """``(T, 3, 3)``: the plane ``(a0, dadx, dady)`` of ``q_k = λ_k / W_k`` for each vertex k."""
    p = device[triangles][:, :, :2]                           # (T, 3, 2) screen positions
    w = inv_w[triangles]                                      # (T, 3)
    x0, y0 = p[:, 0, 0], p[:, 0, 1]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area2 = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    ok = area2 != 0.0
    inv = np.divide(1.0, area2, out=np.zeros_like(area2), where=ok)
    # λ1 = ((x − x0) e2y − (y − y0) e2x) / area2, λ2 = ((y − y0) e1x − (x − x0) e1y) / area2
    d1 = np.stack([e2[:, 1] * inv, -e2[:, 0] * inv], axis=1)  # (dλ1/dx, dλ1/dy)
    d2 = np.stack([-e1[:, 1] * inv, e1[:, 0] * inv], axis=1)
    d0 = -(d1 + d2)
    planes = np.zeros((len(triangles), 3, 3))
    for k, d in enumerate((d0, d1, d2)):
        at_origin = (1.0 if k == 0 else 0.0) - d[:, 0] * x0 - d[:, 1] * y0   # λ_k at (0, 0)
        planes[:, k] = np.stack([at_origin, d[:, 0], d[:, 1]], axis=1) * w[:, k:k + 1]
    planes[~ok] = 0.0
    return planes


@njit(cache=True)
def weights_and_derivatives(planes, t, x, y):
    """Perspective-correct ``b1, b2`` of triangle ``t`` at device (x, y), and their x and y
    derivatives: ``(b1, b2, db1dx, db1dy, db2dx, db2dy)``."""
    q0 = planes[t, 0, 0] + planes[t, 0, 1] * x + planes[t, 0, 2] * y
    q1 = planes[t, 1, 0] + planes[t, 1, 1] * x + planes[t, 1, 2] * y
    q2 = planes[t, 2, 0] + planes[t, 2, 1] * x + planes[t, 2, 2] * y
    total = q0 + q1 + q2
    if total == 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    inv = 1.0 / total
    b1, b2 = q1 * inv, q2 * inv
    dtdx = planes[t, 0, 1] + planes[t, 1, 1] + planes[t, 2, 1]
    dtdy = planes[t, 0, 2] + planes[t, 1, 2] + planes[t, 2, 2]
    # quotient rule: d(q/Q) = (dq − (q/Q) dQ) / Q
    return (b1, b2, (planes[t, 1, 1] - b1 * dtdx) * inv, (planes[t, 1, 2] - b1 * dtdy) * inv,
            (planes[t, 2, 1] - b2 * dtdx) * inv, (planes[t, 2, 2] - b2 * dtdy) * inv)
