"""Inverse dynamics (core.animation.inverse_dynamics): Newton–Euler's torques against closed
forms worked by hand — a pendulum, the two-link arm of Spong, Hutchinson and Vidyasagar, a
chain holding a load still — a keyed motion's torques frame by frame, and bad input."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from core.animation.inverse_dynamics import LinkMasses, joint_torques, torques_at
from core.animation.keys import animation_of
from core.animation.linkage import Linkage
from core.scene.formats import ReaderError, read_scene_file

G = 9.81
ROOT = Path(__file__).resolve().parents[3]


def chain(bones, axes=None):
    """A serial chain from the origin: joint j turns about axes[j] (default z)."""
    n = len(bones)
    axes = [[0, 0, 1]] * n if axes is None else axes
    return Linkage("chain", [0, 0, 0], list(range(-1, n - 1)), axes, bones, [-9] * n, [9] * n,
                   [[] for _ in range(n)], n - 1)


def point_masses(masses, bones, load=0.0):
    """Each link's mass at the far end of its bone, no inertia of its own."""
    return LinkMasses(np.array(masses, float), np.array(bones, float), np.zeros((len(masses), 3, 3)),
                      load, np.array([0.0, -G, 0.0]))


def rods(masses, bones):
    """Uniform thin rods: the centre mid-bone, m L²/12 about it across the bone."""
    bones = np.array(bones, float)
    inertia = [m * (b @ b) / 12 * (np.eye(3) - np.outer(b, b) / (b @ b)) for m, b in zip(masses, bones)]
    return LinkMasses(np.array(masses, float), bones / 2, np.array(inertia), 0.0,
                      np.array([0.0, -G, 0.0]))


def test_a_pendulum_needs_m_l2_theta_ddot_plus_m_g_l_sin_theta():
    m, l = 1.7, 0.9
    bones = [[0.0, -l, 0.0]]                      # hanging down: θ from the downward vertical
    linkage, masses = chain(bones), point_masses([m], bones)
    rng = np.random.default_rng(1)
    for theta, rate, acc in rng.uniform([-3, -5, -20], [3, 5, 20], (50, 3)):
        tau = joint_torques(linkage, masses, [theta], [rate], [acc])
        assert tau[0] == pytest.approx(m * l * l * acc + m * G * l * math.sin(theta), abs=1e-12)


def spong_two_link(m, l, lc, inertia, q, dq, ddq):
    """Spong, Hutchinson and Vidyasagar, *Robot Modeling and Control*, the planar elbow
    manipulator: angles from the horizontal (q2 relative to link 1), gravity along −y."""
    c2, s2 = math.cos(q[1]), math.sin(q[1])
    d11 = (m[0] * lc[0] ** 2 + m[1] * (l[0] ** 2 + lc[1] ** 2 + 2 * l[0] * lc[1] * c2)
           + inertia[0] + inertia[1])
    d12 = m[1] * (lc[1] ** 2 + l[0] * lc[1] * c2) + inertia[1]
    d22 = m[1] * lc[1] ** 2 + inertia[1]
    h = -m[1] * l[0] * lc[1] * s2
    phi2 = m[1] * lc[1] * G * math.cos(q[0] + q[1])
    phi1 = (m[0] * lc[0] + m[1] * l[0]) * G * math.cos(q[0]) + phi2
    return (d11 * ddq[0] + d12 * ddq[1] + h * (2 * dq[0] * dq[1] + dq[1] ** 2) + phi1,
            d12 * ddq[0] + d22 * ddq[1] - h * dq[0] ** 2 + phi2)


@pytest.mark.parametrize("kind", ["point masses", "rods"])
def test_a_double_pendulum_matches_the_textbook_two_link_arm(kind):
    m, l = (2.0, 0.8), (1.1, 0.7)
    bones = [[l[0], 0, 0], [l[1], 0, 0]]
    if kind == "rods":
        masses, lc, inertia = rods(m, bones), (l[0] / 2, l[1] / 2), [mi * li * li / 12 for mi, li in zip(m, l)]
    else:
        masses, lc, inertia = point_masses(m, bones), l, (0.0, 0.0)
    linkage = chain(bones)
    rng = np.random.default_rng(2)
    for state in rng.uniform(-4, 4, (40, 6)):
        q, dq, ddq = state[:2], state[2:4], state[4:]
        tau = joint_torques(linkage, masses, q, dq, ddq)
        np.testing.assert_allclose(tau, spong_two_link(m, l, lc, inertia, q, dq, ddq),
                                   rtol=0, atol=1e-11)


