"""The window's animated frames: a long simulation (a far seek on rigid bodies) stops at its
next chunk once a newer request supersedes it (the worker's own cancel), and steps on from
there to the same numbers when the time is asked for again."""

from __future__ import annotations

import time

import numpy as np

from app.session.playback import render_animated
from app.viewer.worker import RenderWorker
from core import work
from core.animation.frames import render_at
from core.animation.keys import animation_of
from core.paths import SCENES_DIR
from core.scene.formats import load_scene
from core.settings import RenderSettings

SIZE = (32, 24)


def _animation():
    return animation_of(load_scene(SCENES_DIR / "blocks_falling.toml", size=SIZE))


def _collect(worker, generation, timeout=120.0):
    """Results until that of ``generation``; every generation seen on the way."""
    seen, deadline = [], time.monotonic() + timeout
    while time.monotonic() < deadline:
        result = worker.collect()
        if result is not None:
            seen.append(result.generation)
            if result.generation == generation:
                return result, seen
        time.sleep(0.01)
    raise AssertionError("no result from the worker")


def test_a_superseded_simulation_stops_at_a_chunk_and_steps_on_from_there(monkeypatch):
    monkeypatch.setattr(work, "CHUNK_SECONDS", 0.01)
    animation = _animation()
    world = animation.movers[0]
    settings = RenderSettings.for_scene(animation.scene, size=SIZE)
    t = 2.9
    target = world.steps_to(t)
    worker = RenderWorker()
    newer = []

    def far_seek(control):
        class Superseded:                 # the user moves the slider once stepping has begun
            def check(self):
                control.check()

            def report(self, fraction, detail):
                if fraction > 0 and not newer:
                    newer.append(worker.submit(lambda: "the newer frame", "t = 0.1 s"))
                control.report(fraction, detail)

            def partial(self, frame):
                control.partial(frame)
        return render_animated(animation, t, settings, None, 0, Superseded())

    try:
        first = worker.submit(far_seek, "t = 2.9 s", control=True)
        result, seen = _collect(worker, first + 1)
    finally:
        worker.stop()
    assert result.frame == "the newer frame" and newer == [first + 1]
    assert first not in seen                          # the far seek handed over no picture
    assert 0 < world.step_index < target              # it stopped part of the way
    again = render_animated(animation, t, settings, None, 0)
    assert world.step_index == target
    fresh = render_at(_animation(), t, settings)
    assert np.array_equal(again.color, fresh.color)
    assert not np.array_equal(fresh.color, render_at(_animation(), 0.0, settings).color)
