"""The Phong illumination model (FvDFH 16.1–16.2; the notes of March 12–19, "Phong Illumination Model").

At a surface point ``P`` (world coordinates) with unit normal ``N``, per RGB channel λ:

    I_λ = I_aλ k_a O_dλ + Σ_lights f_att I_pλ [k_d O_dλ max(N·L, 0) + k_s O_sλ max(R·V, 0)^n]

with ``R = 2 (N·L) N − L`` the mirror direction of ``L``, ``V`` the unit vector from ``P`` to the
viewer, ``f_att = min(1, 1 / (c1 + c2 d + c3 d²))`` for a point light at distance ``d`` and
``f_att = 1`` for a directional light. ``specular = "halfway"`` replaces ``(R·V)^n`` by
``(N·H)^n`` with ``H = (L + V) / |L + V|`` (the notes: "Rather than calculating R, the halfway
vector is used"). The result is clamped to [0, 1] per channel.

The model is written once, as :func:`phong_point` (one point, numba), and reached three ways:

- from the compiled kernels (per face for flat, per vertex for Gouraud, per pixel for Phong,
  per hit for the ray casters), through the lighting models' seam
  (:func:`core.shading.models.dispatch.light_point`: a material chooses its model, this one
  by default);
- :func:`illuminate`, the numpy entry point: the same compiled function over N points;
- :func:`core.analysis.exact.phong`: the same Python source run in exact rational arithmetic
  (its ``unit3`` and ``specular_power`` swapped for exact ones), the oracle the float64 result
  is measured against. Integer literals (``2 * n_dot_l``, ``1 / den``) keep it exact there.

Both read the scene through small float arrays that numba can take:

- ``surfaces`` ``(M, 16)`` from :func:`pack_surfaces`: one row per mesh: ``k_a, k_d, k_s, n,
  O_d (3), O_s (3), two_sided``, the lighting model's number and its parameters (4;
  :mod:`core.shading.models`: model 0 is this one); a triangle or vertex names its row.
- ``lights`` ``(L, 11)`` from :func:`pack_lights`: ``kind`` (0 point, 1 directional), the
  position or the unit direction towards the light (3), ``I_p`` (3), ``c1, c2, c3``, and the
  cap (1: ``f_att`` at most 1, FvDFH's; 0: the notes' formula uncapped).
- ``ambient`` ``(3,)``: ``I_a``.
- ``eye`` ``(4,)`` from :func:`pack_eye`: ``kind`` (1 a point: perspective, V = (PRP − P)/|…|;
  0 a direction: parallel, V constant = −DOP/|DOP|) and the point or the direction.
  :func:`eye_from_view` finds both from a :class:`core.camera.view.View`.

Decisions that keep every output finite (the stability suite, core.analysis.stability, checks them):

- two-sided lighting (meshes that are not closed): ``N`` is flipped when ``N·V < 0``, so the
  side the viewer sees is the lit one whatever the winding;
- a point light at distance 0 from ``P``: ``L`` is undefined; the light adds no diffuse or
  specular term there (the limit of the grazing light on the points around it), only ambient;
- ``P`` exactly at the eye (perspective): ``V`` is undefined; ``V = N`` is used;
- ``L + V = 0`` in the halfway form: ``H`` is undefined; no specular term;
- no specular term where ``N·L <= 0`` (the light is behind the surface);
- the specular base is clamped to [0, 1] before ``^n``: exponents like 1e4 underflow to 0
  instead of overflowing, and rounding above 1 cannot blow up;
- ``c1 + c2 d + c3 d² <= 1`` (including all-zero coefficients) gives ``f_att = 1`` (FvDFH's
  cap; a light with ``attenuation_cap = false`` keeps the notes' ``1 / den`` above 1, and a
  zero denominator still gives 1); no division by zero;
- a zero normal (a vertex that has no non-degenerate face) gets ambient only;
- vectors are normalised after dividing by their largest component, so tiny or huge
  coordinates neither underflow nor overflow in the squares;
- underflow (a term below 1e-308 is 0 for an 8-bit image) and overflow (a light of 1e308
  saturates to white) only ever produce 0 or +inf in sums of non-negative terms, which the
  clamp maps to 0 and 1.

:func:`to_uint8` turns [0, 1] into bytes: ``floor(255 c + 0.5)``, i.e. rounded half up
(0.5/255 → 1), the same rule as ``core.camera.film.to_rgb8`` and the numba kernels' ``quantize``.
"""

