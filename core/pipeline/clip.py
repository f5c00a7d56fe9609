"""3D clipping of line segments in the canonical view volumes (FvDFH 6.5.3, Fig. 6.46).

Cohen–Sutherland with a 6-bit outcode per endpoint, done in the canonical volume after
N_per / N_par and before any divide — not in homogeneous coordinates, as the course requires.

Every clip plane is written as a linear function ``f(p) <= 0`` inside, so one loop serves
both volumes (bits in pipeline.md's order):

=====  ==============  =====================
 bit   parallel        perspective
=====  ==============  =====================
  0    y > 1           y > -z
  1    y < -1          y < z
  2    x > 1           x > -z
  3    x < -1          x < z
  4    z < -1          z < -1
  5    z > 0           z > z_min
=====  ==============  =====================

A point exactly on a plane is inside. Everything is vectorised numpy over the segments (no
numba here, so a wireframe frame needs no compiler); only segments that are neither trivially
accepted nor rejected enter the clipping loop.
"""

from __future__ import annotations

import numpy as np


def planes(projection: str, z_min: float = 0.0) -> np.ndarray:
    """(6, 4) rows ``(a, b, c, d)``: the point is outside plane i when ``a x + b y + c z + d > 0``."""
    if projection == "parallel":
        return np.array([[0, 1, 0, -1], [0, -1, 0, -1], [1, 0, 0, -1], [-1, 0, 0, -1],
                         [0, 0, -1, -1], [0, 0, 1, 0]], dtype=np.float64)
    if projection == "perspective":
        return np.array([[0, 1, 1, 0], [0, -1, 1, 0], [1, 0, 1, 0], [-1, 0, 1, 0],
                         [0, 0, -1, -1], [0, 0, 1, -z_min]], dtype=np.float64)
    raise ValueError(f"projection must be 'perspective' or 'parallel', not {projection!r}")


def outcodes(points: np.ndarray, projection_or_planes, z_min: float = 0.0) -> np.ndarray:
    """The 6-bit Cohen–Sutherland outcode of each canonical point ``(N, 3)`` → ``(N,)`` int64.

    The second argument is a projection name or a ``planes(...)`` array.
    """
    pl = (planes(projection_or_planes, z_min) if isinstance(projection_or_planes, str)
          else projection_or_planes)
    outside = points @ pl[:, :3].T + pl[:, 3] > 0.0                  # (N, 6)
    return outside.astype(np.int64) @ (np.int64(1) << np.arange(6, dtype=np.int64))


def _cohen_sutherland(a, b, code_a, code_b, pl):
    """Clip the segments a[k]–b[k] (none trivially accepted or rejected) in place.

    FvDFH's loop, run for all segments at once: while a segment is neither accepted nor
    rejected, take an endpoint that is outside, the first plane it violates, and move that
    endpoint to the plane. Returns a mask of the segments that keep a visible part.
    """
    code_a, code_b = code_a.astype(np.int64), code_b.astype(np.int64)
    for _ in range(12):              # each pass clears one bit; 12 bounds round-off cycling
        active = ((code_a | code_b) != 0) & ((code_a & code_b) == 0)
        if not active.any():
            break
        i = np.flatnonzero(active)
        a_out = code_a[i] != 0                      # clip endpoint a if it is outside, else b
        code = np.where(a_out, code_a[i], code_b[i])
        bit = _lowest_bit(code)
        plane = pl[bit]
        out = np.where(a_out[:, None], a[i], b[i])
        other = np.where(a_out[:, None], b[i], a[i])
        f_out = np.einsum("ij,ij->i", plane[:, :3], out) + plane[:, 3]
        f_in = np.einsum("ij,ij->i", plane[:, :3], other) + plane[:, 3]
        # f_out > 0 >= f_in up to round-off (else the AND test rejected); clamp t anyway.
        denominator = f_out - f_in
        t = np.divide(f_out, denominator, out=np.zeros_like(f_out), where=denominator != 0.0)
        t = np.clip(t, 0.0, 1.0)
        moved = out + t[:, None] * (other - out)
        new_code = outcodes(moved, pl) & ~(np.int64(1) << bit)   # on that plane by construction
        ia, ib = i[a_out], i[~a_out]
        a[ia], code_a[ia] = moved[a_out], new_code[a_out]
        b[ib], code_b[ib] = moved[~a_out], new_code[~a_out]
    return (code_a | code_b) == 0


def _lowest_bit(code: np.ndarray) -> np.ndarray:
    """Index of the lowest set bit of each (non-zero) code: the first violated plane."""
    return np.log2(code & -code).astype(np.int64)


def clip_lines(p0: np.ndarray, p1: np.ndarray, projection: str, z_min: float = 0.0):
    """Clip segments ``p0[k]–p1[k]`` (canonical coordinates, ``(N, 3)`` each).

    Returns ``(q0, q1)``: the visible parts of the surviving segments (rejected ones are
    dropped), in input order. Trivially accepted segments come back unchanged.
    """
    p0 = np.asarray(p0, dtype=np.float64).reshape(-1, 3)
    p1 = np.asarray(p1, dtype=np.float64).reshape(-1, 3)
    c0, c1 = outcodes(p0, projection, z_min), outcodes(p1, projection, z_min)
    accept = (c0 | c1) == 0
    reject = (c0 & c1) != 0
    work = ~accept & ~reject
    keep = accept.copy()
    q0, q1 = p0.copy(), p1.copy()
    if work.any():
        w0, w1 = q0[work], q1[work]
        keep[work] = _cohen_sutherland(w0, w1, c0[work], c1[work], planes(projection, z_min))
        q0[work], q1[work] = w0, w1
    return q0[keep], q1[keep]


