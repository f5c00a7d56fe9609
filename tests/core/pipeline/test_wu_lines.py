"""Wu's antialiased lines (``--antialias-lines``) against the exact area a line one pixel wide
(across its minor axis) covers in each pixel, integrated here column by column in closed form
along y and finely along x: an independent computation of the same area."""

from __future__ import annotations

import numpy as np
import pytest

from core import RenderSettings, render
from core.pipeline.raster_lines import wu_coverage
from core.scene.formats import load_scene


def _exact(p0, p1, column: int, row: int, n: int = 4000) -> float:
    """Area of the band |y − y(x)| <= 1/2 inside pixel (column, row), x over the pixel."""
    x = column + (np.arange(n) + 0.5) / n
    y = p0[1] + (p1[1] - p0[1]) * (x - p0[0]) / (p1[0] - p0[0])
    low, high = np.maximum(y - 0.5, row), np.minimum(y + 0.5, row + 1)
    return float(np.maximum(high - low, 0.0).mean())


@pytest.mark.parametrize("p0, p1, bound", [
    ((2.0, 5.3), (40.0, 5.3), 1e-9),             # horizontal: Wu is the area exactly
    # a sloped line: Wu samples the overlap (a tent in y about the pixel's centre row) at the
    # column's centre; where the line crosses the centre row inside the column the area is
    # the tent's mean over a height m, at most m / 4 below its peak
    ((2.0, 5.1), (40.0, 14.6), 0.25 / 4),        # slope 1/4
    ((1.5, 3.7), (30.5, 17.2), 0.4655 / 4),      # slope 0.4655
])
def test_wu_intensity_is_the_lines_area_coverage(p0, p1, bound):
    x, y, c = wu_coverage(np.array([p0]), np.array([p1]))
    inner = (x > p0[0] + 1) & (x < p1[0] - 2)   # away from the ends, which Wu leaves square
    worst = max(abs(cov - _exact(p0, p1, int(i), int(j))) for i, j, cov in
                zip(x[inner], y[inner], c[inner]))
    assert worst <= bound
    # each column's two coverages add up to the band's width, 1
    per_column = np.bincount(x[inner] - x[inner].min(), weights=c[inner])
    assert np.allclose(per_column[per_column > 0], 1.0)


def test_steep_lines_swap_the_axes():
    x, y, c = wu_coverage(np.array([[5.3, 2.0]]), np.array([[5.3, 40.0]]))
    assert set(x.tolist()) == {4, 5} and np.allclose(c[x == 5], 0.8)    # 0.8 of it in column 5


def test_the_house_antialiased_keeps_its_midpoint_pixels_lit():
    scene = load_scene("scenes/house.toml")
    settings = RenderSettings.for_scene(scene, size=(160, 160))
    jagged = render(scene, scene.views[0], settings).color
    smooth = render(scene, scene.views[0], settings.replace(antialias_lines=True)).color
    lit, soft = jagged.max(axis=2) > 0, smooth.max(axis=2)
    assert (soft[lit] > 0).mean() > 0.95          # where the midpoint line is, so is Wu's
    assert ((soft > 0) & (soft < 255)).sum() > lit.sum() // 2      # and it has grey levels