from __future__ import annotations

import math

import numpy as np

from core.camera.film import to_rgb8 as to_uint8  # noqa: F401  (one rounding rule)
from core.camera.view import Eye, eye_from_view  # noqa: F401  (re-exported)
from core.jit import njit
from core.shading.models.registry import PARAMETER_COLUMNS, pack_model
from core.vectors import unit3  # noqa: F401  (re-exported)
from core.transforms import unit_rows

# Columns of a packed surface row (pack_surfaces).
KA, KD, KS, EXPONENT, OD, OS, TWO_SIDED, MODEL, PARAMETERS = 0, 1, 2, 3, 4, 7, 10, 11, 12
SURFACE_COLUMNS = PARAMETERS + PARAMETER_COLUMNS
# Columns of a packed light row (pack_lights).
LIGHT_KIND, LIGHT_XYZ, LIGHT_INTENSITY, LIGHT_ATTENUATION, LIGHT_CAP = 0, 1, 4, 7, 10
LIGHT_COLUMNS = 11
POINT_LIGHT, DIRECTIONAL_LIGHT = 0.0, 1.0
# eye[0]: the viewer is a point (perspective) or a direction (parallel).
EYE_DIRECTION, EYE_POINT = 0.0, 1.0
from core.settings import SPECULAR_FORMS  # noqa: E402,F401  (listed once, with the other names)


def pack_eye(eye: Eye) -> np.ndarray:
    """``(4,)``: ``[EYE_POINT, x, y, z]`` or ``[EYE_DIRECTION, unit direction]``."""
    if eye.point is not None:
        return np.array([EYE_POINT, *np.asarray(eye.point, dtype=np.float64)])
    unit, length = unit_rows(np.asarray(eye.direction, dtype=np.float64).reshape(1, 3))
    if not length[0] > 0.0:
        raise ValueError("the direction towards the viewer is zero")
    return np.array([EYE_DIRECTION, *unit[0]])


def pack_surfaces(materials, two_sided) -> np.ndarray:
    """``(M, 16)`` rows ``k_a, k_d, k_s, n, O_d, O_s, two_sided, model, parameters (4)``
    from ``M`` materials.

    ``two_sided[i]`` is true for a mesh that is not closed (lit from both sides).
    """
    rows = np.zeros((len(materials), SURFACE_COLUMNS))
    for i, (m, sided) in enumerate(zip(materials, two_sided)):
        rows[i, KA], rows[i, KD], rows[i, KS], rows[i, EXPONENT] = m.ka, m.kd, m.ks, m.n
        rows[i, OD:OD + 3] = m.od
        rows[i, OS:OS + 3] = m.os
        rows[i, TWO_SIDED] = 1.0 if sided else 0.0
        rows[i, MODEL], rows[i, PARAMETERS:] = pack_model(m)
    return rows


def pack_lights(lights) -> np.ndarray:
    """``(L, 11)`` rows ``kind, position | unit direction, I_p (3), c1, c2, c3, cap``
    (cap 1: ``f_att`` at most 1, FvDFH's; 0: the notes' ``1 / (c1 + c2 d + c3 d²)`` uncapped).

    Raises ValueError for a light with neither position nor a non-zero direction.
    """
    rows = np.zeros((len(lights), LIGHT_COLUMNS))
    for i, light in enumerate(lights):
        if light.position is not None:
            rows[i, LIGHT_KIND] = POINT_LIGHT
            rows[i, LIGHT_XYZ:LIGHT_XYZ + 3] = light.position
        else:
            direction = np.asarray(light.direction if light.direction is not None else (0, 0, 0),
                                   dtype=np.float64).reshape(1, 3)
            unit, length = unit_rows(direction)          # scaled first: 1e-300 or 1e300 is fine
            if not length[0] > 0.0:
                raise ValueError(f"light {i + 1}: it has no position and no direction")
            rows[i, LIGHT_KIND] = DIRECTIONAL_LIGHT
            rows[i, LIGHT_XYZ:LIGHT_XYZ + 3] = unit[0]
        rows[i, LIGHT_INTENSITY:LIGHT_INTENSITY + 3] = light.intensity
        rows[i, LIGHT_ATTENUATION:LIGHT_ATTENUATION + 3] = light.attenuation
        rows[i, LIGHT_CAP] = 1.0 if getattr(light, "attenuation_cap", True) else 0.0
    return rows


