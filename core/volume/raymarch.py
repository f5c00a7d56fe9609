"""The ray marcher's kernels (FvDFH 20.6.2, volume rendering; Levoy, "Display of Surfaces from
Volume Data", 1988; Max, "Optical Models for Direct Volume Rendering", 1995).

Each ray ``o + t·d`` (world, ``d`` a unit vector, so ``t`` is world length) is carried into
index space by the volume's inverse placement, clipped to the grid's box ``[0, n − 1]³`` and to
its own interval ``[t_lo, t_hi]`` (the view's front and back planes; ``t_hi`` also stops at
the opaque geometry the z-buffer drew), and cut into segments of length ``step`` (the last
one shorter, so that the segments add up to the clipped length exactly). Each segment is
sampled at its midpoint by trilinear interpolation.

- **Emission–absorption** (Max's model, front to back): the transfer function gives the
  sample's colour ``c`` and extinction ``σ``; the segment's opacity is ``α = 1 − e^{−σ·Δt}``
  and ``C += T·α·c``, ``T *= 1 − α``; the march ends early once ``T < EARLY_TERMINATION``.
  For a homogeneous medium this is the exact integral ``c (1 − e^{−σ L})``.
- **Gradient shading** (Levoy): where the data's gradient is not negligible, ``c`` is lit by
  the volume material's lighting model through the seam every renderer lights by
  (:func:`core.shading.models.dispatch.light_point_calling`: Phong unless the material names another,
  the scene's lights, the material with ``O_d = c``, two-sided) with the normal
  ``−∇f / |∇f|``. The gradient is Levoy's: central differences at every sample (one-sided at
  the border), computed once per volume (:func:`sample_gradients`) and interpolated
  trilinearly like the data. A volume over :data:`GRADIENT_VOXELS` (whose gradients would
  take more than 192 MiB) takes the trilinear field's central differences half a sample either
  side at each lit sample instead (six more fetches; the two agree at the samples).
- **MIP**: the largest sample along the ray.
- **Empty-space skipping** (Levoy, "Efficient Ray Tracing of Volume Data", 1990): the grid's
  cells are grouped in blocks of :data:`BLOCK`³, each with the smallest and largest sample it
  reads (its corner samples shared with its neighbours), so that every trilinear value inside
  lies between them. A block where the transfer function's σ is 0 over that whole range
  (:func:`empty_blocks`: σ is piecewise linear, so its ends and its points between) adds
  nothing, and a ray there jumps to the first sample past the block's far face; in MIP a
  block whose largest sample cannot beat the ray's maximum so far is jumped the same way.
  The samples taken are the same ones at the same points, so the picture is the same to the
  bit; the block ranges are computed once per volume (:func:`block_ranges`). Blocks are
  grouped again in coarse blocks of :data:`COARSE`³, jumped whole where every block in them
  would be (a ray outside the data crosses a quarter as many).
- **Blocks of one value** (:func:`block_constants`): where every sample a block reads is one
  value, its samples all classify alike, and the ray's ``m`` samples there composite in
  closed form: with ``q = 1 − α`` each, ``C += T·c·(1 − q^m)`` and ``T *= q^m`` (the loop's
  own sum, ``Σ T·q^k·α·c``); MIP takes the value once. Lit, the block must be one value one
  sample round it as well, so that its gradient is zero and its samples unlit. Where the ray
  would end early inside such a block, it is marched sample by sample. The same sum
  regrouped: within a few units in the last place of the every-sample march (segmented data
  such as the Shepp–Logan phantom is mostly such blocks; noisy scans have few).

The caller composites ``C + T · (what lies behind)``.
"""

from __future__ import annotations

import math
import weakref

import numpy as np
from numba import get_num_threads

from core.jit import call_compiled, compiled_at, njit, prange
from core.shading.illumination import LIGHT_COLUMNS, OD, pack_surfaces
from core.shading.models import with_model
from core.shading.models.dispatch import light_point_calling
from core.volume.marching import gradient_at

