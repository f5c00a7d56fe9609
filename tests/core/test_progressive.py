"""The coarse first picture's size (core.progressive.coarse_factor): the smallest reduction
whose one-sample pass the last measured rate puts within the budget (hand-counted rays)."""

from __future__ import annotations

import pytest

from core.context import RenderContext
from core.progressive import COARSE_BUDGET, coarse_factor, coarse_size, note_rate


def test_before_any_rate_the_default_factor():
    assert coarse_factor(RenderContext(), "raytrace", 1580, 1080, 8) == 8
    assert coarse_factor(None, "raytrace", 1580, 1080, 8) == 8
    assert coarse_factor(RenderContext(), "volume", 100, 100, 1, least=2) == 2


def test_the_smallest_reduction_within_the_budget():
    context = RenderContext()
    assert COARSE_BUDGET == 0.08
    # 1 microsecond a ray: 1580 x 1080 at f = 4 is 395 x 270 = 106,650 rays = 0.107 s (over),
    # at f = 8 it is 198 x 135 = 26,730 rays = 0.027 s
    note_rate(context, "raytrace", 0.5, 500_000)
    assert coarse_factor(context, "raytrace", 1580, 1080, 8) == 8
    assert coarse_size(1580, 1080, 8) == (198, 135)
    # ten times faster: f = 4 takes 0.0107 s, f = 2 (790 x 540 = 426,600 rays) 0.043 s,
    # f = 1 (1,706,400 rays) 0.171 s
    note_rate(context, "raytrace", 0.05, 500_000)
    assert coarse_factor(context, "raytrace", 1580, 1080, 8) == 2
    # a small picture needs no coarse pass at all, unless one is asked for
    assert coarse_factor(context, "raytrace", 200, 200, 8) == 1
    assert coarse_factor(context, "raytrace", 200, 200, 8, least=2) == 2
    # rates are kept per renderer
    assert coarse_factor(context, "pathtrace", 1580, 1080, 4) == 4


def test_a_very_slow_renderer_gets_the_coarsest_reduction():
    context = RenderContext()
    note_rate(context, "pathtrace", 10.0, 100)        # 0.1 s a ray
    assert coarse_factor(context, "pathtrace", 1580, 1080, 4) == 64


@pytest.mark.parametrize("seconds, rays", [(0.0, 100), (1.0, 0)])
def test_a_pass_with_no_time_or_no_rays_changes_nothing(seconds, rays):
    context = RenderContext()
    note_rate(context, "raytrace", seconds, rays)
    assert coarse_factor(context, "raytrace", 1580, 1080, 8) == 8