def attenuation(den: float, cap: float) -> float:
    """f_att from its denominator c1 + c2 d + c3 d²: FvDFH's min(1, 1/den) when ``cap`` is
    non-zero, the notes' 1/den as is when it is 0 (a zero denominator gives 1 either way);
    :func:`phong_point` writes the same test inline."""
    if den > 1 or (cap == 0 and den > 0):
        return 1 / den
    return 1


def pack_ambient(ambient) -> np.ndarray:
    return np.asarray(ambient, dtype=np.float64).reshape(3)


# --------------------------------------------------------------------------------------------
# numba: one point


# Whole exponents up to this are raised by repeated squaring; larger or fractional ones by pow.
SQUARING_LIMIT = 1 << 16


@njit(cache=True)
def specular_power(base, n):
    """``max(base, 0)^n`` with the base clamped to [0, 1] (no overflow for any n >= 0).

    A whole exponent (every material so far) is raised by repeated squaring: about 2 log2(n)
    products instead of ``pow``'s exp(n log x), several times cheaper per pixel. Each product
    rounds, so the result is within about n ulps of the exact power (d(x^n)/x^n = n dx/x: the
    same amplification pow applies to the rounding already in the base), far below 1/255.
    """
    x = min(max(base, 0), 1)
    if n == math.floor(n) and 0 <= n <= SQUARING_LIMIT:
        k = int(n)
        result = 1.0
        while k > 0:
            if k & 1:
                result *= x
            x *= x
            k >>= 1
        return result
    return x ** n


@njit(cache=True)
def quantize(c):
    """One channel in [0, 1] (clamped) → 0..255, rounded half up (see :func:`to_uint8`)."""
    return np.uint8(math.floor(min(max(c, 0.0), 1.0) * 255.0 + 0.5))


@njit(cache=True, inline="always")   # no call, no reference counts per point
def phong_point(px, py, pz, nx, ny, nz, s, surfaces, lights, ambient, eye, halfway):
    """The model at world point P with unit (or zero) normal N for surface row ``s``.

    Returns ``(r, g, b)`` clamped to [0, 1]. The model itself: every other form calls this.
    """
    ka, kd, ks, n = surfaces[s, KA], surfaces[s, KD], surfaces[s, KS], surfaces[s, EXPONENT]
    # V: towards the PRP (perspective) or the constant direction towards the viewer (parallel).
    if eye[0] == EYE_POINT:
        vx, vy, vz, dist = unit3(eye[1] - px, eye[2] - py, eye[3] - pz)
        if dist == 0.0:                 # P at the eye: V undefined, look along the normal
            vx, vy, vz = nx, ny, nz
    else:
        vx, vy, vz = eye[1], eye[2], eye[3]
    # Two-sided lighting: the side the viewer sees is the lit side.
    if surfaces[s, TWO_SIDED] != 0.0 and nx * vx + ny * vy + nz * vz < 0.0:
        nx, ny, nz = -nx, -ny, -nz
    r = ambient[0] * ka * surfaces[s, OD]
    g = ambient[1] * ka * surfaces[s, OD + 1]
    b = ambient[2] * ka * surfaces[s, OD + 2]
    for k in range(lights.shape[0]):
        if lights[k, LIGHT_KIND] == POINT_LIGHT:
            lx, ly, lz, d = unit3(lights[k, 1] - px, lights[k, 2] - py, lights[k, 3] - pz)
            if d == 0.0:                # light on the surface point: L undefined, ambient only
                continue
            den = lights[k, 7] + lights[k, 8] * d + lights[k, 9] * d * d
            if den > 1 or (lights[k, LIGHT_CAP] == 0 and den > 0):
                f_att = 1 / den         # (FvDFH caps it at 1; an uncapped light is the notes')
            else:
                f_att = 1
        else:
            lx, ly, lz = lights[k, 1], lights[k, 2], lights[k, 3]
            f_att = 1
        n_dot_l = nx * lx + ny * ly + nz * lz
        if not n_dot_l > 0.0:           # light behind the surface: no diffuse, no specular
            continue
        if halfway:
            hx, hy, hz, h_len = unit3(lx + vx, ly + vy, lz + vz)
            base = nx * hx + ny * hy + nz * hz
        else:
            two_n_dot_l = 2 * n_dot_l
            rx, ry, rz = two_n_dot_l * nx - lx, two_n_dot_l * ny - ly, two_n_dot_l * nz - lz
            base = rx * vx + ry * vy + rz * vz
        spec = specular_power(base, n)
        r += f_att * lights[k, 4] * (kd * surfaces[s, OD] * n_dot_l + ks * surfaces[s, OS] * spec)
        g += f_att * lights[k, 5] * (kd * surfaces[s, OD + 1] * n_dot_l + ks * surfaces[s, OS + 1] * spec)
        b += f_att * lights[k, 6] * (kd * surfaces[s, OD + 2] * n_dot_l + ks * surfaces[s, OS + 2] * spec)
    return min(max(r, 0), 1), min(max(g, 0), 1), min(max(b, 0), 1)


