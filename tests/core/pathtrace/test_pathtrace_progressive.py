"""The path tracer in the window (core.renderers.pathtrace.progressive): a coarse one-path
picture, then passes adding up to the film's samples, each picture saying how many; the last
picture is the renderer's own; a newer request stops it between passes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from core.renderers.pathtrace.progressive import pathtrace_progressively
from core.context import RenderContext
from core.progressive import upscale
from core.render import render
from core.scene.formats import load_scene
from core.settings import RenderSettings

ROOT = Path(__file__).resolve().parents[3]


class Recorder:
    def __init__(self, stop_after: int | None = None):
        self.partials, self.reports, self.stop_after = [], [], stop_after

    @property
    def cancelled(self):
        return self.stop_after is not None and len(self.reports) > self.stop_after

    def check(self):
        if self.cancelled:
            raise RuntimeError("superseded")

    def report(self, fraction, detail):
        self.reports.append((fraction, detail))

    def partial(self, frame):
        self.partials.append(frame)


@pytest.fixture(scope="module")
def cornell():
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    return scene, scene.views[0]


def test_passes_add_up_to_the_renderers_frame(cornell):
    scene, view = cornell
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(24, 20), samples=4)
    control = Recorder()
    final = pathtrace_progressively(scene, view, settings, RenderContext(), render, control)
    assert np.array_equal(final.color, render(scene, view, settings).color)
    assert final.stats["samples per pixel"] == 4 and final.stats["pass"] == "final"
    # the first picture: one path per 4 x 4 pixels (no rate known yet), upscaled
    coarse = render(scene, view, settings.replace(size=(6, 5), samples=1))
    assert np.array_equal(control.partials[0].color, upscale(coarse.color, 4, 24, 20))
    # then the first pass at once (its samples per pixel said), later ones every quarter second
    assert control.partials[1].stats["samples per pixel"] == 1
    assert control.partials[1].stats["pass"].startswith("1 of 4 samples per pixel, ")
    details = [d for _, d in control.reports[1:]]
    assert [d.split(",")[0] for d in details] == [
        f"path tracing: {k} of 4 samples per pixel" for k in range(1, 5)]
    assert [f for f, _ in control.reports] == [0.0, 0.25, 0.5, 0.75, 1.0]


def test_the_running_mean_is_the_mean_of_the_passes_so_far(cornell):
    from core.renderers.pathtrace.draw import render_passes
    from core.radiosity.tone import tone_map
    from core.shading.illumination import to_uint8
    scene, view = cornell
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(16, 16), samples=9)
    control = Recorder()
    pathtrace_progressively(scene, view, settings, RenderContext(), render, control)
    one, _ = render_passes(scene, view, settings, RenderContext(), first=0, count=1)
    assert np.array_equal(control.partials[1].color, to_uint8(tone_map(one, scene.tone)))


def test_a_newer_request_stops_it_between_passes(cornell):
    scene, view = cornell
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(16, 16), samples=64)
    control = Recorder(stop_after=3)            # the coarse report and two passes
    with pytest.raises(RuntimeError, match="superseded"):
        pathtrace_progressively(scene, view, settings, RenderContext(), render, control)
    assert len(control.reports) == 4 and control.reports[-1][0] == 3 / 64
