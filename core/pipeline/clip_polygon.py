"""Clipping triangles against the canonical view volume: outcodes, then Sutherland–Hodgman.

Takes triangles in the canonical volume, after N_per or N_par and before any divide
(FvDFH 6.5.3–6.5.4; pipeline.md "Clipping in 3D"): ``points`` (V, 3) float64, ``triangles``
(T, 3) int64, per-vertex ``attrs`` (V, K) float64 (K may be 0), the ``projection``
("perspective" or "parallel") and the front plane ``z_min`` of the perspective volume.

Returns :class:`ClippedTriangles`: points (V', 3), triangles (T', 3), attrs (V', K) and
``source`` (T',) int64, the input triangle each output triangle came from.

* Each vertex gets FvDFH's 6-bit outcode in one compiled pass (the numpy version, six
  comparisons on strided columns, took 8 ms for 500k vertices). A point exactly on a plane
  is inside. A triangle whose codes are all 0 is trivially accepted and passes through
  untouched (same vertex indices); one whose codes AND to non-zero lies wholly outside one
  plane and is trivially rejected. When every vertex is inside, the inputs are returned.
* Only the remaining triangles are clipped: Sutherland–Hodgman (FvDFH 3.14.1, Fig. 3.49)
  against each plane their codes say they cross, every attribute interpolated with the same
  parameter t as the position, and the convex result fanned back into triangles. New vertices
  are appended after the input ones; vertices of the input that survive keep their index.
* Output order: the accepted triangles in input order, then the clipped ones in input order.
* ``clipper`` (``--clipper``) swaps the steps for the triangles that are cut: this module's
  Sutherland–Hodgman ("cohen-sutherland", the default), Sutherland–Hodgman with Liang–Barsky's
  parametric tests (:mod:`core.pipeline.clip_liang_barsky`) or in homogeneous clip space
  before the divide (:mod:`core.pipeline.clip_homogeneous`). Same outputs, within 1e-12.
  The loop over the triangles and the fans they come out as are one function for all three,
  :func:`clip_and_fan`, given each clipper's steps (a corner's row, one plane's stage, a
  row's canonical point).

Robustness: the clip happens in the canonical volume, so a triangle crossing the eye plane
never reaches a divide; an intersection is always computed from the inside end of an edge
(t = d_in / (d_in - d_out) with d_in >= 0 > d_out, never 0/0), so both triangles sharing an
edge get bit-identical crossing points and the mesh stays watertight. Each new vertex is then
put exactly on its plane. A NaN or infinite coordinate puts its vertex outside (NaN fails
both planes of its axis), and a triangle that uses such a vertex is never output.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import read_only
from core.jit import njit, prange
from core.pipeline import clip_homogeneous as homogeneous
from core.pipeline import clip_liang_barsky as liang_barsky
from core.settings import CLIPPERS, PROJECTIONS

# Outcode bits, in FvDFH's order (parallel volume | perspective volume).
ABOVE = 1  # y > 1        | y > -z
BELOW = 2  # y < -1       | y < z
RIGHT = 4  # x > 1        | x > -z
LEFT = 8  # x < -1        | x < z
BEHIND = 16  # z < -1     | z < -1   (beyond the back plane)
FRONT = 32  # z > 0       | z > z_min (in front of the front plane)
ALL_PLANES = 63

# The order Sutherland–Hodgman visits the planes (k, the outcode bit 1 << k): front and back
# first, so that the part of a triangle behind the eye is gone before the side planes (which
# meet at the eye) are used.
_PLANE_ORDER = np.array([5, 4, 0, 1, 2, 3], dtype=np.int64)   # FRONT, BEHIND, ABOVE, ...

MAX_POLYGON = 9  # a triangle clipped by six planes has at most 3 + 6 vertices
MAX_FAN = MAX_POLYGON - 2


@dataclass
class ClippedTriangles:
    """Triangles inside the canonical volume, ready for projection to the device."""

    points: np.ndarray  # (V', 3) float64, canonical coordinates
    triangles: np.ndarray  # (T', 3) int64 indices into points
    attrs: np.ndarray  # (V', K) float64, interpolated like the positions
    source: np.ndarray  # (T',) int64, index of the input triangle


def _check_projection(projection: str) -> bool:
    if projection not in PROJECTIONS:
        raise ValueError(f"projection must be 'perspective' or 'parallel', not {projection!r}")
    return projection == "perspective"


@njit(cache=True)
def outcode(x, y, z, perspective, z_min):
    """The outcode of one canonical point (see :func:`outcodes`). Each bit is "not inside"
    rather than "outside", so that a NaN coordinate, which fails every comparison, lands
    outside. No branches: a loop over points runs at memory speed."""
    if perspective:  # the side planes are x, y = +-z; the same bounds serve x and y
        high, low, near = -z, z, z_min
    else:
        high, low, near = 1.0, -1.0, 0.0
    return (np.int64(not (y <= high)) * ABOVE | np.int64(not (y >= low)) * BELOW
            | np.int64(not (x <= high)) * RIGHT | np.int64(not (x >= low)) * LEFT
            | np.int64(not (z >= -1.0)) * BEHIND | np.int64(not (z <= near)) * FRONT)


@njit(cache=True)
def _outcodes(points, perspective, z_min, codes, first, end):
    """Outcode of points first..end-1 into ``codes``; returns the OR of them all (0: all
    inside). (No default arguments: numba dispatches a call that omits them about 25 times
    slower, 0.1 ms a frame.)"""
    any_outside = 0
    for v in range(first, end):
        code = outcode(points[v, 0], points[v, 1], points[v, 2], perspective, z_min)
        codes[v] = code
        any_outside |= code
    return any_outside


def outcodes(points: np.ndarray, projection: str, z_min: float = 0.0) -> np.ndarray:
    """FvDFH's 6-bit outcode of each point, (N,) uint8 (0 = inside or on the volume).

    Bits ABOVE, BELOW, RIGHT, LEFT, BEHIND, FRONT as defined in this module, for the
    canonical parallel volume (-1 <= x, y <= 1, -1 <= z <= 0) or perspective volume
    (z <= x, y <= -z, -1 <= z <= z_min). A NaN or infinite coordinate sets every bit it
    cannot satisfy; a NaN coordinate is outside both of its planes.

    One compiled pass over the points (the clipper's own classification runs on all cores
    from PARALLEL_POINTS points); ``points`` may be a strided view (the first three columns
    of homogeneous points) and is not copied.
    """
    perspective = _check_projection(projection)
    points = np.asarray(points, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] < 3:
        raise ValueError(f"points must be (N, 3), got {points.shape}")
    codes = np.empty(points.shape[0], np.uint8)
    _outcodes(points, perspective, float(z_min), codes, 0, points.shape[0])
    return codes


# From this many points the outcodes are found on all cores, in chunks (500k points: 2.5 ms
# on one core).
PARALLEL_POINTS = 200_000
CHUNKS = 64


@njit(cache=True, parallel=True, nogil=True)
def _outcodes_parallel(points, perspective, z_min, codes):
    n = points.shape[0]
    ors = np.zeros(CHUNKS, np.int64)
    for chunk in prange(CHUNKS):
        ors[chunk] = _outcodes(points, perspective, z_min, codes, chunk * n // CHUNKS,
                               (chunk + 1) * n // CHUNKS)
    any_outside = 0
    for chunk in range(CHUNKS):
        any_outside |= ors[chunk]
    return any_outside


def _outcodes_and_any(points, perspective, z_min):
    codes = np.empty(points.shape[0], np.uint8)
    if points.shape[0] >= PARALLEL_POINTS:
        return codes, _outcodes_parallel(points, perspective, float(z_min), codes)
    return codes, _outcodes(points, perspective, float(z_min), codes, 0, points.shape[0])


@njit(cache=True)
def _classify(triangles, codes):
    """Trivial accept (OR of the corner codes is 0) and reject (AND is not 0), in order.

    Returns (kept, todo, bad): the accepted triangles, those that need clipping, and how many
    name a vertex that does not exist.
    """
    n = triangles.shape[0]
    kept = np.empty(n, np.int64)
    todo = np.empty(n, np.int64)
    n_kept = 0
    n_todo = 0
    bad = 0
    for t in range(n):
        v0 = triangles[t, 0]
        v1 = triangles[t, 1]
        v2 = triangles[t, 2]
        if min(v0, v1, v2) < 0 or max(v0, v1, v2) >= codes.shape[0]:
            bad += 1
            continue
        c0 = codes[triangles[t, 0]]
        c1 = codes[triangles[t, 1]]
        c2 = codes[triangles[t, 2]]
        if (c0 | c1 | c2) == 0:
            kept[n_kept] = t
            n_kept += 1
        elif (c0 & c1 & c2) == 0:
            todo[n_todo] = t
            n_todo += 1
    return kept[:n_kept], todo[:n_todo], bad


# --------------------------------------------------------------------------------------------
# Sutherland–Hodgman (FvDFH Fig. 3.49), one triangle at a time


@njit(cache=True)
def _distance(plane, x, y, z, perspective, z_min):
    """Signed distance-like value of (x, y, z) from a clip plane: >= 0 inside, < 0 outside."""
    if plane == ABOVE:
        return (-z if perspective else 1.0) - y
    if plane == BELOW:
        return y - (z if perspective else -1.0)
    if plane == RIGHT:
        return (-z if perspective else 1.0) - x
    if plane == LEFT:
        return x - (z if perspective else -1.0)
    if plane == BEHIND:
        return z + 1.0
    return (z_min if perspective else 0.0) - z  # FRONT


@njit(cache=True)
def _put_on_plane(plane, p, perspective, z_min):
    """Remove the rounding left by the interpolation: set the coordinate the plane fixes."""
    if plane == ABOVE:
        p[1] = -p[2] if perspective else 1.0
    elif plane == BELOW:
        p[1] = p[2] if perspective else -1.0
    elif plane == RIGHT:
        p[0] = -p[2] if perspective else 1.0
    elif plane == LEFT:
        p[0] = p[2] if perspective else -1.0
    elif plane == BEHIND:
        p[2] = -1.0
    else:
        p[2] = z_min if perspective else 0.0


@njit(cache=True)
def _intersect(plane, inside_p, inside_a, d_in, outside_p, outside_a, d_out, out_p, out_a,
               perspective, z_min):
    """The crossing of edge inside->outside with the plane, positions and attributes alike."""
    t = d_in / (d_in - d_out)  # d_in >= 0 > d_out: 0 <= t < 1, never 0/0
    for c in range(3):
        out_p[c] = inside_p[c] + t * (outside_p[c] - inside_p[c])
    for k in range(inside_a.shape[0]):
        out_a[k] = inside_a[k] + t * (outside_a[k] - inside_a[k])
    _put_on_plane(plane, out_p, perspective, z_min)


@njit(cache=True)
def _corner(x, y, z, perspective, z_min, row):
    """A corner's polygon row: its position (this clipper carries nothing else)."""
    row[0] = x
    row[1] = y
    row[2] = z


