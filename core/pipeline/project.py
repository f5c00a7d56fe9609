"""Projection to the device (FvDFH 6.5.4 and 6.5.6).

Takes canonical-volume points (after N_per / N_par and clipping) and returns device
coordinates: x to the right and y up in pixels (origin at the framebuffer's bottom-left,
pixel centres at half-integers), and z in [-1, 0] with larger z nearer.

- Wireframe perspective: ``M_per`` with ``d = -1`` projects onto the back plane, then
  ``M_vv3dv`` maps the canonical square to the viewport (the whole framebuffer, or a
  letterboxed part of it when the aspect is kept), and the divide by W comes last.
- Depth for the z-buffer: FvDFH's perspective-to-parallel matrix ``M`` keeps relative depth,
  lines and planes; after the divide the perspective volume is the parallel one. Parallel
  views need neither matrix.
"""

from __future__ import annotations

import numpy as np

from core.camera.film import viewport  # noqa: F401  (the device rectangle: the film's)
from core.transforms import scale, translate


def m_per(d: float = -1.0) -> np.ndarray:
    """M_per: perspective projection onto the plane z = d, centre of projection at the origin."""
    m = np.eye(4)
    m[3, 2], m[3, 3] = 1.0 / d, 0.0
    return m


def m_general(z_p: float, q: float, direction) -> np.ndarray:
    """M_general (FvDFH eq. 6.18): projection onto the plane ``z = z_p`` from the centre of
    projection ``(0, 0, z_p) + q (dx, dy, dz)``, ``direction`` = (dx, dy, dz) a unit vector
    with dz ≠ 0; ``q = inf``: a parallel projection along ``direction``. Its special cases:
    M_per (z_p = d, q = |d|, direction (0, 0, -sign d): the centre at the origin), M'_per
    (z_p = 0, q = d, (0, 0, -1)), M_ort (z_p = 0, q = inf, (0, 0, -1)) and the oblique
    projections (q = inf). The course packet's entry (2, 3) reads z_p/(Q dz) + z_p; FvDFH's
    is z_p²/(Q dz) + z_p, which alone gives M_per back (docs/departures.md)."""
    dx, dy, dz = (float(c) for c in direction)
    if dz == 0.0 or not np.isfinite([dx, dy, dz, z_p]).all() or not q > 0.0:
        raise ValueError(f"M_general needs dz != 0, finite z_p and direction, and q > 0, not "
                         f"z_p={z_p!r}, q={q!r}, direction={direction!r}")
    inv = 0.0 if np.isinf(q) else 1.0 / (q * dz)       # 1 / (Q dz); 0 when Q is infinite
    return np.array([[1.0, 0.0, -dx / dz, z_p * dx / dz],
                     [0.0, 1.0, -dy / dz, z_p * dy / dz],
                     [0.0, 0.0, -z_p * inv, z_p * z_p * inv + z_p],
                     [0.0, 0.0, -inv, z_p * inv + 1.0]])


def perspective_to_parallel(z_min: float) -> np.ndarray:
    """FvDFH eq. 6.48: maps the canonical perspective volume onto the parallel one (after /W)."""
    return np.array([[1.0, 0.0, 0.0, 0.0],
                     [0.0, 1.0, 0.0, 0.0],
                     [0.0, 0.0, 1.0 / (1.0 + z_min), -z_min / (1.0 + z_min)],
                     [0.0, 0.0, -1.0, 0.0]])


def m_vv3dv(x_min, x_max, y_min, y_max, z_min=-1.0, z_max=0.0) -> np.ndarray:
    """``T(x_min, y_min, z_min) · S((x_max-x_min)/2, (y_max-y_min)/2, z_max-z_min) · T(1, 1, 1)``.

    Maps the canonical parallel volume onto the 3D viewport. The defaults keep z as it is, so
    the z-buffer holds canonical depth in [-1, 0].
    """
    return (translate(x_min, y_min, z_min)
            @ scale((x_max - x_min) / 2, (y_max - y_min) / 2, z_max - z_min)
            @ translate(1, 1, 1))


def divide_by_w(homogeneous: np.ndarray) -> np.ndarray:
    """``(N, 4)`` → ``(N, 3)``: the homogeneous divide, last step of the chain."""
    return homogeneous[:, :3] / homogeneous[:, 3:4]


def _homogeneous(points: np.ndarray) -> np.ndarray:
    return np.concatenate([points, np.ones((len(points), 1))], axis=1)


def line_matrix(projection: str, vp) -> np.ndarray:
    """Wireframe: ``M_vv3dv · M_per`` (perspective, d = -1) or ``M_vv3dv`` (parallel)."""
    m = m_vv3dv(*vp)
    if projection == "perspective":
        m = m @ m_per(-1.0)
    return m


def project_lines(points: np.ndarray, projection: str, vp) -> np.ndarray:
    """Wireframe: canonical ``(N, 3)`` → device ``(N, 3)`` via M_per (perspective), M_vv3dv, /W.

    Each row of the matrix is applied as ``m0 x + m1 y + m2 z + m3``, left to right, not by a
    BLAS product (whose order and fused multiply-adds vary): the compiled wireframe
    (``core.pipeline.wireframe``) does the same sums and so lands on the same pixels.
    """
    m = line_matrix(projection, vp)
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    x, y, z = points[:, 0], points[:, 1], points[:, 2]
    h = np.empty((len(points), 4))
    for r in range(4):
        h[:, r] = m[r, 0] * x + m[r, 1] * y + m[r, 2] * z + m[r, 3]
    return divide_by_w(h)


def triangle_matrix(projection: str, z_min: float, vp) -> np.ndarray:
    """The one matrix that carries canonical points to the device before the divide:
    ``M_vv3dv · M`` (perspective, M the perspective-to-parallel matrix) or ``M_vv3dv``."""
    m = m_vv3dv(*vp)
    if projection == "perspective":
        m = m @ perspective_to_parallel(z_min)
    return m


def project_triangles(points: np.ndarray, projection: str, z_min: float, vp):
    """Solids: canonical ``(N, 3)`` → ``(device (N, 3), inv_w (N,))``.

    Perspective goes through the perspective-to-parallel matrix so that depth stays affine in
    screen space; ``inv_w`` (1/W) lets the rasterizer interpolate attributes perspective-
    correctly. The clipper guarantees W = -z > 0 for every vertex a triangle uses.
    (``core.pipeline.vertex_kernels.transform_projective`` is the compiled twin the renderer uses.)
    """
    h = _homogeneous(points) @ triangle_matrix(projection, z_min, vp).T
    # The clipper keeps its input vertex array whole, so vertices no triangle uses may lie
    # outside the volume, even at the eye (W = 0): they get inv_w = 0 instead of a division.
    inv_w = np.divide(1.0, h[:, 3], out=np.zeros(len(h)), where=h[:, 3] > 0.0)
    return h[:, :3] * inv_w[:, None], inv_w
