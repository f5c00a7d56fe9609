"""Scan conversion of line segments into the CPU framebuffer (FvDFH 3.2.2, the midpoint line).

Takes device-space endpoints (x right, y up, in pixels) and sets every pixel of every line in
a ``(H, W, 3)`` uint8 image stored top row first. Endpoints land on the pixel that contains
them. The midpoint algorithm steps along the major axis one pixel at a time, choosing between
the two candidate minor-axis pixels by the sign of the decision variable
``d = 2 dy - dx`` (``+2 dy`` each step, ``-2 dx`` when the minor coordinate advances).

Its closed form — after ``i`` steps the minor coordinate has advanced
``k_i = ceil((2 dy i - dx) / (2 dx))`` times (never below 0) — lets every pixel of every line
be computed at once with integer numpy arithmetic; ``tests/core/pipeline/test_raster_lines.py``
checks it against the step-by-step loop. No numba here: a wireframe frame needs no compiler.
"""

from __future__ import annotations

import numpy as np


def line_pixels(x0, y0, x1, y1) -> tuple[np.ndarray, np.ndarray]:
    """All pixels of the integer segments (x0, y0)–(x1, y1), as the midpoint algorithm sets them."""
    x0, y0, x1, y1 = (np.asarray(a, dtype=np.int64) for a in (x0, y0, x1, y1))
    dx, dy = np.abs(x1 - x0), np.abs(y1 - y0)
    x_major = dx >= dy
    major = np.where(x_major, dx, dy)              # steps along the major axis
    minor = np.where(x_major, dy, dx)
    counts = major + 1
    segment = np.repeat(np.arange(len(x0)), counts)
    first = np.cumsum(counts) - counts
    i = np.arange(counts.sum()) - np.repeat(first, counts)          # step number in its line
    big, small = major[segment], minor[segment]
    # k_i = ceil((2 small i - big) / (2 big)) clipped at 0; for a point (big = 0) k = 0.
    numerator = 2 * small * i - big
    k = np.where(big > 0, np.maximum(-((-numerator) // np.maximum(2 * big, 1)), 0), 0)
    sx = np.where(x1 >= x0, 1, -1)[segment]
    sy = np.where(y1 >= y0, 1, -1)[segment]
    xm = x_major[segment]
    x = x0[segment] + sx * np.where(xm, i, k)
    y = y0[segment] + sy * np.where(xm, k, i)
    return x, y


def draw_lines(image: np.ndarray, p0: np.ndarray, p1: np.ndarray, color) -> None:
    """Draw segments ``p0[k]–p1[k]`` (device ``(N, >=2)``) into ``image`` in place.

    The endpoints must be finite (the clipper guarantees it); the pixel containing each is
    clamped to the image, so a point on the far edge belongs to the last pixel.
    """
    if len(p0) == 0 or image.size == 0:
        return
    height, width = image.shape[:2]

    def pixel(p):
        col = np.clip(np.floor(p[:, 0]), 0, width - 1).astype(np.int64)
        row = np.clip(np.floor(p[:, 1]), 0, height - 1).astype(np.int64)
        return col, row

    (x0, y0), (x1, y1) = pixel(np.asarray(p0)), pixel(np.asarray(p1))
    x, y = line_pixels(x0, y0, x1, y1)
    image[height - 1 - y, x] = np.asarray(color, dtype=np.uint8)   # device rows run bottom-up


def wu_coverage(p0: np.ndarray, p1: np.ndarray):
    """Wu's antialiased line (Wu 1991; FvDFH 3.17's unweighted area sampling of a line one
    pixel wide): for each segment, every pixel centre column (row, for a steep line) the line
    spans, the two pixels nearest the line across the minor axis with the coverages
    ``1 − f`` and ``f``, f the line's distance past the first one's centre. Returns
    ``(x, y, coverage)`` in device pixels (y up), one entry per pixel touched (a pixel two
    segments touch appears twice)."""
    p0, p1 = np.asarray(p0, np.float64), np.asarray(p1, np.float64)
    xs, ys, cs = [], [], []
    for steep in (False, True):
        a, b = (1, 0) if steep else (0, 1)           # a: the major axis, b: the minor one
        d = np.abs(p1[:, 0] - p0[:, 0]) < np.abs(p1[:, 1] - p0[:, 1])
        pick = d if steep else ~d
        s, e = p0[pick], p1[pick]
        flip = s[:, a] > e[:, a]
        s, e = np.where(flip[:, None], e, s), np.where(flip[:, None], s, e)
        first = np.ceil(s[:, a] - 0.5).astype(np.int64)          # the first centre inside
        last = np.floor(e[:, a] - 0.5).astype(np.int64)
        counts = np.maximum(last - first + 1, 0)
        seg = np.repeat(np.arange(len(s)), counts)
        step = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        major = first[seg] + step
        span = e[seg, a] - s[seg, a]
        slope = np.divide(e[seg, b] - s[seg, b], span, out=np.zeros_like(span), where=span > 0)
        at = s[seg, b] + slope * (major + 0.5 - s[seg, a])       # the line at the centre
        below = np.floor(at - 0.5).astype(np.int64)              # the centre just under it
        f = (at - 0.5) - below
        for minor, coverage in ((below, 1.0 - f), (below + 1, f)):
            xs.append(minor if steep else major)
            ys.append(major if steep else minor)
            cs.append(coverage)
    return np.concatenate(xs), np.concatenate(ys), np.concatenate(cs)


def draw_lines_wu(image: np.ndarray, p0: np.ndarray, p1: np.ndarray, color) -> None:
    """Draw segments ``p0[k]–p1[k]`` (device ``(N, >=2)``) antialiased (:func:`wu_coverage`):
    each touched pixel becomes ``(1 − c) · pixel + c · colour``, c its coverage, capped at 1
    where lines meet."""
    if len(p0) == 0 or image.size == 0:
        return
    height, width = image.shape[:2]
    x, y, c = wu_coverage(np.asarray(p0)[:, :2], np.asarray(p1)[:, :2])
    keep = (x >= 0) & (x < width) & (y >= 0) & (y < height) & (c > 0)
    x, y, c = x[keep], y[keep], c[keep]
    cover = np.zeros((height, width))
    np.add.at(cover, (height - 1 - y, x), c)
    cover = np.minimum(cover, 1.0)[:, :, None]
    touched = cover[:, :, 0] > 0
    blend = (1.0 - cover) * image + cover * np.asarray(color, np.float64)
    image[touched] = np.floor(blend[touched] + 0.5).astype(np.uint8)