@njit(cache=True)
def _position(row, perspective, p):
    """The canonical point of a polygon row: its first three columns (Liang–Barsky's row
    carries its boundary values after them)."""
    p[0] = row[0]
    p[1] = row[1]
    p[2] = row[2]


@njit(cache=True)
def _clip_against_plane(k, in_p, in_a, in_id, n_in, out_p, out_a, out_id, perspective, z_min):
    """SutherlandHodgmanPolygonClip: the polygon in_* (n_in vertices) against plane k (its
    outcode bit is ``1 << k``).

    Walks the edges s->p: p inside -> output p (preceded by the crossing if s was outside);
    p outside and s inside -> output the crossing. Returns the output vertex count. A vertex
    keeps its id (index of the input vertex) or gets -1 when it is a new crossing point.
    """
    plane = 1 << k
    n_out = 0
    s = n_in - 1
    d_s = _distance(plane, in_p[s, 0], in_p[s, 1], in_p[s, 2], perspective, z_min)
    for p in range(n_in):
        d_p = _distance(plane, in_p[p, 0], in_p[p, 1], in_p[p, 2], perspective, z_min)
        if d_p >= 0.0:
            if d_s < 0.0:  # entering: the crossing, computed from the inside end p
                _intersect(plane, in_p[p], in_a[p], d_p, in_p[s], in_a[s], d_s, out_p[n_out],
                           out_a[n_out], perspective, z_min)
                out_id[n_out] = -1
                n_out += 1
            out_p[n_out] = in_p[p]
            out_a[n_out] = in_a[p]
            out_id[n_out] = in_id[p]
            n_out += 1
        elif d_s >= 0.0:  # leaving: the crossing, computed from the inside end s
            _intersect(plane, in_p[s], in_a[s], d_s, in_p[p], in_a[p], d_p, out_p[n_out],
                       out_a[n_out], perspective, z_min)
            out_id[n_out] = -1
            n_out += 1
        s = p
        d_s = d_p
    return n_out


