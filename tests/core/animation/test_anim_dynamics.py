"""Rigid bodies (core.animation.dynamics) against closed forms: free fall, bounces, energy,
rolling, collisions; checkpoints; the scene file's bad input."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from core.animation.dynamics import mass_properties
from core.animation.keys import animation_of
from core.scene.formats import ReaderError, read_scene_file
from core.scene.generators import cube

VIEW = """
[[view]]
vrp = [0, 0.5, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-1.5, 1.5, -1.5, 1.5]
prp = [0, 0, 6]
front = 3
back = -3
"""

BALL = """
name = "drop"
[[geometry]]
primitive = "sphere"
name = "ball"
center = [0, 1, 0]
radius = 0.1
""" + VIEW + """
[animation]
duration = 3
fps = 30
[dynamics]
planes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]
[[body]]
mesh = "ball"
mass = 1.5
restitution = 0.8
friction = 0.0
"""

G = 9.8


def world(text=BALL, name="test.toml"):
    scene = read_scene_file(text, name)
    return animation_of(scene).movers[0]


def test_a_box_has_the_closed_form_volume_centre_and_inertia():
    mesh = cube(2.0)
    positions = mesh.positions * [0.2, 0.4, 0.6] + [1.0, -2.0, 3.0]     # sides 0.4, 0.8, 1.2
    volume, centre, inertia = mass_properties(positions, mesh.triangles)
    assert volume == pytest.approx(0.4 * 0.8 * 1.2, rel=1e-12)
    assert np.allclose(centre, [1, -2, 3], atol=1e-12)
    a, b, c = 0.4, 0.8, 1.2
    assert np.allclose(inertia, np.diag([b * b + c * c, a * a + c * c, a * a + b * b]) * volume / 12,
                       atol=1e-12)


def test_a_dropped_sphere_follows_h0_minus_g_t2_over_2_until_contact_then_bounces_at_e_v():
    """Velocity Verlet under constant gravity is the parabola itself (its error term, the
    third derivative of x, is zero): every step before the contact is the closed form to
    rounding, and after the contact at t_c = sqrt(2 (h0 - r) / g), solved inside the step,
    the ball climbs from the plane at e times the impact speed."""
    w = world()
    dt, h0, r, e = w.dt, 1.0, 0.1, 0.8
    t_c = math.sqrt(2 * (h0 - r) / G)
    impact = G * t_c
    k = 0
    while (k + 1) * dt < t_c:
        w.step()
        k += 1
        t = k * dt
        assert w.x[0, 1] == pytest.approx(h0 - G * t * t / 2, abs=1e-12)
        assert w.v[0, 1] == pytest.approx(-G * t, abs=1e-12)
    assert k == 102                                 # t_c = 0.4286 s = 102.9 steps of 1/240 s
    for _ in range(20):                                         # up again, after the bounce
        w.step()
        k += 1
        s = k * dt - t_c
        assert w.x[0, 1] == pytest.approx(r + e * impact * s - G * s * s / 2, abs=1e-12)


def test_bounce_heights_fall_by_e_squared():
    w = world()
    apexes = []                      # the height the ball climbs to after each bounce
    climbing = False
    for _ in range(3 * 240):
        before = w.v[0, 1]
        w.step()
        if before < 0 <= w.v[0, 1] or (before < 0 and w.v[0, 1] > 0):
            climbing = True
            apexes.append(w.x[0, 1] - 0.1 + w.v[0, 1] ** 2 / (2 * G))    # energy in flight
    assert climbing and len(apexes) >= 4
    assert apexes[0] == pytest.approx(0.9 * 0.64, rel=1e-9)
    ratios = np.array(apexes[1:4]) / np.array(apexes[:3])
    assert np.allclose(ratios, 0.64, rtol=1e-9), ratios


TUMBLER = """
name = "tumbler"
[[geometry]]
generator = "cube"
name = "box"
transform = { scale = [0.2, 0.4, 0.6], translate = [0, 5, 0] }
""" + VIEW + """
[animation]
duration = 50
fps = 30
[[body]]
mesh = "box"
mass = 2.0
velocity = [1, 3, 0]
spin = [30, 400, 20]
"""


def test_free_flight_keeps_momenta_and_energy_over_10000_steps():
    """No collisions: the linear and angular momenta are conserved (gravity aside) and the
    energy drifts less than the stated bound, 1e-4 of the rotational energy, over 10,000
    steps of 1/240 s of a box tumbling about its unstable middle axis (measured: 1.2e-5)."""
    w = world(TUMBLER)
    L0 = w.L.copy()
    e0 = w.energy()
    rotational = 0.5 * w.L[0] @ np.linalg.solve(w.bodies[0].inertia, w.L[0])
    for _ in range(10_000):
        w.step()
    t = 10_000 * w.dt
    assert np.allclose(w.v[0], [1, 3 - G * t, 0], rtol=0, atol=1e-9)
    assert np.allclose(w.x[0], [t, 5 + 3 * t - G * t * t / 2, 0], rtol=1e-12, atol=1e-9)
    assert np.array_equal(w.L, L0)                   # no torque: L is never touched
    assert abs(w.energy() - e0) < 1e-4 * rotational
    r = w.rotations()[0]
    assert np.allclose(r @ r.T, np.eye(3), atol=1e-12)


SLIDER = BALL.replace("center = [0, 1, 0]", "center = [0, 0.1, 0]").replace(
    "friction = 0.0", "friction = 0.2\nvelocity = [2, 0, 0]")


def test_a_sliding_ball_rolls_at_five_sevenths_of_its_speed():
    """A solid sphere thrown sliding without spin: kinetic friction μ m g slows it and spins
    it up until it rolls, at v = 5/7 v0 (angular momentum about the contact point is
    conserved), after t = 2 v0 / (7 μ g)."""
    w = world(SLIDER)
    for _ in range(240):
        w.step()
    v = w.v[0]
    assert v[0] == pytest.approx(2 * 5 / 7, rel=1e-9)
    assert abs(v[1]) < 1e-12 and abs(w.x[0, 1] - 0.1) < 1e-3
    omega = np.linalg.solve(w.bodies[0].inertia, w.L[0])
    assert omega[2] == pytest.approx(-v[0] / 0.1, rel=1e-9)        # rolling: v = -ω_z r


PAIR = """
name = "pair"
[[geometry]]
primitive = "sphere"
name = "a"
center = [-1, 0, 0]
radius = 0.2
[[geometry]]
primitive = "sphere"
name = "b"
center = [1, 0, 0]
radius = 0.2
""" + VIEW + """
[animation]
duration = 2
fps = 30
[dynamics]
gravity = [0, 0, 0]
[[body]]
mesh = "a"
mass = 1.0
velocity = [2, 0, 0]
restitution = RA
friction = 0
[[body]]
mesh = "b"
mass = 3.0
velocity = [-1, 0, 0]
restitution = RB
friction = 0
"""


@pytest.mark.parametrize("e", [1.0, 0.25])
def test_a_head_on_collision_keeps_momentum_and_separates_at_e_times_the_closing_speed(e):
    w = world(PAIR.replace("RA", str(e)).replace("RB", str(e)))
    for _ in range(240):
        w.step()
    m1, m2, v1, v2 = 1.0, 3.0, 2.0, -1.0
    after1 = (m1 * v1 + m2 * v2 + m2 * e * (v2 - v1)) / (m1 + m2)
    after2 = (m1 * v1 + m2 * v2 + m1 * e * (v1 - v2)) / (m1 + m2)
    assert w.v[0, 0] == pytest.approx(after1, abs=1e-12)
    assert w.v[1, 0] == pytest.approx(after2, abs=1e-12)
    assert w.x[1, 0] - w.x[0, 0] > 0.4                               # apart again


def test_the_frame_rate_does_not_change_the_motion():
    """The step is fixed in seconds: at 30 and at 24 fps the ball is where it is."""
    a = world(BALL)
    b = world(BALL.replace("fps = 30", "fps = 24"))
    assert np.array_equal(a.matrices_at(1.25)[0], b.matrices_at(1.25)[0])
    assert not np.array_equal(a.matrices_at(1.0)[0], a.matrices_at(1.25)[0])


def test_a_restored_world_steps_on_to_the_played_numbers():
    played = world(TUMBLER.replace("[[body]]", "[dynamics]\nplanes = [{ point = [0, 0, 0] }]\n[[body]]"))
    played.state_at(1.0)
    state = pickle.loads(pickle.dumps(played.snapshot()))
    played.state_at(3.0)
    fresh = world(TUMBLER.replace("[[body]]", "[dynamics]\nplanes = [{ point = [0, 0, 0] }]\n[[body]]"))
    fresh.restore(state)
    fresh.state_at(3.0)
    for name in ("x", "v", "q", "L"):
        assert np.array_equal(getattr(fresh, name), getattr(played, name))
    assert played.x[0, 1] < 1.0                       # it has fallen onto the floor by then


def test_the_body_moves_its_mesh_in_the_scene():
    scene = read_scene_file(BALL, "drop.toml")
    anim = animation_of(scene)
    t = 0.3
    moved = anim.scene_at(t)
    drop = 1.0 - G * (math.floor(t * 240 + 1e-9) / 240) ** 2 / 2
    assert np.allclose(moved.meshes[0].positions, scene.meshes[0].positions + [0, drop - 1, 0],
                       atol=1e-9)
    assert moved.primitives[0].center == pytest.approx((0, drop, 0), abs=1e-9)


@pytest.mark.parametrize("change,message", [
    (("mass = 1.5", "mass = 0"), "test.toml:25: body[1].mass: a body's mass must be at least 1e-09, got 0"),
    (("mass = 1.5", "mass = -2"), "body[1].mass: a body's mass must be at least 1e-09, got -2"),
    (("mass = 1.5", "mass = 5e-324"), "body[1].mass: a body's mass must be at least 1e-09, got 4.94066e-324"),
    (("[dynamics]", "[dynamics]\nstep = 0"), "dynamics.step: the time step must be a positive number of seconds, got 0"),
    (("[dynamics]", "[dynamics]\nstep = 1e9"), "dynamics.step: a step of 1e+09 s is longer than a frame (1/fps = 0.0333333 s)"),
    (("[dynamics]", "[dynamics]\nstep = 1e-9"), "dynamics.step: a step of 1e-09 s is below 1e-05 s"),
    (("center = [0, 1, 0]", "center = [0, 0.05, 0]"), "body[1]: 'ball' starts through plane 1 of [dynamics] planes"),
    (('mesh = "ball"', 'mesh = "bal"'), "body[1].mesh: no geometry is named 'bal' (names: ball)"),
    (("normal = [0, 1, 0] }", "normal = [0, 0, 0] }"), "dynamics.planes[1].normal: the plane's normal is the zero vector"),
    (("[animation]\nduration = 3\nfps = 30\n", ""), "body: rigid bodies need an [animation] table"),
    (("duration = 3", "duration = 90000"), "animation.duration: 90000 is out of range"),
    (("duration = 3", "duration = 80000"), "dynamics.step: duration / step = 19,200,000 steps; at most 10,000,000"),
])
def test_bad_bodies_get_one_clear_message(change, message):
    with pytest.raises(ReaderError) as error:
        world(BALL.replace(*change))
    assert message in str(error.value)


def test_interpenetrating_bodies_and_a_million_bodies_are_refused():
    overlapping = PAIR.replace("RA", "1").replace("RB", "1").replace("center = [1, 0, 0]",
                                                                      "center = [-0.7, 0, 0]")
    with pytest.raises(ReaderError) as error:
        world(overlapping)
    assert "body[2]: 'b' starts inside 'a' (their bounding spheres overlap by 0.1)" in str(error.value)
    for count, message in ((1001, "body: 1,001 bodies; at most 1,000 (every pair of bodies is tested"),
                           (10 ** 6, "TOML: 3000032 keys and tables; a scene may have at most 1000000")):
        many = BALL.split("[[body]]")[0] + '[[body]]\nmesh = "ball"\n' * count
        with pytest.raises(ReaderError) as error:
            world(many)
        assert message in str(error.value)


def test_an_open_mesh_and_a_keyed_mesh_cannot_be_bodies():
    open_box = TUMBLER.replace('generator = "cube"', 'generator = "plane"')
    with pytest.raises(ReaderError) as error:
        world(open_box)
    assert "body[1].mesh: 'box' is not a closed mesh" in str(error.value)
    keyed = TUMBLER + '[[key]]\ntime = 0\nobject.box = { translate = [0, 0, 0] }\n'
    with pytest.raises(ReaderError) as error:
        world(keyed)
    assert "'box' is keyed ([[key]] object.box) and a body" in str(error.value)


@pytest.fixture
def on_the_cluster(monkeypatch):
    """A short job on --workers 2 would be kept in this process (a cluster cannot win);
    this test wants frames rendered by the local cluster's worker from checkpoints."""
    import app.commands.animate_frames as animate_frames
    monkeypatch.setattr(animate_frames, "CLUSTER_START_SECONDS", 0.0)
    monkeypatch.setattr(animate_frames, "idle_cores", lambda since: 8.0)
    monkeypatch.setattr(animate_frames, "RENDER_WHILE_STARTING", False)


