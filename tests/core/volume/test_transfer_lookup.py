"""The transfer function is looked up by bisection: a 100,000-point function draws in the
time of a short one and gives the picture of the same ramp written with two points."""

from __future__ import annotations

import numpy as np

from core.volume import generators
from core.volume.data import Volume
from tests.core.volume.test_volume_render import draw, scene_with


def _ramp(points: int) -> np.ndarray:
    x = np.linspace(0.0, 3.0, points)
    return np.column_stack([x, np.full(points, 1.0), x / 3.0, np.full(points, 0.2), x])


def test_a_100000_point_transfer_function_is_the_two_point_ramp():
    values, spacing = generators.sphere(17, radius=0.7, density=3.0)
    short = draw(scene_with([Volume(values=values, spacing=spacing, transfer=_ramp(2))]),
                 (24, 24))
    long = draw(scene_with([Volume(values=values, spacing=spacing, transfer=_ramp(100_000))]),
                (24, 24))
    assert short.max() > 0.2                     # the sphere is drawn
    assert np.abs(short - long).max() <= 1 / 255  # the same linear ramp: rounding at most


def test_classify_by_bisection_is_numpys_interp_at_the_points_between_and_beyond():
    from core.volume.data import transfer_at
    from core.volume.raymarch import classify
    transfer = np.array([[0.0, 0, 0, 0, 0], [0.2, 1, 0, 0, 2], [0.2, 0, 1, 0, 4],
                         [0.5, 0, 0, 1, 1], [1.0, 1, 1, 1, 8]])
    for value in (-1.0, 0.0, 0.1, 0.3, 0.5, 0.75, 1.0, 2.0):
        assert np.allclose(classify(transfer, value), transfer_at(transfer, value),
                           rtol=0, atol=1e-15), value
    # a step (two points at 0.2): below it the first segment, above it the next
    assert classify(transfer, 0.19999)[0] > 0.99 and classify(transfer, 0.20001)[1] > 0.99