# --------------------------------------------------------------------------------------------
# The loop every clipper shares: each triangle to a polygon, plane by plane, fanned out


# Inlined into each clipper's kernel (numba's IR inlining): its function arguments become
# static calls there, so each kernel is cached and compiled as its own loop was. (Called, not
# inlined, a function argument is a pointer to a Python object: the kernel could not be cached.)
@njit(inline="always")
def clip_and_fan(points, triangles, attrs, codes, todo, perspective, z_min, width,
                 every_plane, corner, clip_against_plane, position):
    """Clip the triangles listed in ``todo``; returns new points, attrs, triangles, sources.

    A clipper is three steps over polygon rows of ``width`` floats: ``corner(x, y, z,
    perspective, z_min, row)`` fills a corner's row, ``clip_against_plane(k, in_rows, in_a,
    in_id, n_in, out_rows, out_a, out_id, perspective, z_min)`` is one Sutherland–Hodgman
    stage against plane k (outcode bit ``1 << k``; returns the vertex count, a crossing gets
    id -1) and ``position(row, perspective, p)`` writes a row's canonical point. The planes
    are those some corner's outcode is outside of, or all six with ``every_plane``.

    New vertices are numbered from len(points) on; a vertex of the input that survives the
    clip keeps its index.
    """
    n_attrs = attrs.shape[1]
    n_points = points.shape[0]
    m = todo.shape[0]
    new_points = np.empty((m * MAX_POLYGON, 3))
    new_attrs = np.empty((m * MAX_POLYGON, n_attrs))
    new_triangles = np.empty((m * MAX_FAN, 3), np.int64)
    new_source = np.empty(m * MAX_FAN, np.int64)
    # two polygon buffers, swapped after each plane
    poly = np.empty((2, MAX_POLYGON, width))
    poly_a = np.empty((2, MAX_POLYGON, n_attrs))
    poly_id = np.empty((2, MAX_POLYGON), np.int64)
    index = np.empty(MAX_POLYGON, np.int64)
    n_new_points = 0
    n_new_triangles = 0
    for i in range(m):
        t = todo[i]
        finite = True
        crossed = ALL_PLANES if every_plane else 0  # the planes some vertex is outside of
        for c in range(3):
            v = triangles[t, c]
            corner(points[v, 0], points[v, 1], points[v, 2], perspective, z_min, poly[0, c])
            for a in range(n_attrs):    # not a row assignment: see core.visibility.split.grow
                poly_a[0, c, a] = attrs[v, a]
            poly_id[0, c] = v
            crossed |= codes[v]
            for d in range(3):
                finite &= np.isfinite(points[v, d])
        if not finite:
            continue  # a NaN or infinite vertex: nothing sensible to draw
        n = 3
        cur = 0
        for k in _PLANE_ORDER:
            if crossed & (1 << k) and n > 0:
                n = clip_against_plane(k, poly[cur], poly_a[cur], poly_id[cur], n, poly[1 - cur],
                                       poly_a[1 - cur], poly_id[1 - cur], perspective, z_min)
                cur = 1 - cur
        if n < 3:
            continue  # clipped away, or only an edge or a point on the volume's boundary
        for j in range(n):
            if poly_id[cur, j] >= 0:
                index[j] = poly_id[cur, j]
            else:
                position(poly[cur, j], perspective, new_points[n_new_points])
                for a in range(n_attrs):
                    new_attrs[n_new_points, a] = poly_a[cur, j, a]
                index[j] = n_points + n_new_points
                n_new_points += 1
        for j in range(1, n - 1):  # fan the convex polygon from its first vertex
            new_triangles[n_new_triangles, 0] = index[0]
            new_triangles[n_new_triangles, 1] = index[j]
            new_triangles[n_new_triangles, 2] = index[j + 1]
            new_source[n_new_triangles] = t
            n_new_triangles += 1
    return (new_points[:n_new_points], new_attrs[:n_new_points],
            new_triangles[:n_new_triangles], new_source[:n_new_triangles])