EMISSION_ABSORPTION, MIP = 0, 1
# The march stops when less than this of the light behind can still come through: what it
# leaves out changes a pixel by at most 0.25/255.
EARLY_TERMINATION = 1e-3
# Below this gradient (per sample, relative to the data's range) a sample is not lit: a
# homogeneous region has no surface to shade.
FLAT_GRADIENT = 1e-3
# The largest volume whose gradients are kept (three float32 a sample): 256³, 192 MiB.
GRADIENT_VOXELS = 1 << 24
# Cells a side of an empty-space block: 32³ blocks for a 256³ volume, 128 KiB of ranges.
BLOCK = 8
# Blocks a side of a coarse block, skipped whole when every block in it is.
COARSE = 4


@njit(cache=True, inline="always")
def trilinear(v, x, y, z):
    """The trilinear interpolant of ``v`` at index point (x, y, z); zero outside the grid."""
    n0, n1, n2 = v.shape
    if not (0.0 <= x <= n0 - 1 and 0.0 <= y <= n1 - 1 and 0.0 <= z <= n2 - 1):
        return 0.0
    i, j, k = min(int(x), n0 - 2), min(int(y), n1 - 2), min(int(z), n2 - 2)
    fx, fy, fz = x - i, y - j, z - k
    c00 = v[i, j, k] * (1 - fx) + v[i + 1, j, k] * fx
    c10 = v[i, j + 1, k] * (1 - fx) + v[i + 1, j + 1, k] * fx
    c01 = v[i, j, k + 1] * (1 - fx) + v[i + 1, j, k + 1] * fx
    c11 = v[i, j + 1, k + 1] * (1 - fx) + v[i + 1, j + 1, k + 1] * fx
    c0 = c00 * (1 - fy) + c10 * fy
    c1 = c01 * (1 - fy) + c11 * fy
    return c0 * (1 - fz) + c1 * fz


@njit(cache=True, inline="always")
def trilinear_flat(flat, n0, n1, n2, x, y, z):
    """:func:`trilinear` on the samples as one C-ordered row (``flat``): the eight corners
    are one index plus fixed strides, unsigned, so that no load checks for a negative index;
    the same arithmetic in the same order, so the same value."""
    if not (0.0 <= x <= n0 - 1 and 0.0 <= y <= n1 - 1 and 0.0 <= z <= n2 - 1):
        return 0.0
    i, j, k = min(int(x), n0 - 2), min(int(y), n1 - 2), min(int(z), n2 - 2)
    fx, fy, fz = x - i, y - j, z - k
    sj = np.uint64(n2)
    si = np.uint64(n1) * sj
    at = np.uint64(i) * si + np.uint64(j) * sj + np.uint64(k)
    one = np.uint64(1)
    c00 = flat[at] * (1 - fx) + flat[at + si] * fx
    c10 = flat[at + sj] * (1 - fx) + flat[at + si + sj] * fx
    c01 = flat[at + one] * (1 - fx) + flat[at + si + one] * fx
    c11 = flat[at + sj + one] * (1 - fx) + flat[at + si + sj + one] * fx
    c0 = c00 * (1 - fy) + c10 * fy
    c1 = c01 * (1 - fy) + c11 * fy
    return c0 * (1 - fz) + c1 * fz


@njit(cache=True, inline="always")
def _component(g, i, j, k, a, fx, fy, fz):
    c00 = g[i, j, k, a] * (1 - fx) + g[i + 1, j, k, a] * fx
    c10 = g[i, j + 1, k, a] * (1 - fx) + g[i + 1, j + 1, k, a] * fx
    c01 = g[i, j, k + 1, a] * (1 - fx) + g[i + 1, j, k + 1, a] * fx
    c11 = g[i, j + 1, k + 1, a] * (1 - fx) + g[i + 1, j + 1, k + 1, a] * fx
    return (c00 * (1 - fy) + c10 * fy) * (1 - fz) + (c01 * (1 - fy) + c11 * fy) * fz


@njit(cache=True, inline="always")
def trilinear3(g, x, y, z):
    """The trilinear interpolant of the vectors ``g`` (nx, ny, nz, 3) at an index point inside
    the grid."""
    n0, n1, n2 = g.shape[0], g.shape[1], g.shape[2]
    i, j, k = min(int(x), n0 - 2), min(int(y), n1 - 2), min(int(z), n2 - 2)
    fx, fy, fz = x - i, y - j, z - k
    return (_component(g, i, j, k, 0, fx, fy, fz), _component(g, i, j, k, 1, fx, fy, fz),
            _component(g, i, j, k, 2, fx, fy, fz))


