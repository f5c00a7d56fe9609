"""The world point under a pixel of the frame shown, read from that frame's own depth buffer.

A frame of the z-buffer family keeps the canonical depth of every pixel (``Frame.depth``:
device z, larger nearer, ``-inf`` where nothing was drawn). :func:`depth_pick`, called on the
render worker's thread as the frame is finished, keeps a copy of it (the frame's own array is
the render context's buffer, which the next frame overwrites) with the inverse of the one
matrix that took world points to the device for that frame: ``M_vv3dv · M · N`` (perspective)
or ``M_vv3dv · N`` (parallel), as ``core.renderers.zbuffer.draw`` composes it. :func:`point_at`
then turns pixel (column, row) into the world point drawn there with one 4 x 4 product: the
device point ``(column + 0.5, H - row - 0.5, z, 1)`` (pixel centres, device rows counted from
the bottom) through the inverse, divided by its W. Nothing is rendered and nothing waits: the
window asks on its own thread at the press of a drag (the orbit's pivot).

No GL and no window library here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PICK_KEY = "pick"          # the frame's stats entry holding its DepthPick


@dataclass(frozen=True)
class DepthPick:
    """A frame's depth buffer (a copy) and the device-to-world matrix of its camera."""

    depth: np.ndarray          # (H, W) canonical depth, larger nearer, -inf empty
    to_world: np.ndarray       # (4, 4): device (x, y, z, 1) -> world, homogeneous


def depth_pick(frame, view, settings) -> DepthPick | None:
    """What :func:`point_at` needs of ``frame`` drawn through ``view`` with ``settings``;
    None when the frame keeps no depth buffer of its own size (the tracers, a supersampled
    frame) or the camera's matrix cannot be inverted."""
    from core.camera.film import sample_viewport, viewport
    from core.camera.view import normalizing_transform
    from core.pipeline.project import triangle_matrix
    depth = getattr(frame, "depth", None)
    if view is None or not isinstance(depth, np.ndarray) \
            or depth.shape != frame.color.shape[:2]:
        return None
    height, width = depth.shape
    try:
        n, z_min = normalizing_transform(view, settings.projection)
        vp = sample_viewport(viewport(view.window, width, height, settings.keep_aspect),
                             settings.pixel_offset)
        to_world = np.linalg.inv(triangle_matrix(settings.projection, z_min, vp) @ n)
    except (ValueError, np.linalg.LinAlgError):
        return None
    return DepthPick(depth.copy(), to_world)


def point_at(pick: DepthPick | None, column: int, row: int) -> np.ndarray | None:
    """The world point drawn at frame pixel (column, row from the top), or None where the
    pixel is outside the frame or shows the background."""
    if pick is None:
        return None
    height, width = pick.depth.shape
    if not (0 <= column < width and 0 <= row < height):
        return None
    z = float(pick.depth[row, column])
    if not math.isfinite(z):
        return None
    world = pick.to_world @ np.array([column + 0.5, height - row - 0.5, z, 1.0])
    if not (np.isfinite(world).all() and world[3] != 0.0):
        return None
    return world[:3] / world[3]
