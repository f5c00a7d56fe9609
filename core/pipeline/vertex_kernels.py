"""Compiled per-vertex loops of the triangle path: the normalizing transform and the projection.

At a million triangles the vertex arrays are half a million rows, and numpy's way of applying
a 4 x 4 matrix — append a column of ones, multiply, slice, divide — builds several (N, 4)
temporaries and spends its time moving memory (measured: 10–14 ms for N_per and 20–30 ms for
the projection at 1M triangles). These loops read each point once and write each result once,
on all cores. They compute exactly what ``core.transforms.apply`` and
``core.pipeline.project.project_triangles`` compute
(``tests/core/pipeline/test_vertex_kernels.py`` holds them together); the wireframe path keeps
the numpy forms and so needs no compiler.
"""

from __future__ import annotations

import numpy as np

from core.arrays import read_only
from core.jit import njit, prange
from core.pipeline.clip_polygon import CHUNKS, outcode


# Below this many points one core is quicker: waking the second costs ~0.1 ms.
PARALLEL_POINTS = 20_000


# numpy's error model, as in the parallel loops that call it with their index: one
# compiled form for both (core.jit.reuse_plain_overloads)
@njit(cache=True, error_model="numpy")
def _affine_point(m, points, out, i):
    x, y, z = points[i, 0], points[i, 1], points[i, 2]
    for r in range(3):
        out[i, r] = m[r, 0] * x + m[r, 1] * y + m[r, 2] * z + m[r, 3]


@njit(cache=True, error_model="numpy")
def _projective_point(m, points, out, inv_w, i):
    x, y, z = points[i, 0], points[i, 1], points[i, 2]
    w = m[3, 0] * x + m[3, 1] * y + m[3, 2] * z + m[3, 3]
    # Vertices no triangle uses may sit at or behind the eye (W <= 0): no division there.
    iw = 1.0 / w if w > 0.0 else 0.0
    inv_w[i] = iw
    for r in range(3):
        out[i, r] = (m[r, 0] * x + m[r, 1] * y + m[r, 2] * z + m[r, 3]) * iw


@njit(cache=True, parallel=True, nogil=True)
def _affine_parallel(m, points, out):
    for i in prange(points.shape[0]):
        _affine_point(m, points, out, np.uint64(i))


@njit(cache=True, nogil=True)
def _affine_serial(m, points, out):
    for i in range(points.shape[0]):
        _affine_point(m, points, out, np.uint64(i))


@njit(cache=True, parallel=True, nogil=True)
def _projective_parallel(m, points, out, inv_w):
    for i in prange(points.shape[0]):
        _projective_point(m, points, out, inv_w, np.uint64(i))


@njit(cache=True, nogil=True)
def _projective_serial(m, points, out, inv_w):
    for i in range(points.shape[0]):
        _projective_point(m, points, out, inv_w, np.uint64(i))


