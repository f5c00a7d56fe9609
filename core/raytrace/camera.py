"""Primary rays from the FvDFH view (FvDFH 6.5; the notes' "a CoP and a window selected"),
and the front and back clipping planes as a ray interval.

The sample at device point ``(x, y)`` (y up, pixel centres at half-integers) looks through
the view-plane point ``VRP + u·u_vrc + v·v_vrc``, with ``u = u_min + (x − x0)/(x1 − x0) ·
(u_max − u_min)`` (and ``v`` alike) over the letterboxed viewport ``(x0, x1, y0, y1)`` of
:func:`core.pipeline.project.viewport` — the same mapping the z-buffer's ``M_vv3dv`` makes.
Perspective rays start at the PRP; parallel rays run along the DOP through the view-plane
point. A sample outside the viewport sees nothing (``t_min = +inf``).

:func:`clip_interval` turns the front and back planes (``n = F`` and ``n = B`` measured from the
VRP along the VPN) into the interval of the ray parameter a primary hit must lie in, so the
ray tracer sees exactly what the z-buffer's clipper leaves.

When the redesign's ``core.camera.rays.primary_rays`` is on main, :func:`primary_rays` defers
to it (same contract: ``(H·W·S, 3)`` origins and unit directions, sample-major then
row-major, offsets in ``[0, 1)²`` from the pixel's top-left corner).
"""

from __future__ import annotations

import numpy as np

from core.camera.view import View, check, vrc_basis
from core.pipeline.project import viewport
from core.shading.illumination import eye_from_view


def own_primary_rays(view: View, projection: str, width: int, height: int,
                     offsets, rows=None, cols=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(origins (N, 3), unit directions (N, 3), inside (N,) bool)`` for ``offsets (S, 2)``.

    ``inside`` is false for samples outside the letterboxed viewport. ``rows`` and ``cols``
    (``(first, stop)`` image rows and columns, row 0 at the top) restrict the rays to a tile.
    """
    check(view, projection)
    u_axis, v_axis, _ = vrc_basis(view)
    offsets = np.asarray(offsets, dtype=np.float64).reshape(-1, 2)
    x0, x1, y0, y1 = viewport(view.window, width, height)
    u_min, u_max, v_min, v_max = view.window
    col = np.arange(*(cols or (0, width)), dtype=np.float64)
    row = np.arange(*(rows or (0, height)), dtype=np.float64)
    # Device x grows to the right; device y grows upward while image rows grow downward.
    x = col[None, None, :] + offsets[:, 0][:, None, None]                       # (S, 1, W)
    y = (height - 1 - row)[None, :, None] + (1.0 - offsets[:, 1])[:, None, None]  # (S, H, 1)
    x, y = np.broadcast_arrays(x, y)
    inside = ((x0 <= x) & (x <= x1) & (y0 <= y) & (y <= y1)).reshape(-1)
    u = u_min + (x - x0) / (x1 - x0) * (u_max - u_min)
    v = v_min + (y - y0) / (y1 - y0) * (v_max - v_min)
    target = (np.asarray(view.vrp, dtype=np.float64)
              + u.reshape(-1, 1) * u_axis + v.reshape(-1, 1) * v_axis)
    eye = eye_from_view(view, projection)
    if projection == "perspective":
        origins = np.broadcast_to(eye.point, target.shape).copy()
        directions = target - eye.point
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    else:
        origins = target
        directions = np.broadcast_to(-eye.direction, target.shape).copy()
    return origins, directions, inside


def primary_rays(view: View, projection: str, width: int, height: int, offsets):
    """The redesign's primary rays when on main, else :func:`own_primary_rays`; both give
    ``(origins, directions, inside)``."""
    try:
        from core.camera.rays import primary_rays as lead_rays    # the redesign (issue 9)
    except ImportError:
        return own_primary_rays(view, projection, width, height, offsets)
    origins, directions = lead_rays(view, projection, width, height, offsets)
    _, _, inside = own_primary_rays(view, projection, width, height, offsets)
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