def test_one_and_two_workers_give_the_same_frames_byte_for_byte(tmp_path, on_the_cluster, capsys):
    """The shipped blocks falling, motion-blurred (two samples a frame, so each run's
    checkpoint is taken at its first frame's first sample): the worker steps on from the
    checkpoints it is sent, this process from t = 0, and every PNG is the same file."""
    from tools import need_module

    from app.cli import main
    from core.paths import ROOT
    need_module("distributed", "the animate extra runs frames on Dask workers")
    scene = str(ROOT / "scenes" / "blocks_falling.toml")
    common = ["--size", "48x36", "--frames", "40", "--motion-blur", "2"]
    assert main(["animate", scene, "--out", str(tmp_path / "one")] + common) == 0
    assert main(["animate", scene, "--out", str(tmp_path / "two"), "--workers", "2"] + common) == 0
    assert "this process and 1 local worker" in capsys.readouterr().out
    one = sorted((tmp_path / "one").glob("frame_*.png"))
    two = sorted((tmp_path / "two").glob("frame_*.png"))
    assert len(one) == len(two) == 40
    assert all(a.read_bytes() == b.read_bytes() for a, b in zip(one, two))
    assert one[0].read_bytes() != one[-1].read_bytes()             # and the blocks did fall


def test_a_box_dropped_on_a_box_comes_to_rest_on_its_top_face():
    """Two convex hulls: the small box lands on the big one (turned 30° to it, so no corner
    of either is inside the other: edge on edge) and rests with its bottom on the big top."""
    text = TUMBLER.split("[[geometry]]")[0] + """
[[geometry]]
generator = "cube"
name = "base"
transform = { scale = [0.4, 0.2, 0.4], translate = [0, 0.2, 0] }
[[geometry]]
generator = "cube"
name = "top"
transform = { scale = [0.3, 0.1, 0.3], rotate = [0, 30, 0], translate = [0, 0.9, 0] }
""" + VIEW + """
[animation]
duration = 3
fps = 30
[dynamics]
planes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]
[[body]]
mesh = "base"
restitution = 0.1
friction = 0.6
[[body]]
mesh = "top"
restitution = 0.1
friction = 0.6
"""
    w = world(text)
    assert [len(b.faces) for b in w.bodies] == [6, 6]
    w.state_at(2.0)
    assert w.x[0, 1] == pytest.approx(0.2, abs=2e-3)
    assert w.x[1, 1] == pytest.approx(0.5, abs=2e-3)             # 0.4 + its half height 0.1
    assert np.linalg.norm(w.x[1, [0, 2]]) < 0.05


