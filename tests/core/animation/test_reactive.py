"""Reactive control (core.animation.reactive): actors that sense and respond. Oracles: the
turning circle's closed form for an obstacle met head on, distances that must shrink (a
faster pursuer) or grow (a faster quarry), a field of view worked by hand."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from core.animation.actors import STEP, Senses, Stage
from core.animation.keys import animation_of
from core.paths import SCENES_DIR
from core.scene.formats import ReaderError, load_scene, read_scene_file

STILL = """
[[geometry]]
generator = "cube"
name = "a"
transform.scale = 0.1
[[geometry]]
generator = "cube"
name = "b"
transform.scale = 0.1
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-4, 4, -4, 4]
prp = [0, 0, 12]
front = 6
back = -6
[animation]
duration = 10
fps = 30
"""

HEAD_ON = STILL + """
[[actor]]
mesh = "a"
behaviours = ["avoid_obstacles"]
position = [0, 0, -6]
velocity = [0, 0, {s}]
max_speed = {s}
[actor.senses]
radius = {r}
fov = 180
[actor.avoid_obstacles]
spheres = [{{ center = [0, 0, 0], radius = {R} }}]
acceleration = {a}
clearance = {c}
"""


def stage(text) -> Stage:
    mover = animation_of(read_scene_file(text, "reactive.toml")).movers[0]
    assert isinstance(mover, Stage)
    return mover


@pytest.mark.parametrize("s, r, R, a, c", [
    (2.0, 1.5, 1.5, 4.0, 0.8),       # the circle's closest point inside the corridor
    (3.0, 2.0, 1.0, 6.0, 2.0),
    (1.0, 1.0, 1.0, 2.0, 1.0),
    (2.0, 1.5, 1.5, 4.0, 0.2),       # the turn stops at the corridor's edge, R + clearance
])
def test_an_actor_heading_at_an_obstacle_turns_away_by_the_closed_form(s, r, R, a, c):
    """Straight at the centre at speed s, the obstacle seen when its surface is r away
    (its centre D = r + R away), turning at a = s²/ρ across the heading: the circle of radius
    ρ from there passes the centre at √(ρ² + D²) − ρ, unless that is past the corridor
    R + clearance, where the turn stops. Within one step's travel, s·dt, and never inside."""
    mover = stage(HEAD_ON.format(s=s, r=r, R=R, a=a, c=c))
    actor = mover.groups[0]
    rho, d = s * s / a, r + R
    circle = math.sqrt(rho * rho + d * d) - rho
    expected = min(circle, R + c)
    # the circle's closest point is found to the step's travel; where the corridor stops the
    # turn, the last step's turn (a dt / s radians) swings the line past it by up to D times it
    tolerance = s * STEP + (0.0 if circle < R + c else d * a * STEP / s)
    closest, where = np.inf, None
    for k in range(1, int(8.0 / STEP)):
        mover.state_at(k * STEP)
        x = actor.state.x[0]
        if np.linalg.norm(x) < closest:
            closest, where = np.linalg.norm(x), x.copy()
        assert np.linalg.norm(actor.state.v[0]) == pytest.approx(s, rel=1e-12)   # no braking
        if x[2] < -d:
            assert x[0] == 0.0                          # straight until it sees the obstacle
    assert closest > R
    assert abs(closest - expected) <= tolerance, (closest, expected)
    assert where[0] < 0.0                               # to its right (heading +z, up +y)


def test_no_turn_while_the_obstacle_is_unseen_or_out_of_the_way():
    # seen only 0.5 from its surface: the same turn from D = 2 passes at √5 − 1 = 1.236 < 1.5
    mover = stage(HEAD_ON.format(s=2.0, r=0.5, R=1.5, a=4.0, c=0.8))
    closest = min(np.linalg.norm(mover.state_at(k * STEP).groups[0].state.x[0])
                  for k in range(1, 600))
    assert abs(closest - (math.sqrt(5.0) - 1.0)) <= 2.0 * STEP
    # a path that passes 2.5 from the centre, outside R + clearance = 2.3: never steered
    mover = stage(HEAD_ON.format(s=2.0, r=3.0, R=1.5, a=4.0, c=0.8)
                  .replace("position = [0, 0, -6]", "position = [2.5, 0, -6]"))
    mover.state_at(6.0)
    actor = mover.groups[0]
    assert np.array_equal(actor.state.v[0], [0.0, 0.0, 2.0]) and actor.state.x[0, 0] == 2.5