def test_a_chain_holding_a_load_still_needs_the_weights_times_their_horizontal_lever_arms():
    bones = [[1.0, 0.2, 0], [0.6, 0, 0], [0.5, -0.3, 0]]
    m, load = [1.5, 0.8, 0.4], 2.5
    theta = np.radians([35.0, -70.0, 50.0])
    linkage = chain(bones)
    masses = rods(m, bones)
    masses.load = load
    tau = joint_torques(linkage, masses, theta, np.zeros(3), np.zeros(3))
    # by hand: the joints' and centres' x in the posed chain, angles summed along it
    x, angle, joints, centres = 0.0, 0.0, [], []
    for (bx, by, _), th in zip(bones, theta):
        angle += th
        c, s = math.cos(angle), math.sin(angle)
        joints.append(x)
        centres.append(x + (c * bx - s * by) / 2)
        x += c * bx - s * by
    weights = [(mi, xc) for mi, xc in zip(m, centres)] + [(load, x)]
    for j in range(3):
        outboard = weights[j:3] + [weights[3]]
        expected = sum(mi * G * (xc - joints[j]) for mi, xc in outboard)
        assert tau[j] == pytest.approx(expected, abs=1e-12)


# The scenes below: one cube named {name}, seen along -z.
CUBE_AND_VIEW = """
[[geometry]]
generator = "cube"
name = "{name}"
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 5]
front = 2
back = -2
"""

PENDULUM = CUBE_AND_VIEW.format(name="bob") + """[animation]
duration = 4
fps = 10
[[linkage]]
gravity = [0, -9.81, 0]
interpolation = "{method}"
[[linkage.joint]]
name = "swing"
bone = [0, -0.9, 0]
mass = 1.7
center = [0, -0.9, 0]
inertia = 0
meshes = ["bob"]
[[linkage.key]]
time = 0
angles = {{ swing = 0 }}
[[linkage.key]]
time = 2
angles = {{ swing = 60 }}
[[linkage.key]]
time = 4
angles = {{ swing = -20 }}
"""


def pendulum(method="ease", text=PENDULUM):
    scene = read_scene_file(text.format(method=method), "pendulum.toml")
    return animation_of(scene).movers[0]


def ease(t):
    """The ease keys' θ and θ'' by hand: θ0 + Δ(1 − cos πu)/2 on each 2 s interval."""
    (a, b), u = ((0.0, 60.0), t / 2) if t < 2 else ((60.0, -20.0), (t - 2) / 2)
    delta = math.radians(b - a)
    return (math.radians(a) + delta * (1 - math.cos(math.pi * u)) / 2,
            delta * (math.pi / 2) ** 2 / 2 * math.cos(math.pi * u))


def test_a_keyed_pendulum_swing_needs_the_closed_form_torque_at_every_frame():
    linkage = pendulum()
    m, l = 1.7, 0.9
    for k in range(41):                           # the frames, the keys at 0, 2 and 4 s among them
        t = k / 10
        theta, d1, d2, tau = torques_at(linkage, linkage.masses, t, linkage.key_times)
        angle, acc = ease(t)
        assert theta[0] == pytest.approx(angle, abs=1e-12)
        assert d2[0] == pytest.approx(acc, abs=1e-5)          # finite differences, h = 1 ms
        assert tau[0] == pytest.approx(m * l * l * acc + m * G * l * math.sin(angle), abs=1e-5)


def test_after_a_key_the_torque_is_the_next_intervals():
    """Catmull–Rom's θ'' jumps at a key: the frame at the key takes the interval after it."""
    from core.animation.inverse_dynamics import motion_at
    linkage = pendulum("catmull-rom", PENDULUM.replace("time = 2", "time = 1"))   # uneven keys
    at = motion_at(linkage, 1.0, linkage.key_times)[2][0]
    after = motion_at(linkage, 1.0 + 1e-2, linkage.key_times)[2][0]
    before = motion_at(linkage, 1.0 - 1e-2, linkage.key_times)[2][0]
    assert abs(after - before) > 1.0                          # a real jump here ...
    assert at == pytest.approx(after, abs=0.05 * abs(after - before))   # ... and the right side


