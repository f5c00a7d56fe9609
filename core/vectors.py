"""Unit vectors inside compiled kernels: one numba function every kernel shares."""

from __future__ import annotations

import math

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
