"""Volumes made from formulas, sampled on ``size`` points a side over the cube [−1, 1]³.

Each generator returns ``(values (n, n, n) float32, spacing)`` with spacing ``2 / (n − 1)`` on
every axis, so that the grid spans the cube (the volume's default placement centres it on the
origin; see :mod:`core.volume.data`).

- :func:`shepp_logan`: the 3D Shepp–Logan head phantom, ten ellipsoids summed, as Kak and
  Slaney tabulate it (*Principles of Computerized Tomographic Imaging*, 1988, table 3.1, the
  3D extension) with the rotation convention of Schabel's ``phantom3d``; ``variant =
  "modified"`` (Toft's intensities 1, −0.8, −0.2, …, visible contrast: the default) or
  ``"original"`` (2, −0.98, −0.02, …);
- :func:`sphere`: density ``σ`` inside radius ``r``, with a one-sample linear ramp across the
  boundary (the partial volume of each sample): its two kinks lie one sample apart, so along
  an axis the trilinear field integrates to exactly ``σ`` times the chord, and ``σ / 2`` is
  crossed at radius ``r``;
- :func:`metaballs`: Wyvill's soft objects, ``Σ (1 − d²/R²)³`` for ``d < R``;
- :func:`torus`: the negated signed distance to a torus about z (positive inside), so that the
  surface is ``iso = 0`` and the inside is above it, as for the other generators.
"""

from __future__ import annotations

import numpy as np

from core.volume.data import MAX_VOXELS, VolumeError

MAX_SIZE = round(MAX_VOXELS ** (1 / 3))      # 406: n³ within the budget

# A, a, b, c, x0, y0, z0, φ, θ, ψ (degrees): Kak & Slaney's 3D Shepp–Logan ellipsoids.
SHEPP_LOGAN = np.array([
    [2.00, .6900, .920, .810, 0.00, 0.0000, 0.00, 0., 0., 0.],
    [-.98, .6624, .874, .780, 0.00, -.0184, 0.00, 0., 0., 0.],
    [-.02, .1100, .310, .220, 0.22, 0.0000, 0.00, -18., 0., 10.],
    [-.02, .1600, .410, .280, -.22, 0.0000, 0.00, 18., 0., 10.],
    [0.01, .2100, .250, .410, 0.00, 0.3500, -.15, 0., 0., 0.],
    [0.01, .0460, .046, .050, 0.00, 0.1000, 0.25, 0., 0., 0.],
    [0.01, .0460, .046, .050, 0.00, -.1000, 0.25, 0., 0., 0.],
    [0.01, .0460, .023, .050, -.08, -.6050, 0.00, 0., 0., 0.],
    [0.01, .0230, .023, .020, 0.00, -.6060, 0.00, 0., 0., 0.],
    [0.01, .0230, .046, .020, 0.06, -.6050, 0.00, 0., 0., 0.]])
# Toft's modified intensities: the same ellipsoids with contrast a display can show.
MODIFIED_INTENSITIES = np.array([1.0, -0.8, -0.2, -0.2, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1])
VARIANTS = ("modified", "original")


def samples_a_side(size) -> int:
    if (isinstance(size, bool) or not isinstance(size, (int, float))
            or not float(size).is_integer() or not 2 <= size <= MAX_SIZE):
        raise VolumeError(f"size must be a whole number of samples from 2 to {MAX_SIZE}, "
                          f"not {size!r}")
    return int(size)


def grid(size: int):
    """The sample points of the cube: three coordinate arrays that broadcast to ``(n, n, n)``
    (``(n, 1, 1)``, ``(1, n, 1)``, ``(1, 1, n)``: full ones cost 3 x 535 MB at the largest
    size, before the expressions' own) and the spacing."""
    axis = np.linspace(-1.0, 1.0, samples_a_side(size))
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij", sparse=True)
    return x, y, z, 2.0 / (int(size) - 1)


def euler_rows(phi: float, theta: float, psi: float) -> np.ndarray:
    """phantom3d's rotation (z–x–z Euler angles, degrees): rotated = A · (x, y, z)."""
    p, t, s = np.radians([phi, theta, psi])
    cp, sp, ct, st, cs, ss = np.cos(p), np.sin(p), np.cos(t), np.sin(t), np.cos(s), np.sin(s)
    return np.array([[cs * cp - ct * sp * ss, cs * sp + ct * cp * ss, ss * st],
                     [-ss * cp - ct * sp * cs, -ss * sp + ct * cp * cs, cs * st],
                     [st * sp, -st * cp, ct]])