CHASE = STILL + """
[[actor]]
name = "hunter"
mesh = "a"
behaviours = ["pursue"]
position = [0, 0, 0]
max_speed = {hunter}
[actor.senses]
radius = 8
fov = 360
[actor.pursue]
target = "quarry"
[[actor]]
name = "quarry"
mesh = "b"
behaviours = [{quarry}]
position = [4, 0, 0]
velocity = [0, 0, 1]
max_speed = {speed}
steering = "priority"
[actor.senses]
radius = 6
fov = 360
[actor.wander]
speed = 1.0
turn = 0
"""


def distances(mover, times):
    out = []
    for t in times:
        mover.state_at(t)
        h, q = mover.groups
        out.append(float(np.linalg.norm(h.state.x[0] - q.state.x[0])))
    return np.array(out)


def test_a_pursuers_distance_to_its_target_shrinks():
    # the quarry walks straight on at 1 m/s (wander without turning); the hunter runs at 2
    mover = stage(CHASE.format(hunter=2.0, quarry='"wander"', speed=1.0))
    d = distances(mover, np.arange(0.0, 3.01, 0.25))
    assert np.all(np.diff(d[d > 0.3]) < 0.0) and d[0] == 4.0
    assert d[-1] < 0.3
    q = mover.groups[1]
    assert np.allclose(q.state.x[0], [4.0, 0.0, 3.0], atol=1e-9)       # straight, unsteered


def test_a_fleeing_actors_distance_grows():
    # the same hunter (1.5 m/s now) and a quarry that flees it at up to 2 m/s
    mover = stage(CHASE.format(hunter=1.5, quarry='"flee", "wander"', speed=2.0)
                  .replace("[actor.wander]", '[actor.flee]\nthreat = "hunter"\n[actor.wander]')
                  .replace("radius = 6\n", "radius = 20\n"))        # it sees the hunter throughout
    d = distances(mover, np.arange(0.0, 6.01, 0.25))
    assert np.all(np.diff(d) > 0.0), d
    assert d[-1] > 6.0


def test_the_senses_see_within_the_radius_and_the_field_of_view():
    senses = Senses(radius=2.0, fov=90.0)                     # 45 degrees either side
    x, v = np.zeros((1, 3)), np.array([[1.0, 0.0, 0.0]])
    a = math.radians(44.0)
    points = np.array([[1.9, 0, 0], [2.1, 0, 0], [math.cos(a), math.sin(a), 0],
                       [math.cos(a + 0.04), math.sin(a + 0.04), 0], [-1, 0, 0]])
    assert senses.see(x, v, points).tolist() == [[True, False, True, False, False]]
    # a sphere is seen by its surface; an actor at rest sees all round
    assert senses.see(x, v, np.array([[2.5, 0, 0]]), 0.6).tolist() == [[True]]
    assert senses.see(x, np.zeros((1, 3)), points).tolist() == [[True, False, True, True, True]]


def test_a_target_behind_a_narrow_view_is_not_pursued():
    text = CHASE.format(hunter=2.0, quarry='"wander"', speed=1.0).replace(
        "radius = 8\nfov = 360", "radius = 8\nfov = 90").replace(
        'position = [0, 0, 0]\nmax_speed', 'position = [0, 0, 0]\nvelocity = [-1, 0, 0]\n'
                                           'max_speed')
    mover = stage(text)
    mover.state_at(1.0)
    assert np.array_equal(mover.groups[0].state.v[0], [-1.0, 0.0, 0.0])     # unseen: no turn


