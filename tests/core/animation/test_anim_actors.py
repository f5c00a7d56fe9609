"""Actors (core.animation.actors): a registered behaviour against the integrator's closed
form, boids that gather and align, planes that are avoided, paths that are followed."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from core.animation.actors import STEP, heading, loop_point, register_behaviour
from core.animation.keys import animation_of
from core.scene.formats import ReaderError, read_scene_file

BASE = """
name = "actors"
[[geometry]]
generator = "cube"
name = "bird"
transform = { scale = [0.1, 0.03, 0.05] }
[[view]]
vrp = [0, 2, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-4, 4, -4, 4]
prp = [0, 0, 12]
front = 6
back = -6
[animation]
duration = 10
fps = 30
seed = 3
[[actor]]
mesh = "bird"
"""


def group(text):
    scene = read_scene_file(text, "actors.toml")
    anim = animation_of(scene)
    return scene, anim, anim.movers[0]


def test_a_registered_behaviour_runs_at_the_step_with_the_integrators_closed_form():
    """Semi-implicit Euler under a constant a from rest: v_n = n a dt and
    x_n = a dt² n (n + 1) / 2."""
    register_behaviour("push east", lambda t, x, v, p: np.tile([p["a"], 0.0, 0.0], (len(x), 1)),
                       {"a": 1.0})
    _, _, g = group(BASE + 'behaviours = ["push east"]\nmax_speed = 1000\n["push east"]\na = 2.0\n'
                    .replace('["push east"]\na', '[actor."push east"]\na'))
    g.state_at(1.0)
    n = 120
    assert g.state.step_index == n and STEP == 1 / 120
    assert g.state.v[0, 0] == pytest.approx(n * 2.0 * STEP, rel=1e-12)
    assert g.state.x[0, 0] == pytest.approx(2.0 * STEP ** 2 * n * (n + 1) / 2, rel=1e-12)


def test_the_mesh_faces_along_its_velocity_and_stays_upright():
    for v in ([1, 0, 0], [0, 0, -2], [1, 1, 1], [-3, 0.5, 2]):
        r = heading(np.array(v, float))
        assert np.allclose(r @ [1, 0, 0], np.array(v) / np.linalg.norm(v))
        assert np.allclose(r @ r.T, np.eye(3)) and np.linalg.det(r) == pytest.approx(1.0)
        assert (r @ [0, 1, 0])[1] >= 0.0                          # up stays up


FLOCK = BASE + """count = 30
behaviours = ["flock"]
position = [0, 2, 0]
spread = 3
velocity = [1, 0, 0]
velocity_var = 1.5
[actor.flock]
center = [0, 2, 0]
"""


def polarisation(v):
    """|mean of the unit headings|: 1 when all fly one way, ~1/sqrt(N) when at random."""
    return np.linalg.norm((v / np.linalg.norm(v, axis=1, keepdims=True)).mean(axis=0))


def test_boids_gather_align_and_keep_apart():
    _, _, g = group(FLOCK)
    start_x, start_v = g.state.x.copy(), g.state.v.copy()
    g.state_at(8.0)
    x, v = g.state.x, g.state.v
    spread = lambda p: np.linalg.norm(p - p.mean(axis=0), axis=1).mean()
    assert polarisation(v) > 0.9 > polarisation(start_v)
    assert spread(x) < 0.7 * spread(start_x)
    d = np.linalg.norm(x[:, None] - x[None], axis=2) + np.eye(len(x)) * 1e9
    assert d.min() > 0.1                                        # separation: nobody collides


def test_avoided_planes_are_not_crossed():
    text = BASE + """count = 12
behaviours = ["avoid"]
position = [0, 3, 0]
spread = 0.5
velocity = [0.5, -2.5, 0]
max_speed = 2.5
[actor.avoid]
planes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]
distance = 1.5
"""
    _, _, g = group(text)
    low = np.inf
    for k in range(1, 400):
        g.state_at(k * STEP)
        low = min(low, g.state.x[:, 1].min())
    assert 0.0 < low < 1.5                                       # it came near, never through


def test_a_path_is_followed_and_a_restored_group_steps_on_to_the_same_numbers():
    path = [[2, 2, 0], [0, 2, 2], [-2, 2, 0], [0, 2, -2]]
    text = BASE + f"""behaviours = ["follow"]
position = [2, 2, 0]
max_speed = 50
[actor.follow]
path = {path}
period = 4.0
gain = 6.0
"""
    _, anim, g = group(text)
    g.state_at(4.0)
    state = pickle.loads(pickle.dumps(g.snapshot()))
    g.state_at(8.0)
    assert np.linalg.norm(g.state.x[0] - loop_point(np.array(path, float), 0.0)) < 0.05
    _, _, other = group(text)
    other.restore(state)
    other.state_at(8.0)
    assert np.array_equal(other.state.x, g.state.x) and np.array_equal(other.state.v, g.state.v)


def test_copies_of_the_mesh_are_drawn_one_per_actor():
    scene, anim, g = group(FLOCK)
    assert len(scene.meshes) == 30
    moved = anim.scene_at(2.0)
    centres = np.array([m.positions.mean(axis=0) for m in moved.meshes])
    assert np.allclose(centres, g.state_at(2.0).state.x, atol=1e-12)


@pytest.mark.parametrize("change,message", [
    ('behaviours = ["flock"]', 'behaviours = ["swarm"]', ),
    ("count = 30", "count = 1000000"),
    ("[actor.flock]\ncenter", "[actor.flock]\nradius = 0\ncenter"),
])
def test_bad_actors_get_one_clear_message(change, message):
    expected = {"swarm": "actor[1].behaviours[1]: 'swarm' is not one of",
                "1000000": "actor[1].count: 1000000 is out of range [1, 2000]",
                "radius = 0": "actor[1].flock.radius: radius must be greater than 0, got 0"}
    with pytest.raises(ReaderError) as error:
        group(FLOCK.replace(change, message))
    key = next(k for k in expected if k in message)
    assert expected[key] in str(error.value)


def test_a_short_path_and_parameters_of_an_unused_behaviour_are_refused():
    with pytest.raises(ReaderError) as error:
        group(BASE + 'behaviours = ["follow"]\n[actor.follow]\npath = [[0, 0, 0], [1, 0, 0]]\n')
    assert "actor[1].follow.path: a path needs at least 3 points" in str(error.value)
    with pytest.raises(ReaderError) as error:
        group(BASE + 'behaviours = ["flock"]\n[actor.avoid]\ndistance = 1\n')
    assert "actor[1].avoid: parameters for 'avoid', which is not in behaviours" in str(error.value)


def test_a_day_of_one_actor_is_refused_by_its_steps_before_it_runs():
    # 24 h at 1/120 s is 10,368,000 steps (~30 min here); at most 300,000
    text = BASE.replace("duration = 10", "duration = 86400") + 'behaviours = ["flock"]\n'
    with pytest.raises(ReaderError, match=r"actor\[1\]: 86400 s of actors is 10,368,000 steps "
                                          r"of 0.008333 s; at most 300,000"):
        read_scene_file(text, "actors.toml")


def test_two_thousand_flocking_actors_for_four_seconds_are_refused_by_their_work():
    # 480 steps x 2000² = 1.92e9 neighbour tests (~3 min here); at most 5e8
    text = BASE.replace("duration = 10", "duration = 4") + 'count = 2000\nbehaviours = ["flock"]\n'
    with pytest.raises(ReaderError, match=r"2,000 actors over 480 steps are 1.92e\+09 "
                                          r"neighbour tests; at most 5e\+08"):
        read_scene_file(text, "actors.toml")