def transform_affine(m: np.ndarray, points: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``(N, 3)`` points through an affine 4 x 4 matrix (last row 0 0 0 1) → ``(N, 3)``
    (into ``out`` when given)."""
    out = np.empty((len(points), 3)) if out is None else out
    kernel = _affine_parallel if len(points) >= PARALLEL_POINTS else _affine_serial
    kernel(read_only(np.ascontiguousarray(m, dtype=np.float64)),
           read_only(np.ascontiguousarray(points, dtype=np.float64)), out)
    return out


def transform_projective(m: np.ndarray, points: np.ndarray, out: np.ndarray | None = None,
                         inv_w: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(N, 3)`` points through a 4 x 4 matrix and the divide by W → ``(xyz (N, 3), 1/W (N,))``
    (into ``out`` and ``inv_w`` when given)."""
    out = np.empty((len(points), 3)) if out is None else out
    inv_w = np.empty(len(points)) if inv_w is None else inv_w
    kernel = _projective_parallel if len(points) >= PARALLEL_POINTS else _projective_serial
    kernel(read_only(np.ascontiguousarray(m, dtype=np.float64)),
           read_only(np.ascontiguousarray(points, dtype=np.float64)), out, inv_w)
    return out, inv_w


# The triangle path's work per vertex in one call: N, the outcode, M and the divide.


@njit(cache=True, error_model="numpy")
def _view_run(n, m, points, canonical, codes, device, inv_w, perspective, z_min, first, end):
    """Points ``first`` to ``end``: their canonical points ``N p``, those points' outcodes and
    their device points (``M``, divided by W, from the canonical points as
    :func:`transform_projective` computes them: the same numbers). Returns the OR of the
    outcodes.

    Three loops over the rows as flat runs of numbers, the matrices' entries held as
    scalars, rather than one loop calling the per-point helpers: each loop is then simple
    enough for the compiler to run several points at a time (the bunny's 36,218 points on
    one core: 0.30 → 0.15 ms, the same numbers)."""
    p = points[first:end].reshape(-1)
    c = canonical[first:end].reshape(-1)
    d = device[first:end].reshape(-1)
    iw = inv_w[first:end]
    n00, n01, n02, n03 = n[0, 0], n[0, 1], n[0, 2], n[0, 3]
    n10, n11, n12, n13 = n[1, 0], n[1, 1], n[1, 2], n[1, 3]
    n20, n21, n22, n23 = n[2, 0], n[2, 1], n[2, 2], n[2, 3]
    for k in range(iw.shape[0]):                    # N (_affine_point's sums)
        x, y, z = p[3 * k], p[3 * k + 1], p[3 * k + 2]
        c[3 * k] = n00 * x + n01 * y + n02 * z + n03
        c[3 * k + 1] = n10 * x + n11 * y + n12 * z + n13
        c[3 * k + 2] = n20 * x + n21 * y + n22 * z + n23
    any_outside = 0
    for k in range(iw.shape[0]):
        code = outcode(c[3 * k], c[3 * k + 1], c[3 * k + 2], perspective, z_min)
        codes[first + k] = code
        any_outside |= code
    m00, m01, m02, m03 = m[0, 0], m[0, 1], m[0, 2], m[0, 3]
    m10, m11, m12, m13 = m[1, 0], m[1, 1], m[1, 2], m[1, 3]
    m20, m21, m22, m23 = m[2, 0], m[2, 1], m[2, 2], m[2, 3]
    m30, m31, m32, m33 = m[3, 0], m[3, 1], m[3, 2], m[3, 3]
    for k in range(iw.shape[0]):                    # M and the divide (_projective_point's)
        x, y, z = c[3 * k], c[3 * k + 1], c[3 * k + 2]
        w = m30 * x + m31 * y + m32 * z + m33
        s = 1.0 / w if w > 0.0 else 0.0
        iw[k] = s
        d[3 * k] = (m00 * x + m01 * y + m02 * z + m03) * s
        d[3 * k + 1] = (m10 * x + m11 * y + m12 * z + m13) * s
        d[3 * k + 2] = (m20 * x + m21 * y + m22 * z + m23) * s
    return any_outside


@njit(cache=True, parallel=True, nogil=True)
def _view_parallel(n, m, points, canonical, codes, device, inv_w, perspective, z_min):
    count = points.shape[0]
    ors = np.zeros(CHUNKS, np.int64)
    for chunk in prange(CHUNKS):
        ors[chunk] = _view_run(n, m, points, canonical, codes, device, inv_w, perspective,
                               z_min, chunk * count // CHUNKS, (chunk + 1) * count // CHUNKS)
    any_outside = 0
    for chunk in range(CHUNKS):
        any_outside |= ors[chunk]
    return any_outside


def view_points(n: np.ndarray, m: np.ndarray, points: np.ndarray, perspective: bool,
                z_min: float, canonical: np.ndarray, codes: np.ndarray, device: np.ndarray,
                inv_w: np.ndarray) -> int:
    """The normalizing transform, the clipper's outcodes and the projection of ``(N, 3)``
    points in one call, chunk by chunk (three calls over all points took 0.36 ms a frame on
    the bunny's 36,218 vertices, one pass 0.22, the chunks' loops (:func:`_view_run`) less):
    ``canonical`` (what :func:`transform_affine` gives), ``codes`` (what the clipper's
    ``outcodes`` gives), ``device`` and ``inv_w`` (what :func:`transform_projective` gives
    for the canonical points), filled in place. Returns the OR of the outcodes: 0 when every
    point lies inside the view volume, and the device points are then the frame's."""
    given = (read_only(np.ascontiguousarray(n, dtype=np.float64)),
             read_only(np.ascontiguousarray(m, dtype=np.float64)),
             read_only(np.ascontiguousarray(points, dtype=np.float64)), canonical, codes,
             device, inv_w, bool(perspective), float(z_min))
    if len(points) >= PARALLEL_POINTS:
        return int(_view_parallel(*given))
    return int(_view_run(*given, 0, len(points)))