def test_the_shipped_chase_restores_to_the_same_numbers_and_keeps_off_the_rocks():
    scene = load_scene(SCENES_DIR / "reactive_chase.toml")
    mover = animation_of(scene).movers[0]
    assert isinstance(mover, Stage) and [g.name for g in mover.groups] == ["fox", "rabbits"]
    fox, rabbits = mover.groups
    rocks = [p for _, p in fox.steps if "spheres" in p][0]["spheres"]
    assert len(rocks) == 4
    mover.state_at(3.0)
    saved = pickle.loads(pickle.dumps(mover.snapshot()))
    worst = np.inf
    for k in range(int(3.0 / STEP), int(6.0 / STEP), 4):
        mover.state_at(k * STEP)
        x = np.concatenate([g.state.x for g in mover.groups])
        assert np.abs(x[:, [0, 2]]).max() < 4.0                       # inside the fence
        for centre, radius in rocks:
            worst = min(worst, (np.linalg.norm((x - centre)[:, [0, 2]], axis=1) - radius).min())
    assert worst > 0.0
    other = animation_of(load_scene(SCENES_DIR / "reactive_chase.toml")).movers[0]
    other.restore(saved)
    other.state_at(6.0)
    mover.state_at(6.0)
    for a, b in zip(other.groups, mover.groups):
        assert np.array_equal(a.state.x, b.state.x) and np.array_equal(a.state.v, b.state.v)


@pytest.mark.parametrize("change, message", [
    ("radius = 8\n", "radius = 0\n"),
    ("radius = 8\n", "radius = inf\n"),
    ("radius = 8\n", "radius = 1e300\n"),
    ("radius = 8\n", "radius = nan\n"),
    ("fov = 360\n[actor.pursue]", "fov = 0\n[actor.pursue]"),
    ("fov = 360\n[actor.pursue]", "fov = 400\n[actor.pursue]"),
    ('target = "quarry"', 'target = "prey"'),
    ("[actor.senses]\nradius = 8\nfov = 360\n", ""),
])
def test_bad_senses_and_names_get_one_clear_message(change, message):
    expected = {
        "radius = 0": "actor[1].senses.radius: a sensing radius must be greater than 0 (an "
                      "actor that senses nothing cannot react), got 0",
        "radius = inf": "actor[1].senses.radius: a sensing radius is finite (at most 1e+06: an "
                        "actor senses what is near it), got inf",
        "radius = 1e300": "actor[1].senses.radius: a sensing radius is finite (at most 1e+06: "
                          "an actor senses what is near it), got 1e+300",
        "radius = nan": "actor[1].senses.radius: expected a finite number, got nan",
        "fov = 0": "actor[1].senses.fov: the field of view is the whole angle of a cone about "
                   "the heading, in (0, 360] degrees, got 0",
        "fov = 400": "actor[1].senses.fov: the field of view is the whole angle of a cone "
                     "about the heading, in (0, 360] degrees, got 400",
        "prey": "actor[1].pursue.target: no actor group is named 'prey' (groups: 'hunter', "
                "'quarry')",
        "": "actor[1]: 'pursue' reacts to what the actors sense: give [actor.senses] radius = R "
            "(and fov = DEGREES)",
    }
    text = CHASE.format(hunter=2.0, quarry='"wander"', speed=1.0)
    assert change in text
    with pytest.raises(ReaderError) as error:
        read_scene_file(text.replace(change, message, 1), "reactive.toml")
    key = next(k for k in expected if k and k in message) if message else ""
    assert expected[key] in str(error.value) and "\n" not in str(error.value)


def test_an_unknown_obstacle_and_a_missing_target_are_refused():
    with pytest.raises(ReaderError, match=r"actor\[1\]\.avoid_obstacles\.obstacles\[1\]: no "
                                          r"geometry is named 'rock'"):
        read_scene_file(HEAD_ON.format(s=2, r=1, R=1, a=4, c=0.2).replace(
            "acceleration", 'obstacles = ["rock"]\nacceleration'), "reactive.toml")
    with pytest.raises(ReaderError, match=r"actor\[1\]\.pursue: pursue needs target = \"NAME\""):
        read_scene_file(CHASE.format(hunter=2.0, quarry='"wander"', speed=1.0)
                        .replace('target = "quarry"', "prediction = 1"), "reactive.toml")
