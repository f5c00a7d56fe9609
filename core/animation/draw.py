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

from core.camera.view import normalizing_transform, vrc_basis
from core.jit import njit
from core.pipeline import project

POINT, SPRITE, STREAK = 0, 1, 2
# The stage's cost is the pixels its sprites cover (each blended once per sprite): 2M sprites
# that fill a 500 x 500 frame are 5·10^11 blends, over half an hour. Above this many (a few
# seconds) the frame is not drawn and says why.
MAX_SPLAT_PIXELS = 2_000_000_000
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


@njit(cache=True)
def _to_device(p0, p1, p2, n, m, z_near, out, k):
    """One world point → device (x, y, z) in ``out[k]``: N_per/N_par, then the
    perspective-to-parallel matrix and M_vv3dv (``m``), then the divide by W. Returns whether
    it lies between the back (z = -1) and front (z = z_near) planes, in front of the eye."""
    w = n[3, 0] * p0 + n[3, 1] * p1 + n[3, 2] * p2 + n[3, 3]
    c0 = (n[0, 0] * p0 + n[0, 1] * p1 + n[0, 2] * p2 + n[0, 3]) / w
    c1 = (n[1, 0] * p0 + n[1, 1] * p1 + n[1, 2] * p2 + n[1, 3]) / w
    c2 = (n[2, 0] * p0 + n[2, 1] * p1 + n[2, 2] * p2 + n[2, 3]) / w
    dw = m[3, 0] * c0 + m[3, 1] * c1 + m[3, 2] * c2 + m[3, 3]
    if not dw > 0.0:
        out[k, 0] = out[k, 1] = out[k, 2] = 0.0
        return False
    out[k, 0] = (m[0, 0] * c0 + m[0, 1] * c1 + m[0, 2] * c2 + m[0, 3]) / dw
    out[k, 1] = (m[1, 0] * c0 + m[1, 1] * c1 + m[1, 2] * c2 + m[1, 3]) / dw
    out[k, 2] = (m[2, 0] * c0 + m[2, 1] * c1 + m[2, 2] * c2 + m[2, 3]) / dw
    return -1.0 <= c2 <= z_near


@njit(cache=True)
def _project_all(position, tail, radius, u, n, m, z_near, head, tail_dev, pixels, inside,
                 tail_inside):
    """Every sprite's centre, tail and radius in pixels (the distance between the projections
    of the centre and of the centre moved by its size along the VRC's u axis)."""
    edge = np.empty((1, 3))
    for k in range(position.shape[0]):
        x, y, z = position[k, 0], position[k, 1], position[k, 2]
        inside[k] = _to_device(x, y, z, n, m, z_near, head, k)
        tail_inside[k] = _to_device(tail[k, 0], tail[k, 1], tail[k, 2], n, m, z_near, tail_dev, k)
        s = radius[k]
        _to_device(x + s * u[0], y + s * u[1], z + s * u[2], n, m, z_near, edge, 0)
        pixels[k] = np.hypot(edge[0, 0] - head[k, 0], edge[0, 1] - head[k, 1])


def project_sprites(sprites: Sprites, view, projection: str, width: int, height: int,
                    keep_aspect: bool = False):
    """Device centres, tails and pixel radii of the sprites, and ``order``: the indices of
    those inside the view volume, back to front."""
    n, z_min = normalizing_transform(view, projection)
    vp = project.viewport(view.window, width, height, keep_aspect)
    m = project.triangle_matrix(projection, z_min, vp)
    count = len(sprites)
    head, tail = np.empty((count, 3)), np.empty((count, 3))
    pixels = np.empty(count)
    inside, tail_inside = np.empty(count, np.bool_), np.empty(count, np.bool_)
    _project_all(np.ascontiguousarray(sprites.position, dtype=np.float64),
                 np.ascontiguousarray(sprites.tail, dtype=np.float64),
                 np.ascontiguousarray(sprites.radius, dtype=np.float64), vrc_basis(view)[0],
                 n, m, z_min if projection == "perspective" else 0.0, head, tail, pixels,
                 inside, tail_inside)
    mode = sprites.mode.astype(np.int64)
    mode[(mode == STREAK) & ~tail_inside] = SPRITE        # a tail behind the eye: no streak
    keep = np.flatnonzero(inside)
    order = keep[np.argsort(head[keep, 2], kind="stable")]  # far (small z) first
    return {"head": head, "tail": tail, "r": np.minimum(pixels, float(max(width, height))),
            "mode": mode, "order": order}