def shepp_logan(size: int = 128, variant: str = "modified"):
    if variant not in VARIANTS:
        raise VolumeError(f"variant must be one of {', '.join(VARIANTS)}, not {variant!r}")
    n = samples_a_side(size)
    axis, h = np.linspace(-1.0, 1.0, n), 2.0 / (n - 1)
    values = np.zeros((n, n, n), dtype=np.float32)
    intensities = SHEPP_LOGAN[:, 0] if variant == "original" else MODIFIED_INTENSITIES
    for row, amount in zip(SHEPP_LOGAN, intensities):
        a, b, c, x0, y0, z0 = row[1:7]
        rot = euler_rows(*row[7:10])
        # only the samples within the ellipsoid's bounding sphere (its centre: rotᵀ · x0)
        centre, reach = rot.T @ np.array([x0, y0, z0]), max(a, b, c)
        box = [slice(*np.searchsorted(axis, [m - reach, m + reach + 1e-12])) for m in centre]
        x, y, z = np.meshgrid(axis[box[0]], axis[box[1]], axis[box[2]], indexing="ij")
        xr = rot[0, 0] * x + rot[0, 1] * y + rot[0, 2] * z
        yr = rot[1, 0] * x + rot[1, 1] * y + rot[1, 2] * z
        zr = rot[2, 0] * x + rot[2, 1] * y + rot[2, 2] * z
        inside = ((xr - x0) / a) ** 2 + ((yr - y0) / b) ** 2 + ((zr - z0) / c) ** 2 <= 1.0
        values[tuple(box)][inside] += np.float32(amount)
    return values, (h, h, h)


def _point(value, name: str) -> np.ndarray:
    """``value`` as a point of the cube's space: three finite numbers within ±10^3."""
    try:
        point = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        point = None
    if point is None or point.shape != (3,) or not np.all(np.isfinite(point)) \
            or np.any(np.abs(point) > 1e3):
        raise VolumeError(f"{name} must be three finite numbers [x, y, z] within ±1000, not "
                          f"{value!r}")
    return point


def sphere(size: int = 64, radius: float = 0.8, density: float = 1.0,
           center=(0.0, 0.0, 0.0)):
    if not 0.0 < radius <= 2.0:
        raise VolumeError(f"radius must lie in (0, 2], not {radius!r}")
    if not 0.0 < density <= 1e6:
        raise VolumeError(f"density must lie in (0, 1e6], not {density!r}")
    center = _point(center, "center")
    x, y, z, h = grid(size)
    d = np.sqrt((x - center[0]) ** 2 + (y - center[1]) ** 2 + (z - center[2]) ** 2)
    ramp = np.clip((radius - d) / h + 0.5, 0.0, 1.0)      # each sample's partial volume
    return (density * ramp).astype(np.float32), (h, h, h)


MAX_BALL_SAMPLES = 50_000_000       # samples within the balls' boxes: a few seconds of numpy
DEFAULT_BALLS = ((-0.35, 0.0, 0.0, 0.55), (0.35, 0.1, 0.0, 0.5), (0.0, -0.2, 0.35, 0.45))


def _reach(axis: np.ndarray, centre: float, radius: float) -> tuple[int, int]:
    """The index range of the samples of ``axis`` within ``radius`` of ``centre``."""
    return (int(np.searchsorted(axis, centre - radius, "left")),
            int(np.searchsorted(axis, centre + radius, "right")))


def metaballs(size: int = 64, balls=DEFAULT_BALLS):
    """``balls``: rows ``x, y, z, R``; the surface is usually taken at iso 0.5."""
    try:
        balls = np.asarray(balls, dtype=np.float64)
    except (TypeError, ValueError):
        raise VolumeError("balls must be rows [x, y, z, R] of numbers") from None
    if balls.ndim != 2 or balls.shape[1] != 4 or not len(balls) or np.any(balls[:, 3] <= 0):
        raise VolumeError("balls must be rows [x, y, z, R] with R > 0")
    if not np.all(np.isfinite(balls)) or np.any(np.abs(balls) > 1e6) \
            or np.any(balls[:, 3] < 1e-6):
        raise VolumeError("balls must be finite numbers within ±10^6, each R at least 10^-6 "
                          "(a NaN centre, or an R whose square is zero, draws nothing)")
    n = samples_a_side(size)
    axis = np.linspace(-1.0, 1.0, n)
    boxes = [tuple(_reach(axis, c, r) for c in (cx, cy, cz)) for cx, cy, cz, r in balls]
    work = sum((i1 - i0) * (j1 - j0) * (k1 - k0) for (i0, i1), (j0, j1), (k0, k1) in boxes)
    if work > MAX_BALL_SAMPLES:
        raise VolumeError(f"{len(balls):,} balls reach {work:,} samples in all; at most "
                          f"{MAX_BALL_SAMPLES:,}: fewer or smaller balls, or a smaller size")
    values = np.zeros((n, n, n))
    for (cx, cy, cz, r), ((i0, i1), (j0, j1), (k0, k1)) in zip(balls, boxes):
        # only the samples within R of the centre can change: its bounding box of samples
        x, y, z = np.meshgrid(axis[i0:i1], axis[j0:j1], axis[k0:k1], indexing="ij")
        q = ((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (r * r)
        values[i0:i1, j0:j1, k0:k1] += np.where(q < 1.0, (1.0 - q) ** 3, 0.0)
    h = 2.0 / (int(size) - 1)
    return values.astype(np.float32), (h, h, h)


def torus(size: int = 64, major: float = 0.6, minor: float = 0.25):
    if not (0.0 < minor < major and major + minor <= 1.0):
        raise VolumeError(f"need 0 < minor < major and major + minor <= 1, "
                          f"not {major!r}, {minor!r}")
    x, y, z, h = grid(size)
    ring = np.sqrt(x * x + y * y) - major
    return (minor - np.sqrt(ring * ring + z * z)).astype(np.float32), (h, h, h)


GENERATORS = {"shepp-logan": shepp_logan, "sphere": sphere, "metaballs": metaballs,
              "torus": torus}