@njit(cache=True, inline="always")
def classify(transfer, value):
    """The transfer function at ``value``: (r, g, b, σ), piecewise linear between its points
    and constant beyond the ends (numpy's ``interp`` rule: :func:`core.volume.data.transfer_at`)."""
    k = transfer.shape[0]
    if value <= transfer[0, 0]:
        return transfer[0, 1], transfer[0, 2], transfer[0, 3], transfer[0, 4]
    if value >= transfer[k - 1, 0]:
        return transfer[k - 1, 1], transfer[k - 1, 2], transfer[k - 1, 3], transfer[k - 1, 4]
    lo, hi = 1, k - 1                 # the first point at or past value, by bisection: a
    while lo < hi:                    # transfer function of 100,000 points costs 17 steps
        mid = (lo + hi) // 2
        if transfer[mid, 0] < value:
            lo = mid + 1
        else:
            hi = mid
    m = lo
    s = (value - transfer[m - 1, 0]) / (transfer[m, 0] - transfer[m - 1, 0])
    a, b = transfer[m - 1], transfer[m]
    return (a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]), a[3] + s * (b[3] - a[3]),
            a[4] + s * (b[4] - a[4]))


@njit(cache=True, inline="always")
def box_interval(v, ox, oy, oz, dx, dy, dz):
    """The ray's (index space) interval of t inside the grid's box (Kay–Kajiya slabs)."""
    t0, t1 = -np.inf, np.inf
    o = (ox, oy, oz)
    d = (dx, dy, dz)
    for a in range(3):
        hi = v.shape[a] - 1.0
        if d[a] == 0.0:
            if not (0.0 <= o[a] <= hi):
                return np.inf, -np.inf
            continue
        ta, tb = (0.0 - o[a]) / d[a], (hi - o[a]) / d[a]
        t0, t1 = max(t0, min(ta, tb)), min(t1, max(ta, tb))
    return t0, t1


@njit(cache=True, inline="always")
def block_exit(ox, oy, oz, rx, ry, rz, bi, bj, bk, side):
    """The ray's t where it leaves the cube of ``side`` cells (bi, bj, bk) (index space,
    Kay–Kajiya's far slab); ``r``: the direction's reciprocals (0 along an axis it does not
    move on), so that a ray crossing fifty empty blocks does not divide 150 times."""
    t = np.inf
    if rx > 0.0:
        t = min(t, ((bi + 1) * side - ox) * rx)
    elif rx < 0.0:
        t = min(t, (bi * side - ox) * rx)
    if ry > 0.0:
        t = min(t, ((bj + 1) * side - oy) * ry)
    elif ry < 0.0:
        t = min(t, (bj * side - oy) * ry)
    if rz > 0.0:
        t = min(t, ((bk + 1) * side - oz) * rz)
    elif rz < 0.0:
        t = min(t, (bk * side - oz) * rz)
    return t


@njit(cache=True, inline="always")
def reciprocal(d):
    return 1.0 / d if d != 0.0 else 0.0


@njit(cache=True, parallel=True, nogil=True)
def _block_ranges(v, lows, highs):
    n0, n1, n2 = v.shape
    for bi in prange(lows.shape[0]):
        for bj in range(lows.shape[1]):
            for bk in range(lows.shape[2]):
                lo, hi = np.inf, -np.inf
                for i in range(bi * BLOCK, min((bi + 1) * BLOCK + 1, n0)):
                    for j in range(bj * BLOCK, min((bj + 1) * BLOCK + 1, n1)):
                        for k in range(bk * BLOCK, min((bk + 1) * BLOCK + 1, n2)):
                            lo = min(lo, v[i, j, k])
                            hi = max(hi, v[i, j, k])
                lows[bi, bj, bk], highs[bi, bj, bk] = lo, hi


