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
  ``−∇f / |∇f|``; the gradient is the trilinear field's, by central differences half a
  sample either side.
- **MIP**: the largest sample along the ray.

The caller composites ``C + T · (what lies behind)``.
"""

from __future__ import annotations

import math

import numpy as np

from core.jit import njit, prange
from core.shading.illumination import LIGHT_COLUMNS, OD, pack_surfaces
from core.shading.models import with_model
from core.shading.models.dispatch import light_point_calling

EMISSION_ABSORPTION, MIP = 0, 1
# The march stops when less than this of the light behind can still come through: what it
# leaves out changes a pixel by at most 0.25/255.
EARLY_TERMINATION = 1e-3
# Below this gradient (per sample, relative to the data's range) a sample is not lit: a
# homogeneous region has no surface to shade.
FLAT_GRADIENT = 1e-3


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
def shade_sample(v, x, y, z, r, g, b, px, py, pz, m_inv, surface, lights, ambient, eye,
                 halfway, flat):
    """The sample's colour lit by the material's lighting model with the normal −∇f (world), or
    as it is where the gradient is below ``flat``."""
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
def march(v, m_inv, origins, directions, t_lo, t_hi, step, mode, transfer, lit, material,
          lights, ambient, eye, halfway, flat, color, transmittance, largest):
    """March every ray (see the module). Fills ``color`` (N, 3) and ``transmittance`` (N,)
    (emission–absorption) or ``largest`` (N,) (MIP; −inf where the ray misses the grid)."""
    for n in prange(origins.shape[0]):
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
        surface = material.copy()              # this ray's O_d is each sample's colour
        length = tb - ta
        segments = int(length // step) + 1
        T, cr, cg, cb, top = 1.0, 0.0, 0.0, 0.0, -np.inf
        for s in range(segments):
            t0 = ta + s * step
            dt = min(step, tb - t0)
            if dt <= 0.0:
                break
            t = t0 + 0.5 * dt
            x, y, z = ox + t * dx, oy + t * dy, oz + t * dz
            value = trilinear(v, x, y, z)
            if mode == MIP:
                top = max(top, value)
                continue
            r, g, b, sigma = classify(transfer, value)
            if sigma <= 0.0:
                continue
            if lit:
                r, g, b = shade_sample(v, x, y, z, r, g, b, wx + t * ex, wy + t * ey,
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


def march_volume(volume, origins, directions, t_lo, t_hi, step, lights, ambient, eye,
                 halfway=False, lighting_model=None):
    """``(color (N, 3), transmittance (N,), largest (N,))`` of ``volume`` along the rays (the
    numpy entry; ``step`` in world units). ``lighting_model`` names a model that lights the
    volume instead of its material's own (the settings' override); ``None`` keeps it."""
    n = len(origins)
    color, transmittance, largest = np.empty((n, 3)), np.empty(n), np.empty(n)
    m_inv = np.linalg.inv(volume.world_from_index())
    mat = volume.material if lighting_model is None else with_model(volume.material,
                                                                    lighting_model)
    # two-sided: the side the viewer sees is lit; O_d is each sample's colour (march)
    material = pack_surfaces([mat], [True])
    transfer = (volume.transfer if volume.transfer is not None
                else np.zeros((1, 5)))
    lo, hi = volume.value_range
    march(volume.values, m_inv, np.ascontiguousarray(origins, dtype=np.float64),
          np.ascontiguousarray(directions, dtype=np.float64),
          np.ascontiguousarray(t_lo, dtype=np.float64), np.ascontiguousarray(t_hi, dtype=np.float64),
          float(step), MIP if volume.mode == "mip" else EMISSION_ABSORPTION,
          np.ascontiguousarray(transfer, dtype=np.float64), volume.lighting == "gradient",
          material, np.ascontiguousarray(lights, dtype=np.float64).reshape(-1, LIGHT_COLUMNS),
          np.asarray(ambient, dtype=np.float64), np.asarray(eye, dtype=np.float64),
          bool(halfway), FLAT_GRADIENT * max(hi - lo, 1e-30), color, transmittance, largest)
    return color, transmittance, largest
