"""The viewing chain in exact rational arithmetic: the yardstick for the float64 pipeline.

Takes the same inputs as :mod:`core.camera.view` and :mod:`core.pipeline.project` (a :class:`core.camera.view.View`,
world points, the viewport) and returns the same quantities as :class:`fractions.Fraction`
values: every factor of ``N_per = S_per · SH_par · T(-PRP) · R · T(-VRP)`` and
``N_par = S_par · T_par · SH_par · R · T(-VRP)`` (FvDFH 6.5; pipeline.md's formulas, term for
term), the canonical coordinates of points, and their device coordinates after FvDFH's
perspective-to-parallel matrix ``M``, ``M_vv3dv`` and the divide by W (FvDFH 6.5.4, 6.5.6).
The stability suite holds the float64 pipeline to these numbers.

Every float64 input is a dyadic rational, so it converts to a Fraction without error; after
that, additions, products and quotients are exact. The one irrational operation of the chain is
the square root that normalises VPN and ``VUP x n``: :func:`sqrt` is exact when its argument is
the square of a rational and otherwise correct to a relative ``2**-SQRT_BITS`` (about 1e-96), so
every result here is within ~1e-90 of the true real value: nothing we compare against float64
(whose unit round-off is 1.1e-16) can be confused with it. :func:`phong` evaluates the
illumination model of :mod:`core.shading.illumination` the same way (integer exponents exactly,
others through :mod:`decimal` at 100 digits).

Matrices are tuples of four rows of four Fractions; points are tuples of Fractions.
:func:`relative_error` measures a float64 array against exact values (the difference itself is
taken exactly), and :func:`condition` estimates the componentwise relative condition number of
a map by exact perturbation of its inputs — how ill-posed a case is, independently of any
algorithm.
"""

from __future__ import annotations

import decimal
import math
import random
import types
from fractions import Fraction
from typing import Callable, Sequence

import numpy as np

from core.camera.view import View
from core.shading import illumination
from core.shading.models import lighting_model

SQRT_BITS = 320          # relative precision of an inexact square root (2**-320 ~ 5e-97)
ONE, ZERO = Fraction(1), Fraction(0)

Matrix = tuple
Vector = tuple


# --------------------------------------------------------------------------------------------
# Numbers


def q(x) -> Fraction:
    """``x`` (int, float, numpy scalar or Fraction) as an exact Fraction; NaN/inf refused."""
    if isinstance(x, Fraction):
        return x
    if isinstance(x, (int, np.integer)):
        return Fraction(int(x))
    x = float(x)
    if not math.isfinite(x):
        raise ValueError(f"{x!r} has no exact rational value")
    return Fraction(x)


def sqrt(x: Fraction, bits: int = SQRT_BITS) -> Fraction:
    """The square root of ``x >= 0``: exact for squares of rationals, else to 2**-bits relative."""
    if x < 0:
        raise ValueError(f"square root of a negative number {x}")
    if x == 0:
        return ZERO
    a, b = x.numerator, x.denominator
    ra, rb = math.isqrt(a), math.isqrt(b)
    if ra * ra == a and rb * rb == b:
        return Fraction(ra, rb)
    # sqrt(a/b) = sqrt(a b)/b; scale a b by 4^k so its root carries at least `bits` bits.
    m = a * b
    k = max(0, bits - m.bit_length() // 2 + 2)
    return Fraction(math.isqrt(m << (2 * k)), b << k)


def round_to_bits(x: Fraction, bits: int = SQRT_BITS) -> Fraction:
    """``x`` rounded to ``bits`` significant bits: keeps long products (``base**n``) small."""
    if x == 0:
        return x
    shift = bits - (abs(x.numerator).bit_length() - x.denominator.bit_length())
    if shift >= 0:
        return Fraction(round(x * (1 << shift)), 1 << shift)
    return Fraction(round(x / (1 << -shift)) << -shift)


def power(base: Fraction, n: Fraction) -> Fraction:
    """``base ** n`` for ``base >= 0``: exact-to-2**-320 for whole ``n``, 100 digits otherwise."""
    if base == 0:
        return ONE if n == 0 else ZERO
    if n.denominator == 1 and n >= 0:
        result, square, k = ONE, base, int(n)
        while k:                                   # square and multiply, rounding as it goes
            if k & 1:
                result = round_to_bits(result * square)
            square = round_to_bits(square * square)
            k >>= 1
        return result
    with decimal.localcontext() as ctx:
        ctx.prec = 100
        d = decimal.Decimal(base.numerator) / decimal.Decimal(base.denominator)
        e = decimal.Decimal(n.numerator) / decimal.Decimal(n.denominator)
        return Fraction((d.ln() * e).exp())


# --------------------------------------------------------------------------------------------
# Vectors and 4 x 4 matrices


def dot(a: Vector, b: Vector) -> Fraction:
    return sum((x * y for x, y in zip(a, b)), ZERO)


def cross(a: Vector, b: Vector) -> Vector:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a: Vector) -> Fraction:
    return sqrt(dot(a, a))