@njit(cache=True)
def _sutherland_hodgman(points, triangles, attrs, codes, todo, perspective, z_min):
    return clip_and_fan(points, triangles, attrs, codes, todo, perspective, z_min, 3, False,
                        _corner, _clip_against_plane, _position)


@njit(cache=True)
def _liang_barsky(points, triangles, attrs, codes, todo, perspective, z_min):
    return clip_and_fan(points, triangles, attrs, codes, todo, perspective, z_min,
                        liang_barsky.WIDTH, False, liang_barsky.corner,
                        liang_barsky.clip_against_plane, _position)   # a row starts with it


@njit(cache=True)
def _homogeneous(points, triangles, attrs, codes, todo, perspective, z_min):
    # every plane: the outcodes are canonical, the clip is in clip space
    return clip_and_fan(points, triangles, attrs, codes, todo, perspective, z_min,
                        homogeneous.WIDTH, True, homogeneous.corner,
                        homogeneous.clip_against_plane, homogeneous.position)


# --------------------------------------------------------------------------------------------

_KERNELS = {"cohen-sutherland": _sutherland_hodgman, "liang-barsky": _liang_barsky,
            "homogeneous": _homogeneous}

_identity = np.arange(0, dtype=np.int64)


def _arange(n: int) -> np.ndarray:
    """0..n-1 as a read-only view of a cached array (no allocation per frame)."""
    global _identity
    if _identity.shape[0] < n:
        _identity = np.arange(max(n, 2 * _identity.shape[0]), dtype=np.int64)
        _identity.flags.writeable = False
    return _identity[:n]


