"""Going back in a simulation (core.animation.rewind): from the nearest snapshot at or before
the moment, to exactly the numbers of a simulation that never went back."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from core.animation.keys import animation_of
from core.animation.rewind import Rewind
from core.scene.formats import load_scene

SCENES = Path(__file__).resolve().parents[3] / "scenes"


def test_snapshots_every_so_many_steps_and_thinned_past_the_most():
    rewind = Rewind(every=10, most=4)
    for k in range(0, 45):
        rewind.note(k, lambda k=k: f"state {k}")
    # 0, 10, 20, 30 kept; at 40 a fifth: every other dropped, the spacing doubles
    assert rewind.every == 20 and sorted(rewind.kept) == [0, 20, 40]
    assert rewind.nearest(39) == "state 20" and rewind.nearest(40) == "state 40"
    assert Rewind().nearest(100) is None


def _world():
    (world,) = animation_of(load_scene(SCENES / "blocks_falling.toml")).movers
    return world


def test_rigid_bodies_go_back_from_the_nearest_snapshot_to_the_same_numbers():
    world = _world()
    world.state_at(2.1)                       # 504 steps: snapshots at 0, 240, 480
    assert sorted(world.rewind.kept) == [0, 240, 480]
    stepped = []
    real_step = world.step
    world.step = lambda *scratch: stepped.append(1) or real_step(*scratch)
    world.state_at(1.5)                       # step 360: from the snapshot at 240
    assert len(stepped) == 360 - 240
    fresh = _world()
    fresh.state_at(1.5)
    for name in ("x", "v", "q", "L"):
        assert np.array_equal(getattr(world, name), getattr(fresh, name)), name
    assert world.step_index == fresh.step_index == 360


def test_particles_go_back_from_the_nearest_snapshot_to_the_same_particles():
    def system():
        return animation_of(load_scene(SCENES / "fountain.toml")).particle_system
    played = system()
    played.state_at(2.5)
    assert max(played.rewind.kept) > 0
    played.state_at(2.2)
    fresh = system()
    fresh.state_at(2.2)
    assert played.step_index == fresh.step_index
    assert np.array_equal(played.particles.position, fresh.particles.position)


def test_a_played_movie_shows_the_pictures_of_one_simulated_afresh_for_each_moment():
    # one world carried from frame to frame (and back, through a snapshot) against a world
    # made new for each moment and stepped from 0
    from core.animation.frames import render_at
    from core.settings import RenderSettings
    scene = load_scene(SCENES / "blocks_falling.toml", size=(64, 48))
    played = animation_of(scene)
    settings = RenderSettings.for_scene(scene, size=(64, 48))
    for t in (0.4, 1.1, 1.9, 2.6, 1.3):              # the last one back in time
        ours = render_at(played, t, settings, view_index=0).color
        afresh = render_at(animation_of(load_scene(SCENES / "blocks_falling.toml",
                                                   size=(64, 48))), t, settings,
                           view_index=0).color
        assert np.array_equal(ours, afresh), t
        assert len(np.unique(ours.reshape(-1, 3), axis=0)) > 20