def test_only_a_convex_mesh_gets_face_planes():
    from core.animation.dynamics import face_planes
    from core.scene.generators import torus
    box = cube(2.0)
    assert len(face_planes(box.positions, box.positions, box.triangles)) == 6
    ring = torus(1.0, 0.3, 16, 8)
    assert len(face_planes(ring.positions, ring.positions, ring.triangles)) == 0


def test_three_hundred_bodies_for_three_seconds_are_refused_by_their_work():
    # 720 steps x (44,850 pairs + 300 x 1 sphere tests + hull points) x 17 passes: past 3e8
    # (~200 ns a unit here: over a minute), said before a step is taken
    balls = "".join(f'[[geometry]]\nprimitive = "sphere"\nname = "b{k}"\ncenter = '
                    f'[{(k % 20) * 0.3 - 3:.2f}, {1 + (k // 20) * 0.3:.2f}, 0]\nradius = 0.1\n'
                    f'segments = 8\n' for k in range(300))
    bodies = "".join(f'[[body]]\nmesh = "b{k}"\n' for k in range(300))
    text = ("name = \"many\"\n" + balls + VIEW + "[animation]\nduration = 3\nfps = 30\n"
            "[dynamics]\nplanes = [{ point = [0, 0, 0], normal = [0, 1, 0] }]\n" + bodies)
    with pytest.raises(ReaderError, match=r"300 bodies over 720 steps are .* contact tests; "
                                          r"at most 3e\+08"):
        read_scene_file(text, "many.toml")
