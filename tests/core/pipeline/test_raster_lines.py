"""The midpoint line: the vectorised closed form against FvDFH's step-by-step loop."""

from __future__ import annotations

import numpy as np

from core.pipeline.raster_lines import draw_lines, line_pixels


def midpoint_loop(x0, y0, x1, y1):
    """FvDFH's MidpointLine, all eight octants, one pixel per step (the textbook reference)."""
    dx, dy = abs(x1 - x0), abs(y1 - y0)
    sx, sy = (1 if x1 >= x0 else -1), (1 if y1 >= y0 else -1)
    x, y, out = x0, y0, []
    if dx >= dy:
        d = 2 * dy - dx
        for _ in range(dx + 1):
            out.append((x, y))
            if d > 0:
                y += sy
                d -= 2 * dx
            d += 2 * dy
            x += sx
    else:
        d = 2 * dx - dy
        for _ in range(dy + 1):
            out.append((x, y))
            if d > 0:
                x += sx
                d -= 2 * dy
            d += 2 * dx
            y += sy
    return out


def test_closed_form_equals_the_loop_for_every_small_segment():
    ends = [(x0, y0, x1, y1) for x0 in range(-2, 3) for y0 in range(-2, 3)
            for x1 in range(-9, 10) for y1 in range(-9, 10)]
    x0, y0, x1, y1 = (np.array(c) for c in zip(*ends))
    x, y = line_pixels(x0, y0, x1, y1)
    expected = [p for e in ends for p in midpoint_loop(*e)]
    assert list(zip(x.tolist(), y.tolist())) == expected


def test_long_random_segments_equal_the_loop():
    rng = np.random.default_rng(7)
    ends = rng.integers(-400, 400, size=(200, 4))
    x, y = line_pixels(*ends.T)
    expected = [p for e in ends.tolist() for p in midpoint_loop(*e)]
    assert list(zip(x.tolist(), y.tolist())) == expected


def test_draw_lines_sets_exactly_the_line_pixels_top_row_first():
    image = np.zeros((5, 8, 3), np.uint8)
    draw_lines(image, np.array([[0.5, 0.5]]), np.array([[7.9, 4.2]]), (255, 128, 1))
    lit = np.argwhere(image[:, :, 0] == 255)
    rows_from_bottom = sorted((int(c), 4 - int(r)) for r, c in lit)
    assert rows_from_bottom == midpoint_loop(0, 0, 7, 4)
    assert (image[image[:, :, 0] == 255] == (255, 128, 1)).all()


def test_endpoint_on_the_far_edge_belongs_to_the_last_pixel():
    image = np.zeros((4, 4, 3), np.uint8)
    draw_lines(image, np.array([[4.0, 4.0]]), np.array([[0.0, 0.0]]), (9, 9, 9))
    assert [tuple(p) for p in np.argwhere(image[:, :, 0] == 9)] == [(0, 3), (1, 2), (2, 1), (3, 0)]
