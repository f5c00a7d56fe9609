"""The path tracer traces a pass a band of rays at a time and reports each (core.work), so that
a large frame shows its progress and Ctrl+C stops it between two bands; the bands do not change
the picture (each ray draws its numbers from its pixel's index, wherever its band starts)."""

from __future__ import annotations

import numpy as np
import pytest

from core import work
from core.context import RenderContext
from core.renderers.pathtrace import draw as renderer
from core.paths import SCENES_DIR
from core.scene.formats import load_scene
from core.settings import RenderSettings


class Stop(Exception):
    pass


def passes(scene):
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(40, 30), samples=4)
    return renderer.render_passes(scene, scene.views[0], settings, RenderContext())[0]


def test_each_band_is_reported_and_a_watcher_stops_between_two(monkeypatch):
    scene = load_scene(SCENES_DIR / "cornell_box.toml")
    whole = passes(scene)
    monkeypatch.setattr(renderer, "BAND", 500)              # 1,200 rays a pass: 3 bands
    seen = []
    with work.watching(lambda what, done, total, unit: seen.append((what, done, total, unit))):
        banded = passes(scene)
    assert seen == [("path tracing", k * 1200 + done, 4800, "path") for k in range(4)
                    for done in (500, 1000, 1200)]
    assert np.array_equal(banded, whole) and whole.std() > 0.01

    def stop_after_the_second(what, done, total, unit):
        if done >= 1000:
            raise Stop

    traced = []
    monkeypatch.setattr(renderer, "trace", lambda *a, f=renderer.trace, **k:
                        traced.append(k["first_pixel"]) or f(*a, **k))
    with pytest.raises(Stop), work.watching(stop_after_the_second):
        passes(scene)
    assert traced == [0, 500]
