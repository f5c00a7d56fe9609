"""Primary rays for a tile of the picture, and the front and back planes as a ray interval.

The rays are the redesign's (:func:`core.camera.rays.primary_rays`, through the view-plane
point of each device sample, from the PRP or along the DOP), for a tile of the picture so that
the window can trace it piece by piece.

:func:`clip_interval` turns the front and back planes (``n = F`` and ``n = B`` measured from the
VRP along the VPN) into the interval of the ray parameter a primary hit must lie in, so the
ray tracer sees exactly what the z-buffer's clipper leaves.
"""

from __future__ import annotations

import numpy as np

from core.camera.rays import primary_rays
from core.camera.view import View, vrc_basis


def tile_rays(view: View, projection: str, width: int, height: int, offsets,
              rows=None, cols=None, keep_aspect: bool = False
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`core.camera.rays.primary_rays` of the tile ``rows`` x ``cols`` (image rows
    and columns, ``(first, stop)``; default the whole frame)."""
    return primary_rays(view, projection, width, height, offsets, keep_aspect, rows, cols)


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