def covered_pixels(p: dict, width: int, height: int) -> int:
    """The pixels :func:`_splat` will visit for the projected sprites ``p``: each sprite's
    bounding box (its streak's, for a streak) inside the frame, one pixel for a point."""
    k = p["order"]
    if len(k) == 0:
        return 0
    head, tail, mode = p["head"][k], p["tail"][k], p["mode"][k]
    radius = np.maximum(p["r"][k], 0.75)
    far = np.where((mode == STREAK)[:, None], tail[:, :2], head[:, :2])
    lo = np.minimum(head[:, :2], far) - radius[:, None]
    hi = np.maximum(head[:, :2], far) + radius[:, None]
    w = np.clip(np.ceil(hi[:, 0]), -1, width - 1) - np.clip(np.floor(lo[:, 0]), 0, width) + 1
    h = np.clip(np.ceil(hi[:, 1]), -1, height - 1) - np.clip(np.floor(lo[:, 1]), 0, height) + 1
    area = np.where(mode == POINT, 1.0, np.maximum(w, 0) * np.maximum(h, 0))
    return int(area.sum())


@njit(cache=True)
def _blend(image, depth, row, col, z, rgb, a):
    """One fragment: depth-tested (never written), then over-blended."""
    if z > depth[row, col] and a > 0.0:
        for c in range(3):
            image[row, col, c] = a * rgb[c] + (1.0 - a) * image[row, col, c]


@njit(cache=True)
def _splat_rows(image, depth, order, head, tail, r, rgb, alpha, mode, row_first, row_last):
    """Draw the sprites ``order`` names, in that (back-to-front) order, into device rows
    ``row_first`` … ``row_last`` only."""
    height, width = depth.shape
    for o in range(order.shape[0]):
        k = order[o]
        x, y, z = head[k, 0], head[k, 1], head[k, 2]
        if mode[k] == 0:                                   # a point: the pixel under it
            i, j = int(np.floor(x)), int(np.floor(y))
            if 0 <= i < width and row_first <= j <= row_last:
                _blend(image, depth, height - 1 - j, i, z, rgb[k], alpha[k])
            continue
        radius = max(r[k], 0.75)                           # at least the pixel under it
        ax, ay, az = x, y, z
        if mode[k] == 2:
            ax, ay, az = tail[k, 0], tail[k, 1], tail[k, 2]
        dx, dy = x - ax, y - ay
        length2 = dx * dx + dy * dy
        i0 = max(int(np.floor(min(x, ax) - radius)), 0)
        i1 = min(int(np.ceil(max(x, ax) + radius)), width - 1)
        j0 = max(int(np.floor(min(y, ay) - radius)), row_first)
        j1 = min(int(np.ceil(max(y, ay) + radius)), row_last)
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
                zq = az + s * (z - az)
                fade = s if mode[k] == 2 else 1.0          # a streak thins out to its tail
                _blend(image, depth, height - 1 - j, i, zq, rgb[k], alpha[k] * (1.0 - d2) * fade)


@njit(cache=True)
def _splat(image, depth, order, head, tail, r, rgb, alpha, mode):
    """All sprites, back to front, over every row. (Bands drawn in parallel would be
    bit-identical, each going through the sprites in the same order, but every band scans all
    sprites: on two busy cores that cost more CPU than it saved, measured at 100k sprites.)"""
    _splat_rows(image, depth, order, head, tail, r, rgb, alpha, mode, 0, depth.shape[0] - 1)


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
    projection = settings.projection
    p = project_sprites(sprites, view, projection, width, height,
                        settings.keep_aspect)     # the z-buffer's viewport
    covered = covered_pixels(p, width, height)
    if covered > MAX_SPLAT_PIXELS:
        frame.message = (f"the particles would cover {covered:,} pixels ({len(p['order']):,} "
                         f"in view); a frame may blend at most {MAX_SPLAT_PIXELS:,}: make them "
                         "smaller or fewer, or the frame smaller")
        return 0
    depth = frame.depth
    if depth is None:
        # a renderer that keeps no depth (wireframe lines, the ray casters): nothing hides a
        # particle, and the frame says so
        frame.stats["particles depth-tested"] = False
        depth = np.full((height, width), -np.inf)
    image = _to_unit(color)
    _splat(image, np.ascontiguousarray(depth, dtype=np.float64), p["order"], p["head"],
           p["tail"], p["r"], np.ascontiguousarray(sprites.rgb, dtype=np.float64),
           np.ascontiguousarray(sprites.alpha, dtype=np.float64), p["mode"])
    _to_bytes(image, color)
    frame.stats["particles drawn"] = int(len(p["order"]))
    return int(len(p["order"]))