def test_a_keyed_corner_is_refused_naming_the_file_and_the_key_line():
    text = PENDULUM.format(method="linear")
    with pytest.raises(ReaderError) as error:
        read_scene_file(text, "pendulum.toml")
    line = text.splitlines().index("time = 2") + 1 - 1          # the [[linkage.key]] header
    message = str(error.value)
    assert message.startswith(f"pendulum.toml:{line}: linkage[1].key[2]: the keyed motion turns "
                              "a corner at t = 2 s")
    assert "no finite torque" in message and "'swing'" in message
    assert len(message.splitlines()) == 1
    kinematic = text.replace("mass = 1.7\n", "")                 # no masses: only kinematics
    assert animation_of(read_scene_file(kinematic, "pendulum.toml")).movers[0].masses is None


@pytest.mark.parametrize("change, reason", [
    ("swing = 60", "swing = nan"), ("mass = 1.7", "mass = nan"), ("mass = 1.7", "mass = -1"),
    ("inertia = 0", "inertia = [[1, 2, 0], [0, 1, 0], [0, 0, 1]]"),
])
def test_bad_dynamics_keys_give_one_line_with_the_file_and_line(change, reason):
    text = PENDULUM.format(method="ease").replace(change, reason)
    with pytest.raises(ReaderError) as error:
        read_scene_file(text, "pendulum.toml")
    line = next(i + 1 for i, row in enumerate(text.splitlines()) if reason in row)
    assert str(error.value).startswith(f"pendulum.toml:{line}: linkage[1]")
    assert len(str(error.value).splitlines()) == 1


def test_the_torques_command_prints_the_static_holding_torque(tmp_path):
    held = PENDULUM.format(method="catmull-rom").replace("swing = 60", "swing = 30") \
        .replace("swing = 0", "swing = 30").replace("swing = -20", "swing = 30")
    scene = tmp_path / "held.toml"
    scene.write_text(held)
    out = tmp_path / "held.csv"
    done = subprocess.run([sys.executable, "-m", "app", "torques", str(scene), "--fps", "2",
                           "--csv", str(out)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    rows = [line.split(",") for line in out.read_text().splitlines()[1:]]
    assert len(rows) == 9                                       # 0, 0.5, ... 4 s
    for row in rows:
        assert float(row[-1]) == pytest.approx(1.7 * G * 0.9 * math.sin(math.radians(30)), abs=1e-9)
    assert f"{1.7 * G * 0.9 * 0.5:.4f}" in done.stdout
    lost = subprocess.run([sys.executable, "-m", "app", "torques", str(scene), "--csv",
                           str(tmp_path / "no" / "t.csv")], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert lost.returncode == 2 and lost.stderr.count("\n") == 1 and "does not exist" in lost.stderr
    none = subprocess.run([sys.executable, "-m", "app", "torques", str(ROOT / "scenes/robot_arm.toml")],
                          cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert none.returncode == 2 and "no linkage with masses" in none.stderr


POINTER = CUBE_AND_VIEW.format(name="rod") + """[animation]
duration = 2
fps = 10
[[linkage]]
interpolation = "linear"
[[linkage.joint]]
name = "pointer"
bone = [1, 0, 0]
mass = 1.0
meshes = ["rod"]
[[linkage.key]]
time = 0
target = [1, {y}, 0]
[[linkage.key]]
time = 2
target = [-1, {y}, 0]
"""


def test_an_inverse_kinematics_jump_is_refused_and_a_smooth_pass_is_not(tmp_path):
    """A one-joint arm pointing at a target that passes straight through its base turns
    half round at once (no finite torque); passing 0.5 beside it, it turns smoothly."""
    through, beside = tmp_path / "through.toml", tmp_path / "beside.toml"
    through.write_text(POINTER.format(y=0))
    beside.write_text(POINTER.format(y=0.5))
    run = lambda path: subprocess.run([sys.executable, "-m", "app", "torques", str(path)],  # noqa: E731
                                      cwd=ROOT, capture_output=True, text=True, timeout=120)
    done = run(through)
    assert done.returncode == 2 and done.stderr.count("\n") == 1
    line = POINTER.splitlines().index("time = 0")                # the first key's header line
    assert done.stderr.startswith(f"error: {through}:{line}: linkage[1].key[1]: the inverse "
                                  "kinematics' solution jumps at t = 1 s ('pointer' from ")
    assert "no finite torque" in done.stderr
    done = run(beside)
    assert done.returncode == 0, done.stderr
    row = next(r for r in done.stdout.splitlines() if r.strip().startswith("1.000"))
    assert float(row.split()[1]) == pytest.approx(90.0, abs=1e-6)   # straight at (0, 0.5)
