"""Texture sampling in numba: nearest, bilinear, trilinear (MIP mapping) and anisotropic.

Callable from any ``@njit`` kernel. A texture reaches a kernel as two arrays
(:meth:`core.texture.image.Texture.packed`):

- ``texels`` ``(N, 4)`` float32: every MIP level's texels one after another, RGBA, linear;
  row-major, row 0 at v = 0 (the bottom of an image, as in OpenGL and OBJ's ``vt``);
- ``levels`` ``(L, 3)`` int64: per level ``offset`` (its first row in ``texels``), ``width``,
  ``height``; level 0 is the full image, each next one half the size (at least 1).

Coordinates are normalised, (0, 0) the corner of texel (0, 0), (1, 1) the far corner, so the
centre of texel (i, j) of a w x h level is ((i + ½) / w, (j + ½) / h). The rules are OpenGL's
(4.6 core, section 8.14), so that llvmpipe is an oracle:

- **wrap** (Table 8.20) on integer texel indices: ``REPEAT`` i mod size, ``CLAMP`` (to edge)
  clamp(i, 0, size − 1), ``MIRROR`` (mirrored repeat) (size − 1) − mirror((i mod 2 size) − size)
  with mirror(a) = a for a ≥ 0, −(1 + a) otherwise;
- **nearest** (``GL_NEAREST``): the texel (⌊u w⌋, ⌊v h⌋) of level 0, wrapped;
- **bilinear** (``GL_LINEAR``): i0 = ⌊u w − ½⌋, α = frac(u w − ½), the four texels
  (i0, i0 + 1) x (j0, j0 + 1), each wrapped, weighted (1 − α)(1 − β) …;
- **trilinear** (``GL_LINEAR_MIPMAP_LINEAR``, Williams 1983): the level of detail from the
  screen-space derivatives of (u, v): ρ = max(|(du/dx w, dv/dx h)|, |(du/dy w, dv/dy h)|) (texels
  per pixel along x and along y, GL's eq. 8.5 with its scale factor), λ = log2 ρ. λ ≤ 0 is
  magnification: bilinear on level 0. Otherwise bilinear on levels ⌊λ⌋ and ⌊λ⌋ + 1 (clamped
  to the last) blended by frac(λ);
- **anisotropic** (the "beyond" option, as GPUs do it with EXT_texture_filter_anisotropic):
  the pixel's footprint is a parallelogram whose long side (the major axis) covers ρ_max texels
  and short side ρ_min; N = min(⌈ρ_max / ρ_min⌉, ``MAX_ANISOTROPY``) trilinear probes spaced
  evenly along the major axis, each at the level of ρ_max / N, averaged. Where trilinear blurs
  a floor seen at a grazing angle (its level follows the long side), this keeps the detail
  across the view.

Every function returns ``(r, g, b, a)``.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit

# The kernels here that are not inlined declare _nrt=False (no reference counts): they make
# no array, and numba compiles a callee with the flags of the first caller that needs it,
# so without the declaration a counted copy, linked into the ray tracer's or the pixel
# step's uncounted code, would take and give back a count for every view it makes.
from core.texture.modes import (ANISOTROPIC, BILINEAR, CLAMP, FILTERS, MIRROR,  # noqa: F401
                                NEAREST, REPEAT, TRILINEAR, WRAPS)

MAX_ANISOTROPY = 16          # probes along the major axis at most (GPUs offer 2 … 16)


@njit(cache=True, _nrt=False)
def wrap_index(i, size, mode):
    """GL's wrap of an integer texel index ``i`` into [0, size) (Table 8.20)."""
    if mode == REPEAT:
        return i % size                       # Python's % is already non-negative
    if mode == CLAMP:
        return min(max(i, 0), size - 1)
    a = i % (2 * size) - size                  # MIRROR
    mirror = a if a >= 0 else -(1 + a)
    return (size - 1) - mirror


@njit(cache=True, _nrt=False)
def floor_index(x):
    """⌊x⌋ as an integer, with coordinates far outside the texture kept in int64 range."""
    return int(math.floor(min(max(x, -1e15), 1e15)))