# --------------------------------------------------------------------- the other clippers
# Selectable with ``RenderSettings.clipper`` (``--clipper``): each keeps the same part of every
# segment as Cohen–Sutherland (the same planes, a point on a plane inside), so the picture is
# the same; they differ in how they find it.
from core.settings import CLIPPERS  # noqa: E402,F401  (named once, with the settings)


def _parametric(p0, p1, f0, f1):
    """Liang–Barsky's interval: ``f0``, ``f1`` (N, 6) are the planes' values at the ends
    (inside where <= 0). A plane the segment enters raises t_in to f0 / (f0 − f1), one it
    leaves lowers t_out to the same (kept as s_out = 1 − t_out, from p1); a segment outside one
    plane at both ends is rejected, and one whose t_in passes t_out misses the volume.
    Returns ``(q0, q1, keep)``; an end inside every plane is kept bit for bit."""
    # Each end's parameter is measured from that end (t from p0 for the entry, s = 1 - t from
    # p1 for the exit): an end moves by its own plane's f / (f_out - f_in), as Cohen–Sutherland
    # moves it, so a segment cut by one plane ends on the same floats.
    with np.errstate(divide="ignore", invalid="ignore"):
        t = f0 / (f0 - f1)
        s = f1 / (f1 - f0)
    entering, leaving = (f0 > 0.0) & (f1 <= 0.0), (f1 > 0.0) & (f0 <= 0.0)
    t_in = np.max(np.where(entering, t, 0.0), axis=1)
    s_out = np.max(np.where(leaving, s, 0.0), axis=1)
    keep = ~((f0 > 0.0) & (f1 > 0.0)).any(axis=1) & (t_in <= 1.0 - s_out)
    q0 = np.where((t_in == 0.0)[:, None], p0, p0 + t_in[:, None] * (p1 - p0))
    q1 = np.where((s_out == 0.0)[:, None], p1, p1 + s_out[:, None] * (p0 - p1))
    return q0[keep], q1[keep], keep


def liang_barsky(p0, p1, projection: str, z_min: float = 0.0):
    """Liang–Barsky (the notes' Cyrus–Beck for the canonical volume; FvDFH 3.12.4): the
    segment as p0 + t (p1 − p0), each plane cutting the interval [0, 1] at once, no endpoint
    moved plane by plane. Returns ``(q0, q1)`` as :func:`clip_lines` does."""
    p0 = np.asarray(p0, dtype=np.float64).reshape(-1, 3)
    p1 = np.asarray(p1, dtype=np.float64).reshape(-1, 3)
    pl = planes(projection, z_min)
    q0, q1, _ = _parametric(p0, p1, p0 @ pl[:, :3].T + pl[:, 3], p1 @ pl[:, :3].T + pl[:, 3])
    return q0, q1


# The clip volume ``−W ≤ X ≤ W, −W ≤ Y ≤ W, −W ≤ Z ≤ 0``: (6, 4) rows, each plane outside
# where ``h · (X, Y, Z, W) > 0``, in the outcodes' order.
HOMOGENEOUS_PLANES = np.array([[0, 1, 0, -1], [0, -1, 0, -1], [1, 0, 0, -1], [-1, 0, 0, -1],
                               [0, 0, -1, -1], [0, 0, 1, 0]], dtype=np.float64)


def clip_space(points, projection: str, z_min: float = 0.0) -> np.ndarray:
    """``(N, 4)`` (X, Y, Z, W) = M (x, y, z, 1): FvDFH 6.5.4's perspective-to-parallel M for
    perspective, the identity for parallel. M's rows written out, ``Z = (z − z_min) /
    (1 + z_min)``, ``W = −z``, rather than a matrix product: a point on the front or back plane
    then lands exactly on Z = 0 or Z = −W (the product's rounding put some just outside)."""
    x, y, z = np.asarray(points, dtype=np.float64).reshape(-1, 3).T
    if projection == "perspective":
        return np.stack([x, y, (z - z_min) / (1.0 + z_min), -z], axis=1)
    if projection == "parallel":
        return np.stack([x, y, z, np.ones_like(z)], axis=1)
    raise ValueError(f"projection must be 'perspective' or 'parallel', not {projection!r}")


def homogeneous(p0, p1, projection: str, z_min: float = 0.0):
    """Clipping in homogeneous coordinates (FvDFH 6.5.4, the notes' alternative): both ends
    taken by M into (X, Y, Z, W) before any divide and clipped there, parametrically, against
    the planes through the origin of 4D; a linear M keeps t, so the visible part's ends are
    the canonical points at the same t (returned as :func:`clip_lines` does). No point behind
    the eye survives: inside the volume Z ≤ 0 and Z ≥ −W make W > 0."""
    p0 = np.asarray(p0, dtype=np.float64).reshape(-1, 3)
    p1 = np.asarray(p1, dtype=np.float64).reshape(-1, 3)
    f0 = clip_space(p0, projection, z_min) @ HOMOGENEOUS_PLANES.T
    f1 = clip_space(p1, projection, z_min) @ HOMOGENEOUS_PLANES.T
    q0, q1, _ = _parametric(p0, p1, f0, f1)
    return q0, q1


def clip_lines_with(clipper: str, p0, p1, projection: str, z_min: float = 0.0):
    """The segments clipped by ``clipper`` (one of :data:`CLIPPERS`)."""
    if clipper == "liang-barsky":
        return liang_barsky(p0, p1, projection, z_min)
    if clipper == "homogeneous":
        return homogeneous(p0, p1, projection, z_min)
    if clipper != "cohen-sutherland":
        raise ValueError(f"clipper must be one of {', '.join(CLIPPERS)}, not {clipper!r}")
    return clip_lines(p0, p1, projection, z_min)
