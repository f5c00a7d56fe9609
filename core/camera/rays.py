"""Rays from an FvDFH view: the one place every ray-based renderer gets its primary rays.

The sample at device point (x, y) (x right, y **up**, pixel (i, j) spanning [i, i+1] x [j, j+1])
looks through the view-plane point ``VRP + u·u_vrc + v·v_vrc`` with
``u = u_min + (x − x0)/(x1 − x0)·(u_max − u_min)`` (and v alike) over the viewport
``(x0, x1, y0, y1)`` of :func:`core.camera.film.viewport` — the same mapping the z-buffer's
M_vv3dv makes, run backwards. Perspective rays start at the PRP (in world coordinates) and are
unit vectors; parallel rays start on the view plane and run along the unit DOP. A sample
outside the viewport sees nothing. What a ray may hit is limited by the front and back planes,
``F ≤ n ≤ B`` measured along VPN from the VRP (:func:`in_depth_range`).

- :func:`pack_camera` → a float array that numba kernels take (``CAMERA_*`` name its slots);
- :func:`camera_ray` (numba) → one ray for one device point;
- :func:`primary_rays` (numpy entry) → all rays for a frame's pixel samples;
- :func:`clip_interval` → the front and back planes as each ray's interval of t;
- :func:`camera_rays` → both: what every ray-based renderer traces (the Whitted tracer, the
  path tracer, radiosity's ray-cast display).
"""

from __future__ import annotations

import numpy as np

from core.camera.view import View, check, eye_from_view, vrc_basis
from core.jit import njit, prange
from core.camera.film import viewport
from core.vectors import unit3

# Slots of a packed camera.
CAMERA_VRP, CAMERA_BASIS, CAMERA_WINDOW, CAMERA_VIEWPORT = 0, 3, 12, 16
CAMERA_PERSPECTIVE, CAMERA_ORIGIN, CAMERA_DOP, CAMERA_FRONT, CAMERA_BACK = 20, 21, 24, 27, 28
CAMERA_SIZE = 29


def pack_camera(view: View, projection: str, width: int, height: int,
                keep_aspect: bool = False) -> np.ndarray:
    """The view as numbers: VRP, the VRC basis (u, v, n rows), window, viewport, perspective
    flag, ray origin (PRP in world coordinates), unit DOP towards the scene, F and B.
    Raises :class:`core.camera.view.ViewError` for an invalid view."""
    check(view, projection)
    u, v, n = vrc_basis(view)
    eye = eye_from_view(view, projection)
    cam = np.zeros(CAMERA_SIZE)
    cam[CAMERA_VRP:CAMERA_VRP + 3] = view.vrp
    cam[CAMERA_BASIS:CAMERA_BASIS + 9] = np.array([u, v, n]).reshape(-1)
    cam[CAMERA_WINDOW:CAMERA_WINDOW + 4] = view.window
    cam[CAMERA_VIEWPORT:CAMERA_VIEWPORT + 4] = viewport(view.window, width, height, keep_aspect)
    if projection == "perspective":
        cam[CAMERA_PERSPECTIVE] = 1.0
        cam[CAMERA_ORIGIN:CAMERA_ORIGIN + 3] = eye.point
    else:
        cam[CAMERA_DOP:CAMERA_DOP + 3] = -np.asarray(eye.direction)
    cam[CAMERA_FRONT], cam[CAMERA_BACK] = view.front, view.back
    return cam


