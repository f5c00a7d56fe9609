"""core.animation.checkpoint: a particle system restored from a checkpoint steps on to exactly
the numbers of one that played from t = 0 (what lets a run of frames start on a worker
without simulating from the start)."""

from __future__ import annotations

import pickle

import numpy as np

from core.animation.checkpoint import restore, snapshot
from core.animation.keys import animation_of
from core.animation.particles import ARRAYS, ParticleSystem
from core.scene.formats import load_scene
from tests.conftest import ROOT


def test_a_restored_system_steps_on_to_the_played_numbers():
    animation = animation_of(load_scene(ROOT / "scenes" / "fireworks.toml"))
    played = animation.particle_system
    played.state_at(1.0)
    checkpoint = pickle.loads(pickle.dumps(snapshot(played)))     # as it travels to a worker
    played.state_at(1.7)
    specs = [played.specs[i] for i in played.roots]
    fresh = ParticleSystem(specs, played.fps, played.seed, played.substeps)
    fresh.state_at(0.3)                                             # somewhere else first
    restore(fresh, checkpoint)
    assert fresh.step_index == checkpoint.step_index and fresh.step_index > 0
    fresh.state_at(1.7)
    assert len(fresh.particles) == len(played.particles) > 100
    for name in ARRAYS:
        assert np.array_equal(getattr(fresh.particles, name), getattr(played.particles, name)), name
    # the snapshot is a copy: stepping on did not change it
    again = ParticleSystem(specs, played.fps, played.seed, played.substeps)
    again.state_at(1.0)
    assert all(np.array_equal(getattr(again.particles, n), getattr(checkpoint.particles, n))
               for n in ARRAYS)