def unit(a: Vector) -> Vector:
    """``a / |a|``; the zero vector stays zero (as :func:`core.shading.illumination.unit3` does)."""
    length = norm(a)
    return tuple(ZERO for _ in a) if length == 0 else tuple(x / length for x in a)


def identity() -> Matrix:
    return tuple(tuple(ONE if i == j else ZERO for j in range(4)) for i in range(4))


def matmul(a: Matrix, b: Matrix) -> Matrix:
    return tuple(tuple(sum((a[i][k] * b[k][j] for k in range(4)), ZERO) for j in range(4))
                 for i in range(4))


def translate(tx, ty, tz) -> Matrix:
    m = [list(r) for r in identity()]
    m[0][3], m[1][3], m[2][3] = q(tx), q(ty), q(tz)
    return tuple(tuple(r) for r in m)


def scale(sx, sy, sz) -> Matrix:
    m = [list(r) for r in identity()]
    m[0][0], m[1][1], m[2][2] = q(sx), q(sy), q(sz)
    return tuple(tuple(r) for r in m)


def shear_xy(shx, shy) -> Matrix:
    m = [list(r) for r in identity()]
    m[0][2], m[1][2] = q(shx), q(shy)
    return tuple(tuple(r) for r in m)


def rows_as_rotation(u: Vector, v: Vector, n: Vector) -> Matrix:
    return (tuple(u) + (ZERO,), tuple(v) + (ZERO,), tuple(n) + (ZERO,), (ZERO, ZERO, ZERO, ONE))


def apply(m: Matrix, point: Vector) -> Vector:
    """``m · (x, y, z, 1)`` (or ``(x, y, z, w)``) → the homogeneous 4-vector."""
    p = tuple(point) + ((ONE,) if len(point) == 3 else ())
    return tuple(sum((m[i][k] * p[k] for k in range(4)), ZERO) for i in range(4))


# --------------------------------------------------------------------------------------------
# The normalizing transformations (FvDFH 6.5), the same formulas as core.camera.view


def view_numbers(view: View) -> list[Fraction]:
    """The 18 numbers of ``view`` in file order, exactly."""
    return [q(x) for x in view.numbers]


def _split(numbers: Sequence[Fraction]):
    v = list(numbers)
    return v[0:3], v[3:6], v[6:9], v[9:13], v[13:16], v[16], v[17]


def vrc_basis(numbers: Sequence[Fraction]) -> tuple[Vector, Vector, Vector]:
    """``n = VPN/|VPN|``, ``u = VUP x n/|VUP x n|``, ``v = n x u``."""
    _, vpn, vup, *_ = _split(numbers)
    n = unit(tuple(vpn))
    u = unit(cross(tuple(vup), n))
    return u, cross(n, u), n


def _common(numbers) -> dict:
    vrp, _, _, window, prp, _, _ = _split(numbers)
    u, v, n = vrc_basis(numbers)
    u_min, u_max, v_min, v_max = window
    dop = ((u_min + u_max) / 2 - prp[0], (v_min + v_max) / 2 - prp[1], -prp[2])
    return {"T_vrp": translate(*(-x for x in vrp)), "R": rows_as_rotation(u, v, n),
            "SH_par": shear_xy(-dop[0] / dop[2], -dop[1] / dop[2])}


def n_per_factors(view_or_numbers) -> dict:
    """T_vrp, R, T_prp, SH_par, S_per, N_per (Fraction matrices) and z_min (a Fraction)."""
    numbers = _numbers(view_or_numbers)
    _, _, _, window, prp, front, back = _split(numbers)
    u_min, u_max, v_min, v_max = window
    f = _common(numbers)
    f["T_prp"] = translate(*(-x for x in prp))
    vrp_z = -prp[2]                        # z of the VRP after T(-PRP) and the shear
    f["S_per"] = scale(2 * vrp_z / ((u_max - u_min) * (vrp_z + back)),
                       2 * vrp_z / ((v_max - v_min) * (vrp_z + back)), -1 / (vrp_z + back))
    f["N_per"] = matmul(f["S_per"], matmul(f["SH_par"], matmul(f["T_prp"],
                                                               matmul(f["R"], f["T_vrp"]))))
    f["z_min"] = -(vrp_z + front) / (vrp_z + back)
    return f