def clip_triangles(points, triangles, attrs, projection: str,
                   z_min: float = 0.0, before_clip=None,
                   clipper: str = "cohen-sutherland", codes_found=None) -> ClippedTriangles:
    """Clip triangles to the canonical view volume (see the module docstring).

    ``attrs`` may be None (no attributes: (V, 0)). ``z_min`` is the front plane of the
    perspective volume (-1 < z_min < 0); it is ignored for the parallel one. When every
    vertex is inside, the inputs come back unchanged (no copy, and the triangles' indices are
    not even read: the rasterizer checks them), with ``source`` a read-only 0..T-1.
    Otherwise a vertex index out of range raises ValueError. ``before_clip(vertices)``, when
    given, is called with the vertex indices of the triangles about to be clipped, before
    their attributes are read (a shader that computes attributes lazily fills those rows).
    ``clipper`` (``RenderSettings.clipper``) picks the kernel for the triangles that are cut:
    "cohen-sutherland" this module's Sutherland–Hodgman, "liang-barsky"
    (:mod:`core.pipeline.clip_liang_barsky`) or "homogeneous"
    (:mod:`core.pipeline.clip_homogeneous`); the outcodes' accept and reject are shared.
    ``codes_found``: ``(codes (V,) uint8, their OR)`` of ``points`` when the caller found them
    in its own pass over the vertices (:func:`core.pipeline.vertex_kernels.view_points`).
    """
    perspective = _check_projection(projection)
    kernel = _KERNELS.get(clipper)
    if kernel is None:
        raise ValueError(f"clipper must be one of {', '.join(CLIPPERS)}, not {clipper!r}")
    points = np.asarray(points, dtype=np.float64)       # a strided view is fine: no copy
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    if attrs is None:
        attrs = np.empty((points.shape[0], 0))
    attrs = np.asarray(attrs, dtype=np.float64)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must be (V, 3), got {points.shape}")
    if triangles.ndim != 2 or triangles.shape[1] != 3:
        raise ValueError(f"triangles must be (T, 3), got {triangles.shape}")
    if attrs.ndim != 2 or attrs.shape[0] != points.shape[0]:
        raise ValueError(f"attrs must be ({points.shape[0]}, K), got {attrs.shape}")
    codes, any_outside = codes_found or _outcodes_and_any(points, perspective, z_min)
    if not any_outside:  # the whole mesh is inside: trivial accept for every triangle
        return ClippedTriangles(points, triangles, attrs, _arange(triangles.shape[0]))

    kept, todo, bad = _classify(read_only(triangles), codes)     # one kernel type (core.arrays)
    if bad:
        raise ValueError(f"{bad} triangles name a vertex outside 0..{points.shape[0] - 1}")
    if todo.size == 0:
        return ClippedTriangles(points, triangles[kept], attrs, kept)

    if before_clip is not None:
        before_clip(triangles[todo].reshape(-1))
    new_points, new_attrs, new_triangles, new_source = kernel(
        points, read_only(triangles), read_only(attrs), codes, todo, perspective, float(z_min))
    return ClippedTriangles(
        points=np.concatenate([points, new_points]),
        triangles=np.concatenate([triangles[kept], new_triangles]),
        attrs=np.concatenate([attrs, new_attrs]),
        source=np.concatenate([kept, new_source]),
    )
