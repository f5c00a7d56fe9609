"""The ray tracer reports each band of rows it has traced (core.work), so that a large frame
shows its progress and stops between two bands; the bands do not change the picture."""

from __future__ import annotations

import numpy as np
import pytest

from core import work
from core.paths import SCENES_DIR
from core.renderers.raytrace import draw as renderer
from core.render import render
from core.scene.formats import load_scene
from core.settings import RenderSettings


class Stop(Exception):
    pass


def frame(scene):
    settings = RenderSettings.for_scene(scene, renderer="raytrace", size=(64, 48))
    return render(scene, scene.views[0], settings)


def test_each_band_is_reported_and_a_watcher_stops_the_frame_between_two(monkeypatch):
    scene = load_scene(SCENES_DIR / "whitted.toml", size=(64, 48))
    whole = frame(scene).color
    monkeypatch.setattr(renderer, "RAYS_PER_BAND", 64 * 5)      # bands of five rows
    rows = []
    with work.watching(lambda what, done, total, unit: rows.append((what, done, total, unit))):
        banded = frame(scene).color
    assert rows == [("ray tracing", min(r, 48), 48, "row") for r in range(5, 53, 5)]
    assert np.array_equal(banded, whole)
    assert len(np.unique(whole.reshape(-1, 3), axis=0)) > 50

    def stop_at_the_third(what, done, total, unit):
        if done >= 15:
            raise Stop

    traced = []
    monkeypatch.setattr(renderer, "trace_tile", lambda *a, f=renderer.trace_tile:
                        traced.append(a[1]) or f(*a))
    with pytest.raises(Stop), work.watching(stop_at_the_third):
        frame(scene)
    assert traced == [0, 5, 10]