def n_par_factors(view_or_numbers) -> dict:
    """T_vrp, R, SH_par, T_par, S_par and N_par as Fraction matrices."""
    numbers = _numbers(view_or_numbers)
    _, _, _, window, _, front, back = _split(numbers)
    u_min, u_max, v_min, v_max = window
    f = _common(numbers)
    f["T_par"] = translate(-(u_max + u_min) / 2, -(v_max + v_min) / 2, -front)
    f["S_par"] = scale(2 / (u_max - u_min), 2 / (v_max - v_min), 1 / (front - back))
    f["N_par"] = matmul(f["S_par"], matmul(f["T_par"], matmul(f["SH_par"],
                                                              matmul(f["R"], f["T_vrp"]))))
    return f


def _numbers(view_or_numbers) -> list[Fraction]:
    if isinstance(view_or_numbers, View):
        return view_numbers(view_or_numbers)
    return [q(x) for x in view_or_numbers]


def normalizing_transform(view_or_numbers, projection: str) -> tuple[Matrix, Fraction]:
    """``(N, z_min)`` exactly, as :func:`core.camera.view.normalizing_transform` (z_min 0 for parallel)."""
    if projection == "perspective":
        f = n_per_factors(view_or_numbers)
        return f["N_per"], f["z_min"]
    if projection == "parallel":
        return n_par_factors(view_or_numbers)["N_par"], ZERO
    raise ValueError(f"projection must be 'perspective' or 'parallel', not {projection!r}")


# --------------------------------------------------------------------------------------------
# Projection to the device (core.pipeline.project)


def perspective_to_parallel(z_min: Fraction) -> Matrix:
    """FvDFH eq. 6.48."""
    return ((ONE, ZERO, ZERO, ZERO), (ZERO, ONE, ZERO, ZERO),
            (ZERO, ZERO, 1 / (1 + z_min), -z_min / (1 + z_min)), (ZERO, ZERO, -ONE, ZERO))


def m_vv3dv(x_min, x_max, y_min, y_max, z_min=-1, z_max=0) -> Matrix:
    """``T(x_min, y_min, z_min) · S((x_max-x_min)/2, (y_max-y_min)/2, z_max-z_min) · T(1,1,1)``."""
    x_min, x_max, y_min, y_max, z_min, z_max = (q(a) for a in (x_min, x_max, y_min, y_max,
                                                               z_min, z_max))
    return matmul(translate(x_min, y_min, z_min),
                  matmul(scale((x_max - x_min) / 2, (y_max - y_min) / 2, z_max - z_min),
                         translate(1, 1, 1)))


def device_matrix(projection: str, z_min: Fraction, vp) -> Matrix:
    """The matrix :func:`core.pipeline.project.project_triangles` applies before the divide."""
    m = m_vv3dv(*vp)
    return matmul(m, perspective_to_parallel(z_min)) if projection == "perspective" else m


def chain(numbers: Sequence[Fraction], points: Sequence[Vector], projection: str, vp):
    """World points → ``(canonical [(x, y, z)], device [(x, y, z) or None])`` exactly.

    ``numbers`` are the 18 view numbers. A point with ``W <= 0`` (at or behind the eye, which
    the clipper never lets through) has no device coordinates: None.
    """
    n, z_min = normalizing_transform(numbers, projection)
    canonical = [apply(n, p)[:3] for p in points]
    m = device_matrix(projection, z_min, vp)
    device = []
    for c in canonical:
        h = apply(m, c)
        device.append(None if h[3] <= 0 else tuple(x / h[3] for x in h[:3]))
    return canonical, device


# --------------------------------------------------------------------------------------------
# The illumination model (core.shading.illumination), exactly


def _exact_unit3(x, y, z):
    """:func:`core.vectors.unit3` in exact arithmetic (square root to 2**-320)."""
    length = norm((x, y, z))
    if length == 0:
        return ZERO, ZERO, ZERO, ZERO
    return x / length, y / length, z / length, length


def _exact_specular_power(base, n):
    return power(min(max(base, ZERO), ONE), n)


