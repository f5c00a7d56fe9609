"""The CIE 1931 xy chromaticity diagram, drawn with numpy onto an RGB image.

Inside the spectral locus (closed by the line of purples) each pixel shows its chromaticity
as sRGB can: the linear RGB of ``xy`` at Y = 1, negative parts (outside the sRGB gamut)
clipped to 0, scaled so its largest channel is 1, then sRGB-encoded. Inside the sRGB
triangle that is the colour itself at its brightest; outside it, the nearest the screen has.
Over it: a 0.1 grid, the locus's outline, the sRGB triangle, the D65 white point and any
given points.
"""

from __future__ import annotations

import numpy as np

from core.colour import cie, srgb

X_RANGE, Y_RANGE = 0.8, 0.9           # the diagram shows 0 ≤ x ≤ 0.8, 0 ≤ y ≤ 0.9
BACKGROUND = (36, 36, 40)
GRID = (70, 70, 78)
LOCUS = (110, 110, 110)
TRIANGLE = (0, 0, 0)
WHITE_RING = (60, 60, 60)
WHITE_MARK = (255, 255, 255)
TICKS = tuple(range(460, 621, 20))     # nm marked on the locus


def layout(width: int, height: int, margin: int) -> tuple[float, float, float]:
    """(scale px per unit, left, bottom) of the square-unit plot inside the margins."""
    scale = min((width - 2 * margin) / X_RANGE, (height - 2 * margin) / Y_RANGE)
    return scale, float(margin), float(height - margin)


def pixel_of(xy, width: int, height: int, margin: int) -> np.ndarray:
    """(..., 2) xy → (..., 2) (column, row) in pixel units (row 0 the top, centres at +0.5)."""
    scale, left, bottom = layout(width, height, margin)
    xy = np.asarray(xy, np.float64)
    return np.stack([left + xy[..., 0] * scale, bottom - xy[..., 1] * scale], axis=-1)


def xy_of_pixels(width: int, height: int, margin: int) -> np.ndarray:
    """(H, W, 2) the chromaticity at each pixel's centre."""
    scale, left, bottom = layout(width, height, margin)
    cols, rows = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    return np.stack([(cols - left) / scale, (bottom - rows) / scale], axis=-1)


def inside(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(P,) bool: the even-odd rule, a ray to +x crossing the polygon's edges."""
    x, y = points[:, 0], points[:, 1]
    result = np.zeros(len(points), bool)
    for (x0, y0), (x1, y1) in zip(polygon, np.roll(polygon, -1, axis=0)):
        spans = (y0 > y) != (y1 > y)
        with np.errstate(divide="ignore", invalid="ignore"):
            cross = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
        result ^= spans & (x < cross)
    return result


def fill_colours(xy) -> np.ndarray:
    """(..., 2) xy → (..., 3) uint8: the chromaticity at its brightest in sRGB (clipped)."""
    rgb = srgb.xyz_of(xy) @ srgb.XYZ_TO_RGB.T
    rgb = np.clip(rgb, 0.0, None)
    rgb /= rgb.max(axis=-1, keepdims=True)
    return np.round(srgb.encode(rgb) * 255).astype(np.uint8)


def draw_segment(image, a, b, colour, width: float = 1.5) -> None:
    """Every pixel whose centre is within width/2 of the segment a–b (pixel units)."""
    a, b = np.asarray(a, np.float64), np.asarray(b, np.float64)
    lo = np.floor(np.minimum(a, b) - width).astype(int)
    hi = np.ceil(np.maximum(a, b) + width).astype(int)
    lo, hi = np.maximum(lo, 0), np.minimum(hi, [image.shape[1], image.shape[0]])
    cols, rows = np.meshgrid(np.arange(lo[0], hi[0]) + 0.5, np.arange(lo[1], hi[1]) + 0.5)
    d = b - a
    t = np.clip(((cols - a[0]) * d[0] + (rows - a[1]) * d[1]) / max(d @ d, 1e-12), 0, 1)
    near = np.hypot(cols - a[0] - t * d[0], rows - a[1] - t * d[1]) <= width / 2
    image[lo[1]:hi[1], lo[0]:hi[0]][near] = colour


def draw_disc(image, centre, radius: float, colour) -> None:
    draw_segment(image, centre, centre, colour, 2 * radius)


def draw_polyline(image, points, colour, width: float = 1.5, closed: bool = False) -> None:
    ends = np.roll(points, -1, axis=0) if closed else points[1:]
    for a, b in zip(points, ends):
        draw_segment(image, a, b, colour, width)


def chromaticity_diagram(width: int = 640, height: int = 720, margin: int = 48,
                         points=None, point_colours=None, marks: bool = True) -> np.ndarray:
    """(H, W, 3) uint8: the diagram; ``points`` (P, 2) xy drawn as dots of ``point_colours``
    (P, 3) uint8; ``marks = False`` leaves the fill alone (no grid, lines or dots)."""
    image = np.empty((height, width, 3), np.uint8)
    image[:] = BACKGROUND
    to_px = lambda xy: pixel_of(xy, width, height, margin)     # noqa: E731
    if marks:
        for k in range(9):
            draw_segment(image, to_px([k / 10, 0]), to_px([k / 10, Y_RANGE]), GRID, 1)
        for k in range(10):
            draw_segment(image, to_px([0, k / 10]), to_px([X_RANGE, k / 10]), GRID, 1)
    _, locus = cie.spectral_locus()
    xy = xy_of_pixels(width, height, margin).reshape(-1, 2)
    seen = inside(xy, locus)
    image.reshape(-1, 3)[seen] = fill_colours(xy[seen])
    if not marks:
        return image
    draw_polyline(image, to_px(locus), LOCUS, 1.5, closed=True)
    nm, all_xy = cie.spectral_locus()
    for tick in TICKS:
        draw_disc(image, to_px(all_xy[np.searchsorted(nm, tick)]), 2.5, LOCUS)
    draw_polyline(image, to_px(srgb.PRIMARIES), TRIANGLE, 2.0, closed=True)
    draw_disc(image, to_px(srgb.D65), 5.0, WHITE_RING)
    draw_disc(image, to_px(srgb.D65), 3.0, WHITE_MARK)
    if points is not None:
        for p, c in zip(to_px(points), point_colours):
            draw_disc(image, p, 5.0, (0, 0, 0))
            draw_disc(image, p, 3.5, tuple(int(v) for v in c))
    return image