@njit(cache=True)
def camera_ray(cam, x, y):
    """``(inside, ox, oy, oz, dx, dy, dz)``: the ray through device point (x, y); ``inside``
    is False (and the ray zero) outside the viewport."""
    x0, x1 = cam[CAMERA_VIEWPORT], cam[CAMERA_VIEWPORT + 1]
    y0, y1 = cam[CAMERA_VIEWPORT + 2], cam[CAMERA_VIEWPORT + 3]
    if not (x0 <= x <= x1 and y0 <= y <= y1):
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    u_min, u_max = cam[CAMERA_WINDOW], cam[CAMERA_WINDOW + 1]
    v_min, v_max = cam[CAMERA_WINDOW + 2], cam[CAMERA_WINDOW + 3]
    v = v_min + (y - y0) / (y1 - y0) * (v_max - v_min)
    u = u_min + (x - x0) / (x1 - x0) * (u_max - u_min)
    b = CAMERA_BASIS
    tx = cam[0] + u * cam[b] + v * cam[b + 3]
    ty = cam[1] + u * cam[b + 1] + v * cam[b + 4]
    tz = cam[2] + u * cam[b + 2] + v * cam[b + 5]
    if cam[CAMERA_PERSPECTIVE] != 0.0:       # from the PRP through the view-plane point
        ox, oy, oz = cam[CAMERA_ORIGIN], cam[CAMERA_ORIGIN + 1], cam[CAMERA_ORIGIN + 2]
        dx, dy, dz, _ = unit3(tx - ox, ty - oy, tz - oz)
        return True, ox, oy, oz, dx, dy, dz
    return True, tx, ty, tz, cam[CAMERA_DOP], cam[CAMERA_DOP + 1], cam[CAMERA_DOP + 2]


@njit(cache=True)
def in_depth_range(cam, px, py, pz):
    """Whether the point lies between the front and back planes (F ≥ n ≥ B along VPN)."""
    b = CAMERA_BASIS + 6
    n = (px - cam[0]) * cam[b] + (py - cam[1]) * cam[b + 1] + (pz - cam[2]) * cam[b + 2]
    return cam[CAMERA_BACK] <= n <= cam[CAMERA_FRONT]


@njit(cache=True)
def clipped_ray(cam, x, y):
    """``(ox, oy, oz, dx, dy, dz, t_min, t_max)``: :func:`camera_ray` at device point (x, y)
    with its part between the front and back planes, as :func:`camera_rays` gives it (a
    parallel ray moved to start there; ``t_min = inf`` outside the viewport). For a kernel
    that makes its rays itself: the path tracer, one pass after another."""
    ok, ox, oy, oz, dx, dy, dz = camera_ray(cam, x, y)
    b = CAMERA_BASIS + 6                         # n, the VPN's unit vector
    n0 = (ox - cam[0]) * cam[b] + (oy - cam[1]) * cam[b + 1] + (oz - cam[2]) * cam[b + 2]
    dn = dx * cam[b] + dy * cam[b + 1] + dz * cam[b + 2]
    front, back = cam[CAMERA_FRONT], cam[CAMERA_BACK]
    perspective = cam[CAMERA_PERSPECTIVE] != 0.0
    if dn == 0.0:              # parallel to the planes: all of the ray between them, or none
        between = back <= n0 <= front
        t_min, t_max = (0.0, np.inf) if between else (np.inf, -np.inf)
    else:
        t_front, t_back = (front - n0) / dn, (back - n0) / dn
        t_min, t_max = min(t_front, t_back), max(t_front, t_back)
        if perspective:
            t_min = max(t_min, 0.0)
    if not perspective:
        start = t_min if ok and np.isfinite(t_min) else 0.0
        ox, oy, oz = ox + start * dx, oy + start * dy, oz + start * dz
        t_min, t_max = t_min - start, t_max - start
    if not ok:
        t_min = np.inf
    return ox, oy, oz, dx, dy, dz, t_min, t_max


@njit(cache=True, inline="always")
def pixel_point(width, height, pixel, offset_x, offset_y):
    """Device point (x, y) of the sample at film offset (x right, y down, in the pixel) of
    pixel number ``pixel`` (rows from the top, then columns), as :func:`primary_rays` makes it."""
    row = pixel // width
    col = pixel - row * width
    j = height - 1 - row                     # device row, counted from the bottom
    return col + offset_x, j + 1.0 - offset_y


@njit(cache=True, parallel=True, nogil=True)
def _rays(cam, height, row0, row1, col0, col1, offsets, origins, directions, inside):
    rows, cols = row1 - row0, col1 - col0
    for r in prange(rows):
        j = height - 1 - (row0 + r)              # device row, counted from the bottom
        for c in range(cols):
            for s in range(offsets.shape[0]):
                k = (s * rows + r) * cols + c
                ok, ox, oy, oz, dx, dy, dz = camera_ray(cam, col0 + c + offsets[s, 0],
                                                        j + 1.0 - offsets[s, 1])
                inside[k] = ok
                origins[k, 0], origins[k, 1], origins[k, 2] = ox, oy, oz
                directions[k, 0], directions[k, 1], directions[k, 2] = dx, dy, dz