def _exact_model():
    """The Phong lighting model's own Python source (the registered model's ``point``,
    :func:`core.shading.illumination.phong_point`), bound to exact ``unit3`` and
    ``specular_power``: the model is written once, and run here in Fractions."""
    model = lighting_model("phong").kernels().point.py_func
    scope = dict(model.__globals__, unit3=_exact_unit3, specular_power=_exact_specular_power)
    return types.FunctionType(model.__code__, scope, "exact_phong_point")


def _exact_rows(rows) -> np.ndarray:
    """Packed float rows → the same table of Fractions (an object array the model indexes)."""
    rows = np.asarray(rows, dtype=np.float64)
    return np.array([[q(x) for x in row] for row in rows.reshape(len(rows), -1)],
                    dtype=object).reshape(rows.shape)


def phong(point: Vector, normal: Vector, material, lights, ambient, eye: Vector | None,
          toward_viewer: Vector | None, halfway: bool, two_sided: bool = False) -> Vector:
    """The Phong model of :mod:`core.shading.illumination` at one point, exactly: RGB in [0, 1].

    ``material`` is a :class:`core.scene.Material`, ``lights`` :class:`core.scene.Light` s,
    ``eye`` the viewer's point (perspective) or None with ``toward_viewer`` the unit direction
    (parallel). The scene is packed as the renderer packs it, then rounded to nothing: every
    float becomes the Fraction it is exactly, and the model runs in rational arithmetic.
    """
    packed_eye = (illumination.pack_eye(illumination.Eye(np.asarray(eye, float), None))
                  if eye is not None else
                  np.array([illumination.EYE_DIRECTION, *np.asarray(toward_viewer, float)]))
    surfaces = _exact_rows(illumination.pack_surfaces([material], [two_sided]))
    lights = _exact_rows(illumination.pack_lights(lights).reshape(-1, illumination.LIGHT_COLUMNS))
    ambient = _exact_rows(illumination.pack_ambient(ambient).reshape(1, 3))[0]
    p, n = tuple(q(x) for x in point), tuple(q(x) for x in normal)
    rgb = _exact_model()(*p, *n, 0, surfaces, lights, ambient, _exact_rows([packed_eye])[0],
                         halfway)
    return tuple(q(c) for c in rgb)


# --------------------------------------------------------------------------------------------
# Measuring float64 against exact values


def relative_error(approx, exact) -> float:
    """Largest over columns of ``max |approx − exact| / max |exact|`` (the difference exact).

    ``approx`` is ``(N, K)`` floats, ``exact`` N rows of K Fractions. A column whose exact values
    are all zero is measured absolutely. NaN or inf in ``approx`` gives inf.
    """
    a = np.asarray(approx, dtype=np.float64).reshape(len(exact), -1)
    if not np.all(np.isfinite(a)):
        return math.inf
    worst = 0.0
    for k in range(a.shape[1]):
        column = [row[k] for row in exact]
        size = max((abs(x) for x in column), default=ZERO)
        diff = max((abs(Fraction(float(a[i, k])) - column[i]) for i in range(len(column))),
                   default=ZERO)
        worst = max(worst, float(diff / size) if size else float(diff))
    return worst


def condition(f: Callable[[list[Fraction]], list[list[list[Fraction]]]],
              inputs: Sequence[Fraction], trials: int = 3, seed: int = 6) -> float:
    """Componentwise relative condition number of ``f`` at ``inputs``, estimated exactly.

    ``f`` maps the inputs to blocks of rows of outputs (``[[row, ...], ...]``); each column of
    each block is measured against its own largest value, as :func:`relative_error` does.
    Every input is moved by a relative ``h = 2**-64`` with a random sign (the perturbation
    rounding the inputs to float64 makes, shrunk so that the response is linear), ``trials``
    times. The estimate is ``max response / h``: the factor by which the relative error of
    the inputs can grow in the outputs, whatever algorithm computes them. Random signs find it
    to within a small factor.
    """
    h = Fraction(1, 1 << 64)
    base = f(list(inputs))
    rng = random.Random(seed)
    worst = ZERO
    for _ in range(trials):
        moved = f([x * (1 + h * rng.choice((-1, 1))) for x in inputs])
        for block, block0 in zip(moved, base):
            for k in range(len(block0[0]) if block0 else 0):
                size = max(abs(row[k]) for row in block0)
                diff = max(abs(a[k] - b[k]) for a, b in zip(block, block0))
                worst = max(worst, diff / size if size else diff)
    return float(worst / h)
