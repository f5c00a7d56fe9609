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

A point exactly on a plane is inside. Trivial accept and reject are vectorised; only the
segments that need it go through the compiled loop.
"""

from __future__ import annotations

import numpy as np
from numba import njit


def planes(projection: str, z_min: float = 0.0) -> np.ndarray:
    """(6, 4) rows ``(a, b, c, d)``: the point is outside plane i when ``a x + b y + c z + d > 0``."""
    if projection == "parallel":
        return np.array([[0, 1, 0, -1], [0, -1, 0, -1], [1, 0, 0, -1], [-1, 0, 0, -1],
                         [0, 0, -1, -1], [0, 0, 1, 0]], dtype=np.float64)
    if projection == "perspective":
        return np.array([[0, 1, 1, 0], [0, -1, 1, 0], [1, 0, 1, 0], [-1, 0, 1, 0],
                         [0, 0, -1, -1], [0, 0, 1, -z_min]], dtype=np.float64)
    raise ValueError(f"projection must be 'perspective' or 'parallel', not {projection!r}")


def outcodes(points: np.ndarray, projection: str, z_min: float = 0.0) -> np.ndarray:
    """The 6-bit Cohen–Sutherland outcode of each canonical point ``(N, 3)`` → ``(N,)`` uint8."""
    pl = planes(projection, z_min)
    outside = points @ pl[:, :3].T + pl[:, 3] > 0.0                  # (N, 6)
    return (outside.astype(np.uint8) << np.arange(6, dtype=np.uint8)).sum(axis=1, dtype=np.uint8)


@njit(cache=True)
def _outcode(p, pl):
    code = np.int64(0)
    for i in range(6):
        if pl[i, 0] * p[0] + pl[i, 1] * p[1] + pl[i, 2] * p[2] + pl[i, 3] > 0.0:
            code |= np.int64(1) << i
    return code


@njit(cache=True)
def _cohen_sutherland(p0, p1, code0, code1, pl, keep):
    """Clip segments p0[k]–p1[k] in place; keep[k] = False where nothing is left."""
    for k in range(p0.shape[0]):
        a, b = p0[k].copy(), p1[k].copy()
        ca, cb = np.int64(code0[k]), np.int64(code1[k])
        for _ in range(12):          # each pass clears one bit; 12 bounds round-off cycling
            if ca == 0 and cb == 0:  # trivial accept
                break
            if ca & cb != 0:         # trivial reject: both outside one plane
                break
            # Pick an endpoint that is outside and the first plane it violates.
            if ca != 0:
                out, other, code = a, b, ca
            else:
                out, other, code = b, a, cb
            i = 0
            while (code >> i) & 1 == 0:
                i += 1
            f_out = pl[i, 0] * out[0] + pl[i, 1] * out[1] + pl[i, 2] * out[2] + pl[i, 3]
            f_in = pl[i, 0] * other[0] + pl[i, 1] * other[1] + pl[i, 2] * other[2] + pl[i, 3]
            # f_out > 0 >= f_in up to round-off (else the AND test rejected); clamp t anyway.
            t = min(max(f_out / (f_out - f_in), 0.0), 1.0) if f_out != f_in else 0.0
            for c in range(3):
                out[c] = out[c] + t * (other[c] - out[c])
            new_code = _outcode(out, pl) & ~(np.int64(1) << i)   # on plane i by construction
            if ca != 0:
                ca = new_code
            else:
                cb = new_code
        if ca == 0 and cb == 0:
            p0[k] = a
            p1[k] = b
            keep[k] = True
        else:
            keep[k] = False


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
        kept = np.zeros(len(w0), dtype=np.bool_)
        _cohen_sutherland(w0, w1, c0[work], c1[work], planes(projection, z_min), kept)
        q0[work], q1[work] = w0, w1
        keep[work] = kept
    return q0[keep], q1[keep]
