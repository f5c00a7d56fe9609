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
