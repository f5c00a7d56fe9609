"""Scan conversion of line segments into the CPU framebuffer (FvDFH 3.2.2, the midpoint line).

Takes device-space endpoints (x right, y up, in pixels) and sets every pixel of every line in
a ``(H, W, 3)`` uint8 image stored top row first. Endpoints land on the pixel that contains
them; the midpoint algorithm then steps along the major axis one pixel at a time with integer
arithmetic only.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _plot(image, x, y, color):
    h = image.shape[0]
    if 0 <= x < image.shape[1] and 0 <= y < h:
        row = h - 1 - y                      # device rows run bottom-up, image rows top-down
        for c in range(3):
            image[row, x, c] = color[c]


@njit(cache=True)
def _midpoint_line(image, x0, y0, x1, y1, color):
    """FvDFH's MidpointLine generalised to all eight octants."""
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    sx = 1 if x1 >= x0 else -1
    sy = 1 if y1 >= y0 else -1
    x, y = x0, y0
    if dx >= dy:                             # x is the major axis
        d = 2 * dy - dx
        for _ in range(dx + 1):
            _plot(image, x, y, color)
            if d > 0:
                y += sy
                d -= 2 * dx
            d += 2 * dy
            x += sx
    else:                                    # y is the major axis
        d = 2 * dx - dy
        for _ in range(dy + 1):
            _plot(image, x, y, color)
            if d > 0:
                x += sx
                d -= 2 * dy
            d += 2 * dx
            y += sy


@njit(cache=True)
def _draw_segments(image, p0, p1, color):
    w, h = image.shape[1], image.shape[0]
    for k in range(p0.shape[0]):
        # The pixel containing each endpoint; a point on the far edge belongs to the last pixel.
        x0 = min(max(int(np.floor(p0[k, 0])), 0), w - 1)
        y0 = min(max(int(np.floor(p0[k, 1])), 0), h - 1)
        x1 = min(max(int(np.floor(p1[k, 0])), 0), w - 1)
        y1 = min(max(int(np.floor(p1[k, 1])), 0), h - 1)
        _midpoint_line(image, x0, y0, x1, y1, color)


def draw_lines(image: np.ndarray, p0: np.ndarray, p1: np.ndarray, color) -> None:
    """Draw segments ``p0[k]–p1[k]`` (device ``(N, >=2)``) into ``image`` in place.

    The endpoints must be finite (the clipper guarantees it); they are clamped to the image.
    """
    if len(p0) == 0 or image.size == 0:
        return
    rgb = np.asarray(color, dtype=np.uint8)
    _draw_segments(image, np.ascontiguousarray(p0[:, :2], dtype=np.float64),
                   np.ascontiguousarray(p1[:, :2], dtype=np.float64), rgb)