@njit(cache=True, _nrt=False)
def texel(texels, levels, level, i, j):
    """The texel (i, j) of ``level``, indices already wrapped: ``(r, g, b, a)``."""
    row = levels[level, 0] + j * levels[level, 1] + i
    return (np.float64(texels[row, 0]), np.float64(texels[row, 1]),
            np.float64(texels[row, 2]), np.float64(texels[row, 3]))


@njit(cache=True, _nrt=False)
def nearest(texels, levels, wrap, level, u, v):
    """GL_NEAREST on ``level``: the texel that contains (u, v)."""
    w, h = levels[level, 1], levels[level, 2]
    i = wrap_index(floor_index(u * w), w, wrap)
    j = wrap_index(floor_index(v * h), h, wrap)
    return texel(texels, levels, level, i, j)


@njit(cache=True, _nrt=False)
def bilinear(texels, levels, wrap, level, u, v):
    """GL_LINEAR on ``level``: the four texels around (u, v), weighted by distance."""
    w, h = levels[level, 1], levels[level, 2]
    x, y = u * w - 0.5, v * h - 0.5
    i0, j0 = floor_index(x), floor_index(y)
    alpha, beta = x - math.floor(x), y - math.floor(y)
    if not (math.isfinite(alpha) and math.isfinite(beta)):
        alpha, beta = 0.0, 0.0
    ia, ib = wrap_index(i0, w, wrap), wrap_index(i0 + 1, w, wrap)
    ja, jb = wrap_index(j0, h, wrap), wrap_index(j0 + 1, h, wrap)
    r00, g00, b00, a00 = texel(texels, levels, level, ia, ja)
    r10, g10, b10, a10 = texel(texels, levels, level, ib, ja)
    r01, g01, b01, a01 = texel(texels, levels, level, ia, jb)
    r11, g11, b11, a11 = texel(texels, levels, level, ib, jb)
    w00, w10 = (1.0 - alpha) * (1.0 - beta), alpha * (1.0 - beta)
    w01, w11 = (1.0 - alpha) * beta, alpha * beta
    return (w00 * r00 + w10 * r10 + w01 * r01 + w11 * r11,
            w00 * g00 + w10 * g10 + w01 * g01 + w11 * g11,
            w00 * b00 + w10 * b10 + w01 * b01 + w11 * b11,
            w00 * a00 + w10 * a10 + w01 * a01 + w11 * a11)


@njit(cache=True, _nrt=False)
def footprint(levels, dudx, dvdx, dudy, dvdy, base=0):
    """``(ρ_x, ρ_y)``: texels of level 0 (row ``base``) a step of one pixel along x and
    along y covers."""
    w, h = levels[base, 1], levels[base, 2]
    rho_x = math.sqrt((dudx * w) ** 2 + (dvdx * h) ** 2)
    rho_y = math.sqrt((dudy * w) ** 2 + (dvdy * h) ** 2)
    return rho_x, rho_y


@njit(cache=True, _nrt=False)
def level_of_detail(levels, dudx, dvdx, dudy, dvdy, base=0):
    """λ = log2 ρ with ρ = max(ρ_x, ρ_y) (GL eq. 8.5); −inf for a zero footprint."""
    rho_x, rho_y = footprint(levels, dudx, dvdx, dudy, dvdy, base)
    rho = max(rho_x, rho_y)
    if not rho > 0.0:
        return -np.inf
    if not math.isfinite(rho):
        return np.inf
    return math.log2(rho)


