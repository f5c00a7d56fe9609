"""Unit vectors and 3-vector products inside compiled kernels, shared by every kernel.

numba's ``np.dot`` and ``@`` call BLAS, slow on 3-vectors and 3 x 3 matrices: written out
(:func:`dot3`, :func:`mat_vec3`, :func:`mat_t_vec3`), a step of ``blocks_falling.toml`` fell
from 2.8–6.5 ms to 0.56–0.86 ms.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit


@njit(cache=True)
def unit3(x, y, z):
    """``(x, y, z) / |(x, y, z)|`` and the length; the zero vector gives ``(0, 0, 0, 0)``.

    Divides by the largest component first so the squares neither underflow nor overflow.
    """
    m = max(abs(x), abs(y), abs(z))
    if not m > 0.0:
        return 0.0, 0.0, 0.0, 0.0
    if m < 2.2250738585072014e-308:    # subnormal: 1/m would overflow, so divide
        x, y, z = x / m, y / m, z / m
    else:
        inv_m = 1.0 / m               # one division and three products: this runs per pixel
        x, y, z = x * inv_m, y * inv_m, z * inv_m
    s = math.sqrt(x * x + y * y + z * z)
    inv_s = 1.0 / s
    return x * inv_s, y * inv_s, z * inv_s, m * s


@njit(cache=True)
def reflect(dx, dy, dz, nx, ny, nz):
    """``d`` mirrored about the plane of the unit normal ``n``: ``d − 2 (d·n) n``."""
    c = dx * nx + dy * ny + dz * nz
    return dx - 2 * c * nx, dy - 2 * c * ny, dz - 2 * c * nz


@njit(cache=True)
def frame(nx, ny, nz):
    """Two unit vectors perpendicular to the unit n (Duff et al. 2017)."""
    sign = 1.0 if nz >= 0.0 else -1.0
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    return (1.0 + sign * nx * nx * a, sign * b, -sign * nx), (b, sign + ny * ny * a, -ny)


@njit(cache=True)
def around(nx, ny, nz, x, y, z):
    """The vector ``(x, y, z)`` of the frame whose z axis is the unit n, in world axes."""
    t, b = frame(nx, ny, nz)
    return (x * t[0] + y * b[0] + z * nx, x * t[1] + y * b[1] + z * ny,
            x * t[2] + y * b[2] + z * nz)


@njit(cache=True)
def dot3(a, b):
    """a · b of two 3-vectors."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def mat_vec3(m, v):
    """m v for a 3 x 3 m."""
    out = np.empty(3)
    for i in range(3):
        out[i] = m[i, 0] * v[0] + m[i, 1] * v[1] + m[i, 2] * v[2]
    return out


@njit(cache=True)
def mat_t_vec3(m, v):
    """mᵀ v for a 3 x 3 m."""
    out = np.empty(3)
    for i in range(3):
        out[i] = m[0, i] * v[0] + m[1, i] * v[1] + m[2, i] * v[2]
    return out