def primary_rays(view: View, projection: str, width: int, height: int,
                 offsets=((0.5, 0.5),), keep_aspect: bool = False, rows=None, cols=None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(origins (N, 3), directions (N, 3), inside (N,))`` for every pixel sample of the
    image rows ``rows = (first, stop)`` and columns ``cols`` (default: the whole frame; a
    tile lets a renderer trace the picture piece by piece), ordered sample, then image row
    (top first), then column. ``offsets`` ``(S, 2)`` are the film's (x right, y down, in the
    pixel); directions are unit vectors; ``inside`` is false outside the viewport."""
    offsets = np.ascontiguousarray(offsets, dtype=np.float64).reshape(-1, 2)
    row0, row1 = rows or (0, height)
    col0, col1 = cols or (0, width)
    count = len(offsets) * (row1 - row0) * (col1 - col0)
    origins, directions = np.empty((count, 3)), np.empty((count, 3))
    inside = np.empty(count, dtype=np.bool_)
    _rays(pack_camera(view, projection, width, height, keep_aspect), int(height), int(row0),
          int(row1), int(col0), int(col1), offsets, origins, directions, inside)
    return origins, directions, inside


def clip_interval(view: View, origins: np.ndarray, directions: np.ndarray,
                  from_origin: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(t_min, t_max)`` per ray: the part of the ray between the back and front planes.

    ``from_origin``: only ``t >= 0`` (perspective: nothing behind the PRP is seen). A parallel
    projection sees the whole line through the view-plane point (``from_origin=False``):
    objects between the view plane and F are in front of it."""
    _, _, n_axis = vrc_basis(view)
    vrp = np.asarray(view.vrp, dtype=np.float64)
    # n of the origin and dn/dt, a column at a time: ``@`` here is BLAS's matrix-vector
    # product, whose threads then spin for milliseconds beside the tracer's on the same cores
    # (half of a ray-traced frame's samples on two cores)
    n0 = ((origins[:, 0] - vrp[0]) * n_axis[0] + (origins[:, 1] - vrp[1]) * n_axis[1]
          + (origins[:, 2] - vrp[2]) * n_axis[2])
    dn = directions[:, 0] * n_axis[0] + directions[:, 1] * n_axis[1] + directions[:, 2] * n_axis[2]
    with np.errstate(divide="ignore", invalid="ignore"):
        t_front = (view.front - n0) / dn
        t_back = (view.back - n0) / dn
    t_min = np.minimum(t_front, t_back)
    if from_origin:
        t_min = np.maximum(t_min, 0.0)
    t_max = np.maximum(t_front, t_back)
    # A ray parallel to the planes: all of it if it runs between them, none of it otherwise.
    parallel = dn == 0.0
    between = (view.back <= n0) & (n0 <= view.front)
    t_min[parallel] = np.where(between[parallel], 0.0, np.inf)
    t_max[parallel] = np.where(between[parallel], np.inf, -np.inf)
    return t_min, t_max


def camera_rays(view: View, projection: str, width: int, height: int, offsets=((0.5, 0.5),),
                keep_aspect: bool = False, rows=None, cols=None):
    """``(origins, directions, t_min, t_max)``: :func:`primary_rays` with the part of each
    that lies between the front and back planes. A parallel ray starts on the front plane,
    so that t >= 0 along every ray; a sample outside the viewport has ``t_min = inf``."""
    origins, directions, inside = primary_rays(view, projection, width, height, offsets,
                                               keep_aspect, rows, cols)
    perspective = projection == "perspective"
    t_min, t_max = clip_interval(view, origins, directions, from_origin=perspective)
    if not perspective:
        start = np.where(inside & np.isfinite(t_min), t_min, 0.0)
        origins = origins + start[:, None] * directions
        t_min, t_max = t_min - start, t_max - start
    t_min[~inside] = np.inf
    return origins, directions, t_min, t_max
