"""The order in which the path tracer's passes take a pixel's strata
(core.camera.film.progressive_order): a permutation whose every prefix of 4^k strata covers the
pixel one cell of a 2^k x 2^k grid each, checked cell by cell."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.film import progressive_order, sample_offsets
from core.renderers.pathtrace.draw import pass_offsets


@pytest.mark.parametrize("side", [2, 4, 8, 16])
def test_every_prefix_of_a_power_of_four_covers_its_grid_once(side):
    order = progressive_order(side * side)
    assert sorted(order) == list(range(side * side))            # each stratum once
    k = 1
    while k <= side:
        first = order[:k * k]
        cells = {((s % side) * k // side, (s // side) * k // side) for s in first}
        assert len(cells) == k * k, (side, k)                    # one per cell of k x k
        k *= 2


def test_grids_whose_side_is_not_a_power_of_two_stay_row_by_row():
    assert list(progressive_order(9)) == list(range(9))         # 3 x 3: not a power of two
    assert list(progressive_order(12)) == list(range(12))       # not a full grid


def test_the_path_tracer_takes_the_same_offsets_in_that_order():
    film = sample_offsets(256, "jittered", 3)
    passes = pass_offsets(256, 3)
    assert np.array_equal(passes, film[progressive_order(256)])
    first = passes[:16]
    assert np.ptp(first[:, 0]) > 0.7 and np.ptp(first[:, 1]) > 0.7   # spread over the pixel