@njit(cache=True, parallel=True, nogil=True)
def _block_constants(v, margin, out):
    n0, n1, n2 = v.shape
    for bi in prange(out.shape[0]):
        for bj in range(out.shape[1]):
            for bk in range(out.shape[2]):
                i0, j0, k0 = max(bi * BLOCK - margin, 0), max(bj * BLOCK - margin, 0), \
                    max(bk * BLOCK - margin, 0)
                first, same = v[i0, j0, k0], True
                for i in range(i0, min((bi + 1) * BLOCK + 1 + margin, n0)):
                    for j in range(j0, min((bj + 1) * BLOCK + 1 + margin, n1)):
                        for k in range(k0, min((bk + 1) * BLOCK + 1 + margin, n2)):
                            same = same and v[i, j, k] == first
                out[bi, bj, bk] = first if same else np.nan


@njit(cache=True, inline="always")
def shade_sample(v, grads, x, y, z, r, g, b, px, py, pz, m_inv, surface, lights, ambient, eye,
                 halfway, flat):
    """The sample's colour lit by the material's lighting model with the normal −∇f (world), or
    as it is where the gradient is below ``flat``. ``grads``: the samples' gradients, or one
    row where they are not kept."""
    if grads.shape[0] > 1:
        gx, gy, gz = trilinear3(grads, x, y, z)
    else:
        gx = trilinear(v, x + 0.5, y, z) - trilinear(v, x - 0.5, y, z)
        gy = trilinear(v, x, y + 0.5, z) - trilinear(v, x, y - 0.5, z)
        gz = trilinear(v, x, y, z + 0.5) - trilinear(v, x, y, z - 0.5)
    if gx * gx + gy * gy + gz * gz <= flat * flat:
        return r, g, b
    # a gradient is a row: world ∇f = (M⁻¹)ᵀ ∇_index f
    nx = -(m_inv[0, 0] * gx + m_inv[1, 0] * gy + m_inv[2, 0] * gz)
    ny = -(m_inv[0, 1] * gx + m_inv[1, 1] * gy + m_inv[2, 1] * gz)
    nz = -(m_inv[0, 2] * gx + m_inv[1, 2] * gy + m_inv[2, 2] * gz)
    length = math.sqrt(nx * nx + ny * ny + nz * nz)
    surface[0, OD], surface[0, OD + 1], surface[0, OD + 2] = r, g, b
    return light_point_calling(px, py, pz, nx / length, ny / length, nz / length, 0, surface,
                               lights, ambient, eye, halfway)


@njit(cache=True, parallel=True, nogil=True)
def _sample_gradients(v, out):
    for i in prange(v.shape[0]):
        for j in range(v.shape[1]):
            for k in range(v.shape[2]):
                out[i, j, k, 0], out[i, j, k, 1], out[i, j, k, 2] = gradient_at(v, i, j, k)


@njit(cache=True, parallel=True, nogil=True)
def march(v, grads, m_inv, origins, directions, t_lo, t_hi, step, mode, transfer, lit,
          material, lights, ambient, eye, halfway, flat, empty, highs, coarse_empty, coarse_highs,
          constants, cores, color, transmittance, largest, at):
    """March every ray (see the module); ``grads``: the samples' gradients (or one row, not
    kept). Fills ``color`` (N, 3) and ``transmittance`` (N,)
    (emission–absorption) or ``largest`` (N,) (MIP; −inf where the ray misses the grid).
    ``empty`` and ``highs``: each block's σ = 0 everywhere, its largest sample;
    ``coarse_empty`` and ``coarse_highs`` the same of each coarse block
    (:func:`coarse_blocks`); ``constants``: each block's one value or NaN, its colour and
    one step's ``1 − α`` (:func:`classified_constants`); ``cores``:
    numba's threads (read here: the kernel reading it would not be cached). The rays are
    dealt round-robin: the loop's static split would give each core one contiguous run (a
    frame's top rows to one, its middle to the other). ``at``: :func:`march_rays`'s machine
    code for these arguments, called by its address (:func:`core.jit.call_compiled`)."""
    for c in prange(cores):
        call_compiled(at, march_rays, v, grads, m_inv, origins, directions, t_lo, t_hi, step,
                      mode, transfer, lit, material.copy(), lights, ambient, eye, halfway, flat,
                      empty, highs, coarse_empty, coarse_highs, constants, np.int64(c), cores,
                      color, transmittance, largest)