@njit(cache=True, _nrt=False)
def mip_at(texels, levels, wrap, lam, u, v, base=0, count=-1):
    """Bilinear on the two levels around λ, blended (GL_LINEAR_MIPMAP_LINEAR). The texture's
    levels are rows ``base`` … ``base + count − 1`` of ``levels`` (default: all of them)."""
    last = (levels.shape[0] - base if count < 0 else count) - 1
    if not lam > 0.0:                         # magnification (or no footprint): level 0
        return bilinear(texels, levels, wrap, base, u, v)
    if lam >= last:
        return bilinear(texels, levels, wrap, base + last, u, v)
    d1 = int(math.floor(lam))
    f = lam - d1
    r1, g1, b1, a1 = bilinear(texels, levels, wrap, base + d1, u, v)
    r2, g2, b2, a2 = bilinear(texels, levels, wrap, base + d1 + 1, u, v)
    return ((1.0 - f) * r1 + f * r2, (1.0 - f) * g1 + f * g2,
            (1.0 - f) * b1 + f * b2, (1.0 - f) * a1 + f * a2)


@njit(cache=True, _nrt=False)
def trilinear(texels, levels, wrap, u, v, dudx, dvdx, dudy, dvdy, base=0, count=-1):
    """GL_LINEAR_MIPMAP_LINEAR with the level from the derivatives of (u, v)."""
    return mip_at(texels, levels, wrap, level_of_detail(levels, dudx, dvdx, dudy, dvdy, base),
                  u, v, base, count)


@njit(cache=True, _nrt=False)
def anisotropic(texels, levels, wrap, u, v, dudx, dvdx, dudy, dvdy, base=0, count=-1):
    """Several trilinear probes along the footprint's major axis, averaged."""
    rho_x, rho_y = footprint(levels, dudx, dvdx, dudy, dvdy, base)
    if rho_x >= rho_y:
        major, minor, du, dv = rho_x, rho_y, dudx, dvdx
    else:
        major, minor, du, dv = rho_y, rho_x, dudy, dvdy
    if not (major > 0.0 and math.isfinite(major)):
        return trilinear(texels, levels, wrap, u, v, dudx, dvdx, dudy, dvdy, base, count)
    n = MAX_ANISOTROPY if not minor > 0.0 else int(min(math.ceil(major / minor), MAX_ANISOTROPY))
    n = max(n, 1)
    lam = math.log2(major / n)
    r, g, b, a = 0.0, 0.0, 0.0, 0.0
    for k in range(n):
        t = (k + 0.5) / n - 0.5              # probes spread over one pixel step of the major axis
        pr, pg, pb, pa = mip_at(texels, levels, wrap, lam, u + t * du, v + t * dv, base, count)
        r, g, b, a = r + pr, g + pg, b + pb, a + pa
    return r / n, g / n, b / n, a / n


@njit(cache=True, _nrt=False)
def sample(texels, levels, wrap, filter_, u, v, dudx, dvdx, dudy, dvdy, base=0, count=-1):
    """The texture at (u, v) with filter ``filter_`` (NEAREST … ANISOTROPIC): ``(r, g, b, a)``.

    Nearest and bilinear read level 0 only (GL_NEAREST, GL_LINEAR) and ignore the derivatives.
    ``base``, ``count``: the texture's rows of a shared level table (several textures packed
    together); default, the whole table. (Passing rows rather than a slice of the table keeps
    the pixel loops free of array views, whose reference counts both cores would contend for.)
    """
    if filter_ == NEAREST:
        return nearest(texels, levels, wrap, base, u, v)
    if filter_ == BILINEAR:
        return bilinear(texels, levels, wrap, base, u, v)
    if filter_ == TRILINEAR:
        return trilinear(texels, levels, wrap, u, v, dudx, dvdx, dudy, dvdy, base, count)
    return anisotropic(texels, levels, wrap, u, v, dudx, dvdx, dudy, dvdy, base, count)


@njit(cache=True)
def sample_many(texels, levels, wrap, filter_, uv, duv, out):
    """:func:`sample` at each row of ``uv (N, 2)`` with ``duv (N, 4)`` = du/dx, dv/dx, du/dy,
    dv/dy, into ``out (N, 4)`` (for tests and for numpy callers)."""
    for k in range(uv.shape[0]):
        r, g, b, a = sample(texels, levels, wrap, filter_, uv[k, 0], uv[k, 1],
                            duv[k, 0], duv[k, 1], duv[k, 2], duv[k, 3])
        out[k, 0], out[k, 1], out[k, 2], out[k, 3] = r, g, b, a
