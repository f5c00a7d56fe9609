"""The particle stage: after the opaque z-buffer, particles blended back to front.

Takes a rendered frame (its colour, and its z-buffer's depth where it has one), the particles'
:class:`Sprites` and the view, and draws each particle as a point, a camera-facing round
sprite, or a streak (the segment it covered over the last ``streak`` seconds) with its
transparency. The steps, in pipeline order:

1. ``N_per`` / ``N_par`` carry the particle centres into the canonical volume; those outside
   the front and back planes (or behind the eye) are dropped.
2. The perspective-to-parallel matrix, ``M_vv3dv`` and the divide by W
   (``project.triangle_matrix``, as for triangles) give device x, y and the z-buffer's depth z.
   A sprite's radius in pixels is the distance between the projections of its centre and of
   the centre moved by its size along the VRC's u axis.
3. Particles are sorted back to front (ascending z: larger z is nearer), because "over"
   blending is not commutative.
4. Each covered pixel is depth-tested against the opaque depth (drawn only where the particle
   is nearer; the depth is not written, so particles never hide each other) and blended:
   ``C = a · C_particle + (1 - a) · C``, with ``a`` the particle's opacity times a soft round
   falloff ``1 - (d / r)^2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from core.camera.view import normalizing_transform, vrc_basis
from core.pipeline import project

POINT, SPRITE, STREAK = 0, 1, 2
DRAW_CODES = {"point": POINT, "sprite": SPRITE, "streak": STREAK}


@dataclass
class Sprites:
    """What the particle stage draws: per particle ``position`` (N, 3) world, ``tail`` (N, 3)
    (a streak's far end; equal to position otherwise), ``radius`` (N,) world units,
    ``rgb`` (N, 3) in [0, 1], ``alpha`` (N,) opacity, ``mode`` (N,) POINT/SPRITE/STREAK."""

    position: np.ndarray
    tail: np.ndarray
    radius: np.ndarray
    rgb: np.ndarray
    alpha: np.ndarray
    mode: np.ndarray

    def __len__(self) -> int:
        return len(self.alpha)


def _device(points, n, projection, z_min, vp):
    """World points → device (x, y, z) and a mask of those inside the front/back planes."""
    h = np.concatenate([points, np.ones((len(points), 1))], axis=1)
    canonical = h @ n.T
    canonical = canonical[:, :3] / canonical[:, 3:4]
    z = canonical[:, 2]
    inside = (z >= -1.0) & (z <= (z_min if projection == "perspective" else 0.0))
    dev = np.concatenate([canonical, np.ones((len(points), 1))], axis=1) @ \
        project.triangle_matrix(projection, z_min, vp).T
    w = dev[:, 3]
    inside &= w > 0.0
    safe = np.where(w > 0.0, w, 1.0)
    return dev[:, :3] / safe[:, None], inside


def project_sprites(sprites: Sprites, view, projection: str, width: int, height: int):
    """Device centres, tails and pixel radii of the sprites in front of the camera, back to
    front: ``(order-sorted arrays dict)``."""
    n, z_min = normalizing_transform(view, projection)
    vp = project.viewport(view.window, width, height)
    head, inside = _device(sprites.position, n, projection, z_min, vp)
    u = vrc_basis(view)[0]
    edge, _ = _device(sprites.position + sprites.radius[:, None] * u, n, projection, z_min, vp)
    radius = np.hypot(edge[:, 0] - head[:, 0], edge[:, 1] - head[:, 1])
    tail, tail_inside = _device(sprites.tail, n, projection, z_min, vp)
    mode = sprites.mode.copy()
    mode[(mode == STREAK) & ~tail_inside] = SPRITE        # a tail behind the eye: no streak
    keep = np.flatnonzero(inside)
    order = keep[np.argsort(head[keep, 2], kind="stable")]  # far (small z) first
    return {"x": head[order, 0], "y": head[order, 1], "z": head[order, 2],
            "tx": tail[order, 0], "ty": tail[order, 1], "tz": tail[order, 2],
            "r": np.minimum(radius[order], float(max(width, height))),
            "rgb": sprites.rgb[order], "alpha": sprites.alpha[order], "mode": mode[order]}


@njit(cache=True)
def _blend(image, depth, row, col, z, rgb, a):
    """One fragment: depth-tested (never written), then over-blended."""
    if z > depth[row, col] and a > 0.0:
        for c in range(3):
            image[row, col, c] = a * rgb[c] + (1.0 - a) * image[row, col, c]


@njit(cache=True)
def _splat(image, depth, x, y, z, tx, ty, tz, r, rgb, alpha, mode):
    """Draw every sprite in the given (back-to-front) order."""
    height, width = depth.shape
    for k in range(x.shape[0]):
        if mode[k] == 0:                                   # a point: the pixel under it
            i, j = int(np.floor(x[k])), int(np.floor(y[k]))
            if 0 <= i < width and 0 <= j < height:
                _blend(image, depth, height - 1 - j, i, z[k], rgb[k], alpha[k])
            continue
        radius = max(r[k], 0.75)                           # at least the pixel under it
        ax, ay = tx[k], ty[k]
        if mode[k] == 1:
            ax, ay = x[k], y[k]
        dx, dy = x[k] - ax, y[k] - ay
        length2 = dx * dx + dy * dy
        i0 = max(int(np.floor(min(x[k], ax) - radius)), 0)
        i1 = min(int(np.ceil(max(x[k], ax) + radius)), width - 1)
        j0 = max(int(np.floor(min(y[k], ay) - radius)), 0)
        j1 = min(int(np.ceil(max(y[k], ay) + radius)), height - 1)
        for j in range(j0, j1 + 1):
            py = j + 0.5
            for i in range(i0, i1 + 1):
                px = i + 0.5
                # nearest point of the segment tail → head (a sprite: the centre itself)
                s = 1.0
                if length2 > 0.0:
                    s = ((px - ax) * dx + (py - ay) * dy) / length2
                    s = min(1.0, max(0.0, s))
                qx, qy = ax + s * dx, ay + s * dy
                d2 = ((px - qx) * (px - qx) + (py - qy) * (py - qy)) / (radius * radius)
                if d2 >= 1.0:
                    continue
                zq = tz[k] + s * (z[k] - tz[k]) if mode[k] == 2 else z[k]
                fade = s if mode[k] == 2 else 1.0          # a streak thins out to its tail
                _blend(image, depth, height - 1 - j, i, zq, rgb[k], alpha[k] * (1.0 - d2) * fade)


@njit(cache=True)
def _to_unit(color):
    """uint8 (H, W, 3) → float64 in [0, 1] (one pass; numpy's astype-then-divide takes two)."""
    height, width = color.shape[:2]
    out = np.empty((height, width, 3))
    for j in range(height):
        for i in range(width):
            for c in range(3):
                out[j, i, c] = color[j, i, c] / 255.0
    return out


@njit(cache=True)
def _to_bytes(image, color):
    """float [0, 1] → uint8, rounded half up (unblended pixels come back exactly as they were)."""
    height, width = color.shape[:2]
    for j in range(height):
        for i in range(width):
            for c in range(3):
                v = min(max(image[j, i, c], 0.0), 1.0)
                color[j, i, c] = np.uint8(np.floor(v * 255.0 + 0.5))


def draw_particles(frame, sprites: Sprites, view, settings) -> int:
    """Blend ``sprites`` into ``frame.color`` over its opaque picture; returns how many were
    in front of the camera. ``frame.depth`` (the z-buffer's, larger = nearer) hides particles
    behind opaque surfaces; a frame without depth (wireframe) hides none."""
    color = frame.color
    height, width = color.shape[:2]
    if len(sprites) == 0 or width == 0 or height == 0:
        return 0
    projection = getattr(settings, "projection", None) or "perspective"
    p = project_sprites(sprites, view, projection, width, height)
    depth = getattr(frame, "depth", None)
    if depth is None:
        depth = np.full((height, width), -np.inf)
    image = _to_unit(color)
    _splat(image, np.ascontiguousarray(depth, dtype=np.float64), p["x"], p["y"], p["z"], p["tx"],
           p["ty"], p["tz"], p["r"], np.ascontiguousarray(p["rgb"], dtype=np.float64),
           p["alpha"].astype(np.float64), p["mode"].astype(np.int64))
    _to_bytes(image, color)
    frame.stats["particles drawn"] = int(len(p["x"]))
    return int(len(p["x"]))
