"""Homogeneous 4 x 4 transforms (FvDFH 5.6-5.7).

Points are column vectors ``(x, y, z, 1)``; a matrix acts on the left and a translation sits in
the rightmost column (the course notes insist on this). Every function returns a fresh float64
array.
"""

from __future__ import annotations

import numpy as np


def translate(tx: float, ty: float, tz: float) -> np.ndarray:
    """T(tx, ty, tz)."""
    m = np.eye(4)
    m[:3, 3] = np.array((tx, ty, tz), dtype=np.float64) + 0.0   # + 0.0 turns -0.0 into 0.0
    return m


def scale(sx: float, sy: float, sz: float) -> np.ndarray:
    """S(sx, sy, sz)."""
    return np.diag([float(sx), float(sy), float(sz), 1.0])


def rotate_x(theta: float) -> np.ndarray:
    """R_x(theta): rotation by ``theta`` radians about x, counter-clockwise looking down +x."""
    c, s = np.cos(theta), np.sin(theta)
    m = np.eye(4)
    m[1:3, 1:3] = [[c, -s], [s, c]]
    return m


def rotate_y(theta: float) -> np.ndarray:
    """R_y(theta)."""
    c, s = np.cos(theta), np.sin(theta)
    m = np.eye(4)
    m[0, 0], m[0, 2], m[2, 0], m[2, 2] = c, s, -s, c
    return m


def rotate_z(theta: float) -> np.ndarray:
    """R_z(theta)."""
    c, s = np.cos(theta), np.sin(theta)
    m = np.eye(4)
    m[0:2, 0:2] = [[c, -s], [s, c]]
    return m


def shear_xy(shx: float, shy: float) -> np.ndarray:
    """SH_xy(shx, shy): x += shx z, y += shy z (FvDFH eq. 6.22), the form SH_par takes."""
    m = np.eye(4)
    m[0, 2], m[1, 2] = shx, shy
    return m


def shear(xy=(0.0, 0.0), xz=(0.0, 0.0), yz=(0.0, 0.0)) -> np.ndarray:
    """The three shears of FvDFH 5.7, composed as SH_yz · SH_xz · SH_xy: ``xy`` = (shx, shy)
    moves x and y by z (SH_xy, eq. 5.45), ``xz`` = (shx, shz) moves x and z by y, ``yz`` =
    (shy, shz) moves y and z by x."""
    a, b, c = np.eye(4), np.eye(4), np.eye(4)
    a[0, 2], a[1, 2] = xy
    b[0, 1], b[2, 1] = xz
    c[1, 0], c[2, 0] = yz
    return c @ b @ a


def rotate_axis(axis, theta: float, point=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Rotation by ``theta`` radians about the line through ``point`` along ``axis``,
    counter-clockwise looking from the axis' tip towards ``point``: T(P) · R · T(−P) with
    R = cos θ I + (1 − cos θ) k kᵀ + sin θ [k]ₓ for the unit axis k (the notes' and FvDFH
    5.7's rotation about an arbitrary axis, the product of their five rotations worked out).
    Raises ValueError for a zero axis."""
    k = np.asarray(axis, dtype=np.float64)
    length = np.linalg.norm(k)
    if not length > 0.0 or not np.isfinite(length):
        raise ValueError("the axis is zero: no direction to rotate about")
    kx, ky, kz = k / length
    c, s = np.cos(theta), np.sin(theta)
    cross = np.array([[0.0, -kz, ky], [kz, 0.0, -kx], [-ky, kx, 0.0]])
    m = np.eye(4)
    m[:3, :3] = c * np.eye(3) + (1.0 - c) * np.outer((kx, ky, kz), (kx, ky, kz)) + s * cross
    p = np.asarray(point, dtype=np.float64)
    return translate(*p) @ m @ translate(*(-p))


def rows_as_rotation(u: np.ndarray, v: np.ndarray, n: np.ndarray) -> np.ndarray:
    """The rotation whose rows are the orthonormal basis u, v, n (FvDFH eq. 6.25)."""
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = u, v, n
    return m


def apply(m: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Transform ``(N, 3)`` or ``(N, 4)`` points by ``m``; returns ``(N, 4)`` homogeneous rows."""
    points = np.asarray(points, dtype=np.float64)
    if points.shape[-1] == 3:
        points = np.concatenate([points, np.ones(points.shape[:-1] + (1,))], axis=-1)
    return points @ m.T


def unit_rows(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row-wise unit vectors (as ``core.vectors.unit3``): ``(unit vectors (N, 3), lengths
    (N,))``; zero rows stay zero. Each row is divided by its largest component first, so
    that neither huge nor subnormal components overflow or underflow in the squares (a
    division, not a product with 1/m: 1/m of a subnormal m overflows)."""
    m = np.max(np.abs(v), axis=1)
    nonzero = m > 0.0
    scaled = np.divide(v, m[:, None], out=np.zeros_like(v, dtype=np.float64),
                       where=nonzero[:, None])
    x, y, z = scaled[:, 0], scaled[:, 1], scaled[:, 2]
    s = np.sqrt(x * x + y * y + z * z)
    inv_s = np.divide(1.0, s, out=np.zeros_like(s), where=nonzero)
    return scaled * inv_s[:, None], m * s