# numpy's error model, as the parallel loop that calls it has: one compiled form (the loop's
# unsigned core index reuses the signed one, core.jit.reuse_plain_overloads), not two (5 s).
# No reference counts (_nrt): a core's rays make no array (15 % of a frame's time).
@njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def march_rays(v, grads, m_inv, origins, directions, t_lo, t_hi, step, mode, transfer,
               lit, surface, lights, ambient, eye, halfway, flat, empty, highs, coarse_empty,
               coarse_highs, constants, first, every, color, transmittance, largest):
    """Rays ``first``, ``first + every``, ... of :func:`march` (``surface``: this core's
    copy of the material, whose O_d each lit sample sets)."""
    n0, n1, n2 = v.shape
    row = v.reshape(n0 * n1 * n2)          # the samples as one row (trilinear_flat)
    for n in range(first, origins.shape[0], every):
        color[n, 0] = color[n, 1] = color[n, 2] = 0.0
        transmittance[n] = 1.0
        largest[n] = -np.inf
        wx, wy, wz = origins[n, 0], origins[n, 1], origins[n, 2]
        ex, ey, ez = directions[n, 0], directions[n, 1], directions[n, 2]
        ox = m_inv[0, 0] * wx + m_inv[0, 1] * wy + m_inv[0, 2] * wz + m_inv[0, 3]
        oy = m_inv[1, 0] * wx + m_inv[1, 1] * wy + m_inv[1, 2] * wz + m_inv[1, 3]
        oz = m_inv[2, 0] * wx + m_inv[2, 1] * wy + m_inv[2, 2] * wz + m_inv[2, 3]
        dx = m_inv[0, 0] * ex + m_inv[0, 1] * ey + m_inv[0, 2] * ez
        dy = m_inv[1, 0] * ex + m_inv[1, 1] * ey + m_inv[1, 2] * ez
        dz = m_inv[2, 0] * ex + m_inv[2, 1] * ey + m_inv[2, 2] * ez
        ta, tb = box_interval(v, ox, oy, oz, dx, dy, dz)
        ta, tb = max(ta, t_lo[n]), min(tb, t_hi[n])
        if not ta < tb:
            continue
        length = tb - ta
        segments = int(length // step) + 1
        rx, ry, rz = reciprocal(dx), reciprocal(dy), reciprocal(dz)
        T, cr, cg, cb, top = 1.0, 0.0, 0.0, 0.0, -np.inf
        s = -1
        # where the ray leaves the block it is in: till then no sample looks the block up (one
        # near the face that rounds into the next block reads a value within both blocks'
        # ranges, so skipping it or not adds the same)
        block_end = -np.inf
        while s + 1 < segments:
            s += 1
            t0 = ta + s * step
            dt = min(step, tb - t0)
            if dt <= 0.0:
                break
            t = t0 + 0.5 * dt
            x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
            if t > block_end and 0.0 <= x <= n0 - 1 and 0.0 <= y <= n1 - 1 \
                    and 0.0 <= z <= n2 - 1:
                bi, bj, bk = int(x) // BLOCK, int(y) // BLOCK, int(z) // BLOCK
                bi, bj, bk = (min(bi, empty.shape[0] - 1), min(bj, empty.shape[1] - 1),
                              min(bk, empty.shape[2] - 1))
                ci, cj, ck = bi // COARSE, bj // COARSE, bk // COARSE
                if coarse_empty[ci, cj, ck] if mode != MIP else coarse_highs[ci, cj, ck] <= top:
                    out = block_exit(ox, oy, oz, rx, ry, rz, ci, cj, ck, COARSE * BLOCK)
                    s = max(s, int(math.ceil((out - ta) / step - 0.5)) - 1)
                    continue
                out = block_exit(ox, oy, oz, rx, ry, rz, bi, bj, bk, BLOCK)
                if empty[bi, bj, bk] if mode != MIP else highs[bi, bj, bk] <= top:
                    # every sample up to the block's far face adds nothing: the next one
                    # taken is the first whose midpoint (ta + (s + ½)·step) is past it
                    s = max(s, int(math.ceil((out - ta) / step - 0.5)) - 1)
                    continue
                block_end = out
                one = constants[bi, bj, bk]
                last = min(int(math.ceil((out - ta) / step - 0.5)) - 1, segments - 2)
                if one[0] == one[0] and last >= s:
                    # one value all through the block: its samples s..last in closed form
                    if mode == MIP:
                        top = max(top, one[0])
                        s = last
                        continue
                    kept = one[4] ** (last - s + 1)
                    if T * kept >= EARLY_TERMINATION:
                        cr += T * (1.0 - kept) * one[1]
                        cg += T * (1.0 - kept) * one[2]
                        cb += T * (1.0 - kept) * one[3]
                        T *= kept
                        s = last
                        continue
            value = trilinear_flat(row, n0, n1, n2, x, y, z)
            if mode == MIP:
                top = max(top, value)
                continue
            r, g, b, sigma = classify(transfer, value)
            if sigma <= 0.0:
                continue
            if lit:
                r, g, b = shade_sample(v, grads, x, y, z, r, g, b, wx + t * ex, wy + t * ey,
                                       wz + t * ez, m_inv, surface, lights, ambient, eye,
                                       halfway, flat)
            alpha = 1.0 - math.exp(-sigma * dt)
            cr += T * alpha * r
            cg += T * alpha * g
            cb += T * alpha * b
            T *= 1.0 - alpha
            if T < EARLY_TERMINATION:
                break
        color[n, 0], color[n, 1], color[n, 2] = cr, cg, cb
        transmittance[n] = T
        largest[n] = top


# each volume's block ranges, kept while it lives (a frame marches it in several chunks)
_ranges: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def block_ranges(volume):
    """``(lows, highs)``: each block's smallest and largest sample (float32), computed once
    per volume (again if its samples are replaced)."""
    kept = _ranges.get(volume)
    if kept is None or kept[0] is not volume.values:
        v = volume.values
        shape = tuple(-(-(n - 1) // BLOCK) for n in v.shape)
        lows, highs = np.empty(shape, np.float32), np.empty(shape, np.float32)
        _block_ranges(v, lows, highs)
        kept = _ranges[volume] = (v, lows, highs)
    return kept[1], kept[2]


_constants: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def block_constants(volume, margin: int) -> np.ndarray:
    """Each block's one value where every sample it reads, and ``margin`` samples round it,
    is that value; NaN elsewhere. Margin 1 covers what a lit sample's gradient reads (the
    kept central differences, or the half-sample differences), so a lit block of one value
    is flat and unlit. Once per volume and margin."""
    v = volume.values
    kept = _constants.get(volume)
    if kept is None or kept[0] is not v:
        kept = _constants[volume] = (v, {})
    if margin not in kept[1]:
        shape = tuple(-(-(n - 1) // BLOCK) for n in v.shape)
        out = np.empty(shape, np.float64)
        _block_constants(v, margin, out)
        kept[1][margin] = out
    return kept[1][margin]


_gradients: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_NO_GRADIENTS = np.zeros((1, 1, 1, 3), np.float32)


def sample_gradients(volume) -> np.ndarray:
    """``(nx, ny, nz, 3)`` float32: the data's central differences at every sample, once per
    volume; one row of zeros for a volume over :data:`GRADIENT_VOXELS` (the marcher then
    differences the trilinear field at each lit sample)."""
    v = volume.values
    if v.size > GRADIENT_VOXELS:
        return _NO_GRADIENTS
    kept = _gradients.get(volume)
    if kept is None or kept[0] is not v:
        grads = np.empty((*v.shape, 3), np.float32)
        _sample_gradients(v, grads)
        kept = _gradients[volume] = (v, grads)
    return kept[1]


def empty_blocks(transfer, lows, highs) -> np.ndarray:
    """Whether σ is 0 over each block's range [low, high]: σ is piecewise linear (constant
    beyond the ends), so it is positive somewhere there exactly when it is at low, at high, or
    at one of its points strictly between."""
    points, sigma = transfer[:, 0], transfer[:, 4]
    positive = np.concatenate([[0], np.cumsum(sigma > 0.0)])
    between = (positive[np.searchsorted(points, highs, "left")]
               - positive[np.searchsorted(points, lows, "right")])
    at_ends = (np.interp(lows, points, sigma) > 0.0) | (np.interp(highs, points, sigma) > 0.0)
    return ~(at_ends | (between > 0))


def classified_constants(values, transfer, step) -> np.ndarray:
    """``(..., 5)``: each block's one value (NaN where it has none), its colour as the transfer
    function gives it, and ``1 − α`` of one full step there (the march's own ``1 − (1 −
    e^{−σ·Δt})``)."""
    transfer = np.asarray(transfer, np.float64)
    out = np.empty(values.shape + (5,))
    out[..., 0] = values
    for column in range(1, 5):                 # numpy's interp: classify's rule (NaN stays)
        out[..., column] = np.interp(values, transfer[:, 0], transfer[:, column])
    out[..., 4] = 1.0 - (1.0 - np.exp(-out[..., 4] * step))
    return out


def coarse_blocks(empty, highs):
    """``(coarse_empty, coarse_highs)``: whether every block of each coarse block of
    :data:`COARSE`³ is empty, and its largest sample (the grid of blocks padded with empty
    blocks of no sample)."""
    pad = [(0, -n % COARSE) for n in empty.shape]
    empty = np.pad(empty, pad, constant_values=True)
    highs = np.pad(highs, pad, constant_values=-np.inf)
    shape = [n // COARSE for n in empty.shape]
    split = (shape[0], COARSE, shape[1], COARSE, shape[2], COARSE)
    return (np.ascontiguousarray(empty.reshape(split).all(axis=(1, 3, 5))),
            np.ascontiguousarray(highs.reshape(split).max(axis=(1, 3, 5))))


def march_volume(volume, origins, directions, t_lo, t_hi, step, lights, ambient, eye,
                 halfway=False, lighting_model=None, skip_empty=True, skip_constant=True):
    """``(color (N, 3), transmittance (N,), largest (N,))`` of ``volume`` along the rays (the
    numpy entry; ``step`` in world units). ``lighting_model`` names a model that lights the
    volume instead of its material's own (the settings' override); ``None`` keeps it.
    ``skip_empty=False`` takes every sample (the tests' reference for the skipping);
    ``skip_constant=False`` marches blocks of one value sample by sample."""
    n = len(origins)
    color, transmittance, largest = np.empty((n, 3)), np.empty(n), np.empty(n)
    m_inv = np.linalg.inv(volume.world_from_index())
    mat = volume.material if lighting_model is None else with_model(volume.material,
                                                                    lighting_model)
    # two-sided: the side the viewer sees is lit; O_d is each sample's colour (march)
    material = pack_surfaces([mat], [True])
    transfer = (volume.transfer if volume.transfer is not None
                else np.zeros((1, 5)))
    lows, highs = block_ranges(volume)
    lo, hi = float(lows.min()), float(highs.max())          # the data's range
    empty = empty_blocks(np.asarray(transfer, np.float64), lows, highs)
    lit = volume.lighting == "gradient" and volume.mode != "mip"
    constants = classified_constants(block_constants(volume, 1 if lit else 0), transfer, step)
    if not skip_empty:
        empty, highs = np.zeros_like(empty), np.full_like(highs, np.inf)
    if not (skip_empty and skip_constant):
        constants[..., 0] = np.nan
    args = (np.ascontiguousarray(volume.values),
            sample_gradients(volume) if lit else _NO_GRADIENTS, m_inv,
            np.ascontiguousarray(origins, dtype=np.float64),
            np.ascontiguousarray(directions, dtype=np.float64),
            np.ascontiguousarray(t_lo, dtype=np.float64),
            np.ascontiguousarray(t_hi, dtype=np.float64),
            float(step), MIP if volume.mode == "mip" else EMISSION_ABSORPTION,
            np.ascontiguousarray(transfer, dtype=np.float64), lit,
            material, np.ascontiguousarray(lights, dtype=np.float64).reshape(-1, LIGHT_COLUMNS),
            np.asarray(ambient, dtype=np.float64), np.asarray(eye, dtype=np.float64),
            bool(halfway), FLAT_GRADIENT * max(hi - lo, 1e-30),
            empty, highs, *coarse_blocks(empty, highs), constants, get_num_threads())
    rays_at = compiled_at(march_rays, (*args[:11], material.copy(), *args[12:-1], 0, 0,
                                       color, transmittance, largest))   # as march calls it
    march(*args, color, transmittance, largest, rays_at)
    return color, transmittance, largest
