"""The window's progressive volume frames (``coarse_then_full`` in core.progressive, the
drawer of a progressive renderer without one of its own): a coarse picture first, then exactly
the front door's frame."""

from __future__ import annotations

import numpy as np

from core.progressive import COARSE_FIRST as COARSE, coarse_then_full
from core.registry import get_renderer
from core.render import render
from core.settings import RenderSettings
from core.volume import generators
from core.volume.data import Volume
from tests.core.volume.test_volume_render import scene_with


class Collect:
    cancelled = False

    def __init__(self):
        self.partials, self.reports = [], []

    def check(self):
        pass

    def report(self, fraction, detail):
        self.reports.append(fraction)

    def partial(self, frame):
        self.partials.append(frame.color.copy())


def test_coarse_first_then_the_front_doors_frame():
    values, spacing = generators.sphere(17, radius=0.7, density=3.0)
    volume = Volume(values=values, spacing=spacing,
                    transfer=np.array([[0.0, 1, 0.5, 0.2, 0.0], [3.0, 1, 0.5, 0.2, 3.0]]))
    scene = scene_with([volume])
    settings = RenderSettings.for_scene(scene, renderer="volume", size=(24, 16))
    control = Collect()
    frame = coarse_then_full(scene, scene.views[0], settings, None, render, control=control)
    assert np.array_equal(frame.color, render(scene, scene.views[0], settings).color)
    (coarse,) = control.partials
    assert coarse.shape == (16, 24, 3)
    small = render(scene, scene.views[0], settings.replace(size=(6, 4))).color
    assert np.array_equal(coarse[::COARSE, ::COARSE], small)     # each block one coarse ray
    assert control.reports == [0.0, 0.2]


def test_a_progressive_renderer_without_a_drawer_of_its_own_is_drawn_coarse_then_full():
    from core.renderers.raytrace.progressive import trace_progressively
    assert get_renderer("volume").drawer() is coarse_then_full
    assert get_renderer("raytrace").drawer() is trace_progressively
