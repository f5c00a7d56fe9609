"""Simulations stepped in chunks (core.work.advance): the state at a time is bit for bit the
one stepped one step at a time, also when a watcher stops the stepping between two chunks
(Ctrl+C's line, the window's cancel) and it is asked for again."""

from __future__ import annotations

import numpy as np
import pytest

from core import work
from core.animation.keys import animation_of
from core.paths import SCENES_DIR
from core.scene.formats import load_scene


class Stop(Exception):
    pass


def simulation(scene: str, kind: str):
    animation = animation_of(load_scene(SCENES_DIR / scene, size=(32, 24)))
    if kind == "particles":
        return animation.particle_system
    return next(m for m in animation.movers if hasattr(m, "snapshot"))


def state(sim) -> list[np.ndarray]:
    """The arrays the simulation's future depends on, and its step."""
    if hasattr(sim, "particles"):                          # a particle system
        pool = sim.particles
        return [np.array(sim.step_index), pool.position.copy(), pool.velocity.copy(),
                pool.age.copy()]
    s = sim.snapshot()
    return [np.array(s.step_index)] + [np.array(a).copy() for a in vars(s).values()
                                       if isinstance(a, np.ndarray)]


CASES = [("blocks_falling.toml", "bodies", 1.3), ("flock.toml", "actors", 1.3),
         ("fountain.toml", "particles", 1.3)]


@pytest.mark.parametrize("scene, kind, t", CASES)
def test_chunked_and_stopped_stepping_gives_the_states_of_single_steps(monkeypatch, scene,
                                                                       kind, t):
    one_by_one = simulation(scene, kind)
    start = state(one_by_one)
    target = int(np.floor(t / one_by_one.dt + 1e-9))
    for _ in range(target):                                 # what state_at did before chunks
        one_by_one.step()
    expected = state(one_by_one)

    monkeypatch.setattr(work, "CHUNK_SECONDS", 1e-3)       # many chunks of a few steps
    chunked = simulation(scene, kind)
    reports = []

    def stop_at_the_fifth(what, done, total, unit):
        reports.append((what, done, total))
        if len(reports) == 5:
            raise Stop

    with pytest.raises(Stop), work.watching(stop_at_the_fifth):
        chunked.state_at(t)
    stopped_at = int(state(chunked)[0])
    assert 0 < stopped_at < target                          # stopped part of the way
    chunked.state_at(t)                                     # asked again: steps on from there
    got = state(chunked)
    assert int(got[0]) == target
    assert any(not np.array_equal(a, b) for a, b in zip(start[1:], expected[1:]))   # it moved
    assert len(got) == len(expected)
    for a, b in zip(got, expected):
        assert np.array_equal(a, b)
    assert [d for _, d, _ in reports] == sorted(d for _, d, _ in reports)
    assert {total for _, _, total in reports} == {target}
