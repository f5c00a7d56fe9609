"""Form factors by the hemicube (Cohen and Greenberg 1985), drawn by our own z-buffer.

A hemicube of half-side 1 stands on the shooting point, its top face one unit along the
normal. Each of its five faces is a perspective view from the point (the top face a 90° square
frustum, the four sides its upper halves), drawn through the FvDFH pipeline of
:mod:`core.pipeline`: normalize (N_per of a :class:`core.camera.view.View` whose window is the
face), clip, project, and the z-buffer of :func:`core.pipeline.raster.rasterize`. Its visibility
buffer is an *item buffer*: ``tri`` names the element nearest in each pixel.

Every pixel carries a *delta form factor*, precomputed per resolution (:func:`delta_factors`):

- top face, pixel centre (x, y, 1):   ΔF = ΔA / (π (x² + y² + 1)²)
- side face, pixel centre (x, 1, z):  ΔF = z ΔA / (π (x² + z² + 1)²)

with ΔA = (2/res)² the pixel's area. The form factor from the point to element j is the sum of
ΔF over the pixels where j is visible (:func:`form_factors`); the ΔF of a whole hemicube sum to
1 up to the discretisation (``1 − 1.6e-5`` at res 256).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from core.camera.view import View
from core.jit import njit
from core.pipeline import project
from core.pipeline.clip_polygon import clip_triangles
from core.pipeline.raster import VisibilityBuffer, rasterize
from core.pipeline.vertex_kernels import transform_affine, transform_projective

NEAR = 1e-6             # the front plane, a fraction of the scene's size from the point


@lru_cache(maxsize=8)
def delta_factors(res: int) -> tuple[np.ndarray, np.ndarray]:
    """``(top (res, res), side (res // 2, res))`` delta form factors, image order (row 0 at the
    top of the face: y = +1 on the top face, z = 1 on a side face)."""
    if res < 2 or res % 2:
        raise ValueError(f"hemicube resolution must be an even number >= 2, not {res}")
    c = (np.arange(res) + 0.5) / res * 2.0 - 1.0                 # pixel centres, -1..1
    area = (2.0 / res) ** 2
    x, y = np.meshgrid(c, c[::-1])
    top = area / (np.pi * (x * x + y * y + 1.0) ** 2)
    z = c[::-1][: res // 2]                                      # 1 at row 0, down to 0
    x, z = np.meshgrid(c, z)
    side = z * area / (np.pi * (x * x + z * z + 1.0) ** 2)
    for a in (top, side):
        a.flags.writeable = False
    return top, side


def _cross(a, b) -> np.ndarray:
    """a x b of two 3-vectors (np.cross costs 1 ms of set-up per call here)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def _basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``u, v`` with ``(u, v, normal)`` right-handed."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) < 0.6 else np.array([0.0, 1.0, 0.0])
    u = _cross(helper, normal)
    u /= np.linalg.norm(u)
    return u, _cross(normal, u)


def faces(point, normal) -> list[tuple[np.ndarray, np.ndarray, bool]]:
    """The five faces as ``(look direction, up, is_top)``: the top face looks along the normal;
    each side face looks along ±u, ±v with the normal as its up (its upper half only)."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    u, v = _basis(n)
    return [(n, v, True)] + [(d, n, False) for d in (u, -u, v, -v)]


def face_transform(point, look, up, top: bool, scale: float) -> tuple[np.ndarray, float]:
    """``(N_per, z_min)`` of one face: FvDFH's N_per = S_per · SH_par · T(−PRP) · R · T(−VRP)
    for the view whose plane is the face (VRP one unit along ``look``, VPN = −look, window
    [−1, 1] x [−1 or 0, 1], PRP one unit back, at the point), multiplied out by hand: the
    hemicube's views are valid by construction and this is called five times a row.
    :func:`view_of_face` is the same view as a :class:`View` (the tests compare the two)."""
    point, look, up = (np.asarray(a, dtype=np.float64) for a in (point, look, up))
    n_axis = -look
    u = _cross(up, n_axis)
    u /= np.linalg.norm(u)
    v = _cross(n_axis, u)
    m = np.eye(4)
    m[:3, :3] = np.stack([u, v, n_axis])             # R, after T(−point): T(−PRP)·R·T(−VRP)
    m[:3, 3] = -m[:3, :3] @ point
    v_min = -1.0 if top else 0.0
    shear = np.eye(4)
    shear[1, 2] = (v_min + 1.0) / 2.0                # shy = −DOP_y / DOP_z, DOP = (0, ·, −1)
    back = -4.0 * scale - 1.0
    near = NEAR * scale
    s_per = np.diag([1.0 / (1.0 - back), 2.0 / ((1.0 - v_min) * (1.0 - back)),
                     1.0 / (1.0 - back), 1.0])
    return s_per @ shear @ m, -near / (1.0 - back)


def view_of_face(point, look, up, top: bool, scale: float) -> View:
    point = np.asarray(point, dtype=np.float64)
    return View(vrp=tuple(point + look), vpn=tuple(-np.asarray(look)), vup=tuple(up),
                window=(-1.0, 1.0, -1.0 if top else 0.0, 1.0), prp=(0.0, 0.0, 1.0),
                front=1.0 - NEAR * scale, back=-4.0 * scale - 1.0)


_BUFFERS: dict = {}


def _buffer(width: int, height: int):
    """A visibility buffer per face size, reused from row to row (one solve at a time)."""
    if (width, height) not in _BUFFERS:
        _BUFFERS[(width, height)] = VisibilityBuffer.allocate(width, height)
    return _BUFFERS[(width, height)]


def item_buffer(positions, triangles, point, look, up, top: bool, res: int, scale: float):
    """The element index ``(H, res)`` int64 seen in each pixel of one hemicube face (-1: none),
    drawn by our z-buffer. ``positions`` (V, 3), ``triangles`` (T, 3): the elements."""
    height = res if top else res // 2
    n, z_min = face_transform(point, look, up, top, scale)
    points = transform_affine(n, positions)
    clipped = clip_triangles(points, triangles, None, "perspective", z_min)
    device, inv_w = transform_projective(
        project.triangle_matrix("perspective", z_min, (0.0, float(res), 0.0, float(height))),
        clipped.points)
    vis = rasterize(device, inv_w, clipped.triangles, res, height, parallel=False,
                    out=_buffer(res, height))
    source = np.asarray(clipped.source, dtype=np.int64)
    items = np.full(vis.tri.shape, -1, np.int64)
    seen = vis.tri >= 0
    items[seen] = source[vis.tri[seen]]
    return items


def form_factors(positions, triangles, point, normal, res: int, scale: float,
                 count: int | None = None) -> np.ndarray:
    """F from the differential area at ``point`` (facing ``normal``) to each triangle,
    ``(count,)`` (default: one per triangle), by the hemicube of resolution ``res``."""
    top_df, side_df = delta_factors(res)
    count = len(triangles) if count is None else count
    out = np.zeros(count)
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    frame = np.stack([*_basis(n), n])                    # the patch's u, v, n (faces())
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    in_faces = np.empty((5, len(triangles)), np.bool_)
    _face_frusta(positions, triangles, np.asarray(point, dtype=np.float64), frame,
                 1e-9 * scale, in_faces)
    for (look, up, top), in_face in zip(faces(point, normal), in_faces):
        chosen = np.flatnonzero(in_face)
        if not len(chosen):
            continue
        # only the face's own triangles, each with its three corners: the clipper would
        # reject the others whole, and the rest reach the rasterizer in the same order
        corners = np.ascontiguousarray(positions[triangles[chosen]].reshape(-1, 3))
        items = item_buffer(corners, _corner_triangles(len(chosen)), point, look, up, top,
                            res, scale)
        seen = items >= 0
        out += np.bincount(chosen[items[seen]], weights=(top_df if top else side_df)[seen],
                           minlength=count)[:count]
    return out


@njit(cache=True, nogil=True)
def _face_frusta(positions, triangles, point, frame, slack, out):
    """``out[f, k]``: whether triangle k may be in the frustum of face f of :func:`faces`
    (top, +u, −u, +v, −v): not when its three corners, in the patch's frame (a, b, c along
    u, v, n), are all beyond one of the frustum's planes by more than ``slack`` (so that
    rounding never drops one the clipper would keep; the top face |a|, |b| <= c, the side
    face +u |b| <= a and 0 <= c <= a). A triangle wholly at or below the tangent plane
    (c <= 0) is behind every face."""
    nearest = np.empty(17)                     # per plane: the corner least beyond it
    for k in range(triangles.shape[0]):
        nearest[:] = np.inf
        for corner in range(3):
            q = triangles[k, corner]
            dx = positions[q, 0] - point[0]
            dy = positions[q, 1] - point[1]
            dz = positions[q, 2] - point[2]
            a = frame[0, 0] * dx + frame[0, 1] * dy + frame[0, 2] * dz
            b = frame[1, 0] * dx + frame[1, 1] * dy + frame[1, 2] * dz
            c = frame[2, 0] * dx + frame[2, 1] * dy + frame[2, 2] * dz
            beyond = (-c, a - c, -a - c, b - c, -b - c,
                      c - a, b - a, -b - a, c + a, b + a, -b + a,
                      c - b, a - b, -a - b, c + b, a + b, -a + b)
            for plane in range(17):
                nearest[plane] = min(nearest[plane], beyond[plane])
        below = nearest[0] >= 0.0              # wholly at or below the tangent plane
        out[0, k] = not (below or max(nearest[1], nearest[2], nearest[3], nearest[4]) > slack)
        for f in range(4):
            first = 5 + 3 * f
            out[1 + f, k] = not (below or max(nearest[first], nearest[first + 1],
                                              nearest[first + 2]) > slack)


def _corner_triangles(count: int) -> np.ndarray:
    """``(count, 3)``: triangle k made of corners 3k, 3k + 1, 3k + 2."""
    return np.arange(3 * count, dtype=np.int64).reshape(count, 3)
