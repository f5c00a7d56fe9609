"""Mirror reflection, Snell refraction and Schlick's Fresnel weight (the notes of April 9).

Directions are unit vectors; ``I`` is the incident ray's direction (travelling towards the
surface) and ``N`` the unit normal on the side the ray comes from (``N·I < 0``).

- Reflection: ``R = I − 2 (N·I) N``.
- Refraction, the notes' form of Snell's law ``n_i sin θ_i = n_t sin θ_t``:
  ``T = α I + β N`` with ``α = n_i / n_t`` and
  ``β = α (−N·I) − sqrt(1 − α² (1 − (N·I)²))``. (The notes write ``β = α (N·I) − …`` with
  ``N·I`` the cosine of the angle between the normal and the direction *to* the viewer, i.e.
  ``−I``; here ``I`` points along the ray, hence the sign.) When the square root's argument
  is negative — ``sin θ_t > 1`` — there is no transmitted ray: total internal reflection,
  reported as ``ok = False``. At the critical angle ``sin θ_i = n_t / n_i`` the argument is 0
  and ``T`` grazes the surface.
- Schlick (1994): the reflected fraction ``F = F0 + (1 − F0)(1 − cos θ)^5``,
  ``F0 = ((n_i − n_t)/(n_i + n_t))²``, with ``θ`` the angle on the rarer side (θ_t when
  leaving the denser medium). The "beyond the notes" option: with it a surface with ``k_t``
  reflects ``k_r + F k_t`` and transmits ``(1 − F) k_t``, so ``k_r + k_t`` is kept.

- Exact (``--fresnel exact``): the Fresnel equations for unpolarised light,
  ``F = (R_s + R_p) / 2`` (:func:`fresnel_exact`); Schlick's form approximates it.

Named indices of refraction (the notes): :data:`INDICES`.
"""

from __future__ import annotations

import math

from core.jit import njit

from core.scene.media import AIR, GLASS, INDICES, WATER, index_of_refraction  # noqa: F401,E402


def check_material(material, where: str) -> None:
    """Refuse a material whose global terms cannot be traced (ValueError naming ``where``)."""
    for name in ("kr", "kt"):
        k = getattr(material, name)
        if not (isinstance(k, (int, float)) and math.isfinite(k) and 0.0 <= k <= 1.0):
            raise ValueError(f"{where}: {name} must be a number in [0, 1], not {k!r}")
    index_of_refraction(material.ior, f"{where}: ior")


@njit(cache=True, inline="always")
def facing_normals(dx, dy, dz, nx, ny, nz, gx, gy, gz, entering):
    """The geometric and shading normals turned to face a ray of direction D: the geometric
    one (for offsets and sides) flipped when the ray leaves the surface; the shading one (for
    the new directions) turned towards the ray, and replaced by the geometric one when it
    then lies on the other side of the face (an interpolated normal near a silhouette)."""
    if not entering:
        gx, gy, gz = -gx, -gy, -gz
    if nx * dx + ny * dy + nz * dz > 0.0:
        nx, ny, nz = -nx, -ny, -nz
    if nx * gx + ny * gy + nz * gz <= 0.0:
        nx, ny, nz = gx, gy, gz
    return nx, ny, nz, gx, gy, gz


@njit(cache=True)
def reflect(ix, iy, iz, nx, ny, nz):
    """``R = I − 2 (N·I) N``."""
    two_n_dot_i = 2.0 * (nx * ix + ny * iy + nz * iz)
    return ix - two_n_dot_i * nx, iy - two_n_dot_i * ny, iz - two_n_dot_i * nz


@njit(cache=True)
def refract(ix, iy, iz, nx, ny, nz, n_i, n_t):
    """``(ok, T)``: ``T = α I + β N`` (unit); ``ok = False`` on total internal reflection.

    ``N`` faces the incoming ray (``N·I <= 0``)."""
    alpha = n_i / n_t
    cos_i = -(nx * ix + ny * iy + nz * iz)
    k = 1.0 - alpha * alpha * (1.0 - cos_i * cos_i)
    if k < 0.0:
        return False, 0.0, 0.0, 0.0
    beta = alpha * cos_i - math.sqrt(k)
    tx, ty, tz = alpha * ix + beta * nx, alpha * iy + beta * ny, alpha * iz + beta * nz
    # |T| = 1 in exact arithmetic; renormalise away the rounding so long paths do not drift.
    length = math.sqrt(tx * tx + ty * ty + tz * tz)
    return True, tx / length, ty / length, tz / length


@njit(cache=True)
def schlick(cos_i, cos_t, n_i, n_t):
    """Schlick's reflected fraction; ``cos_i``/``cos_t`` the cosines on each side."""
    f0 = ((n_i - n_t) / (n_i + n_t)) ** 2
    c = cos_i if n_i <= n_t else cos_t                 # the angle in the rarer medium
    return f0 + (1.0 - f0) * (1.0 - c) ** 5


@njit(cache=True)
def fresnel_exact(cos_i, cos_t, n_i, n_t):
    """The Fresnel equations' reflected fraction for unpolarised light (the mean of the s- and
    p-polarised reflectances), what outside renderers use::

        R_s = ((n_i cos θ_i − n_t cos θ_t) / (n_i cos θ_i + n_t cos θ_t))²
        R_p = ((n_i cos θ_t − n_t cos θ_i) / (n_i cos θ_t + n_t cos θ_i))²
    """
    s_den = n_i * cos_i + n_t * cos_t
    p_den = n_i * cos_t + n_t * cos_i
    if s_den == 0.0 or p_den == 0.0:
        return 1.0
    r_s = ((n_i * cos_i - n_t * cos_t) / s_den) ** 2
    r_p = ((n_i * cos_t - n_t * cos_i) / p_den) ** 2
    return 0.5 * (r_s + r_p)
