"""Primary rays for a tile of the picture, and the front and back planes as a ray interval.

The rays are the redesign's (:mod:`core.camera.rays`: :func:`~core.camera.rays.camera_ray`
through the view-plane point of each device sample, from the PRP or along the DOP), restricted
to a tile so that the window can trace the picture piece by piece; with the whole image as the
tile they are exactly :func:`core.camera.rays.primary_rays` (a test holds them together).

:func:`clip_interval` turns the front and back planes (``n = F`` and ``n = B`` measured from the
VRP along the VPN) into the interval of the ray parameter a primary hit must lie in, so the
ray tracer sees exactly what the z-buffer's clipper leaves.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from core.camera.rays import camera_ray, pack_camera
from core.camera.view import View, vrc_basis


@njit(cache=True, parallel=True)
def _tile_rays(cam, height, row0, row1, col0, col1, offsets, origins, directions, inside):
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


def tile_rays(view: View, projection: str, width: int, height: int, offsets,
              rows=None, cols=None, keep_aspect: bool = False
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(origins (N, 3), unit directions (N, 3), inside (N,) bool)`` for ``offsets (S, 2)``
    over image rows ``rows = (first, stop)`` and columns ``cols`` (default: all), ordered
    sample, then row (top first), then column. ``inside`` is false outside the viewport
    (``keep_aspect``: the window letterboxed; else stretched over the framebuffer, the course's
    mapping — as :func:`core.camera.rays.pack_camera`)."""
    offsets = np.ascontiguousarray(offsets, dtype=np.float64).reshape(-1, 2)
    row0, row1 = rows or (0, height)
    col0, col1 = cols or (0, width)
    count = len(offsets) * (row1 - row0) * (col1 - col0)
    origins, directions = np.empty((count, 3)), np.empty((count, 3))
    inside = np.empty(count, dtype=np.bool_)
    _tile_rays(pack_camera(view, projection, width, height, keep_aspect), int(height),
               int(row0), int(row1), int(col0), int(col1), offsets, origins, directions, inside)
    return origins, directions, inside


def clip_interval(view: View, origins: np.ndarray, directions: np.ndarray,
                  from_origin: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """``(t_min, t_max)`` per ray: the part of the ray between the back and front planes.

    ``from_origin``: only ``t >= 0`` (perspective: nothing behind the PRP is seen). A parallel
    projection sees the whole line through the view-plane point (``from_origin=False``):
    objects between the view plane and F are in front of it."""
    _, _, n_axis = vrc_basis(view)
    n0 = (origins - np.asarray(view.vrp, dtype=np.float64)) @ n_axis    # n of the origin
    dn = directions @ n_axis                                           # dn/dt
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