@njit(cache=True, inline="always")
def toward_viewer(eye, px, py, pz, nx, ny, nz):
    """V at P, as :func:`phong_point` finds it (for other lighting models; ``phong_point``
    keeps its steps written out, the source the exact analysis runs in Fractions)."""
    if eye[0] == EYE_POINT:
        vx, vy, vz, dist = unit3(eye[1] - px, eye[2] - py, eye[3] - pz)
        if dist == 0.0:                 # P at the eye: V undefined, look along the normal
            return nx, ny, nz
        return vx, vy, vz
    return eye[1], eye[2], eye[3]


@njit(cache=True, inline="always")
def two_sided_normal(surfaces, s, nx, ny, nz, vx, vy, vz):
    """N turned to the viewer on a two-sided surface (the side the viewer sees is lit)."""
    if surfaces[s, TWO_SIDED] != 0.0 and nx * vx + ny * vy + nz * vz < 0.0:
        return -nx, -ny, -nz
    return nx, ny, nz


@njit(cache=True, inline="always")
def toward_light(lights, k, px, py, pz):
    """``(L, f_att)`` of light ``k`` at P as :func:`phong_point` finds them; L = 0 for a point
    light on P (no diffuse or specular term there)."""
    if lights[k, LIGHT_KIND] == POINT_LIGHT:
        lx, ly, lz, d = unit3(lights[k, 1] - px, lights[k, 2] - py, lights[k, 3] - pz)
        if d == 0.0:
            return 0.0, 0.0, 0.0, 1.0
        den = lights[k, 7] + lights[k, 8] * d + lights[k, 9] * d * d
        if den > 1 or (lights[k, LIGHT_CAP] == 0 and den > 0):
            return lx, ly, lz, 1.0 / den
        return lx, ly, lz, 1.0
    return lights[k, 1], lights[k, 2], lights[k, 3], 1.0


# --------------------------------------------------------------------------------------------
# numpy: many points


@njit(cache=True)
def _illuminate_points(points, normals, surface, surfaces, lights, ambient, eye, halfway, out):
    for i in range(points.shape[0]):
        r, g, b = phong_point(points[i, 0], points[i, 1], points[i, 2], normals[i, 0],
                              normals[i, 1], normals[i, 2], surface[i], surfaces, lights, ambient,
                              eye, halfway)
        out[i, 0], out[i, 1], out[i, 2] = r, g, b


def illuminate(points: np.ndarray, normals: np.ndarray, surface: np.ndarray,
               surfaces: np.ndarray, lights: np.ndarray, ambient: np.ndarray,
               eye: np.ndarray, halfway: bool) -> np.ndarray:
    """The model at ``N`` world points with unit (or zero) normals: ``(N, 3)`` RGB in [0, 1].

    ``surface`` ``(N,)`` is each point's row of ``surfaces``. The numpy entry point: the same
    compiled :func:`phong_point`, over every point (the Phong model whatever the rows' model
    number: :func:`core.shading.models.dispatch.illuminate` lights each by its own).
    """
    p = np.ascontiguousarray(points, dtype=np.float64).reshape(-1, 3)
    nrm = np.ascontiguousarray(normals, dtype=np.float64).reshape(-1, 3)
    out = np.empty((len(p), 3))
    _illuminate_points(p, nrm, np.ascontiguousarray(surface, dtype=np.int64).reshape(-1),
                       np.ascontiguousarray(surfaces, dtype=np.float64),
                       np.ascontiguousarray(lights, dtype=np.float64).reshape(-1, LIGHT_COLUMNS),
                       np.ascontiguousarray(ambient, dtype=np.float64),
                       np.ascontiguousarray(eye, dtype=np.float64), bool(halfway), out)
    return out
