"""Linkages (core.animation.linkage): forward kinematics against hand values, inverse
kinematics against the two-link arm's closed form, nearest points, joint limits; bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.animation.keys import animation_of
from core.animation.linkage import CCD, CCD_SWEEPS, DLS, MAX_ITERATIONS, chain_pose, solve_many
from core.scene.formats import ReaderError, read_scene_file

L1, L2 = 1.0, 0.7
BASE = np.zeros(3)
AXES = np.array([[0.0, 0, 1], [0, 0, 1]])
BONES = np.array([[L1, 0, 0], [L2, 0, 0]])
FREE = np.full(2, -1e9), np.full(2, 1e9)


def end(theta, axes=AXES, bones=BONES):
    points, world = np.empty((len(theta) + 1, 3)), np.empty((len(theta), 3))
    chain_pose(BASE, axes, bones, np.asarray(theta, float), points, world)
    return points[-1]


def solve(targets, solver=DLS, lo=FREE[0], hi=FREE[1], start=np.zeros(2), axes=AXES, bones=BONES):
    return solve_many(BASE, axes, bones, start, lo, hi, np.asarray(targets, float), solver, 0.5,
                      CCD_SWEEPS if solver == CCD else MAX_ITERATIONS)


def planar(rng, count, low, high):
    """Targets in the plane z = 0 at distances in [low, high], at every angle."""
    r = np.sqrt(rng.uniform(low ** 2, high ** 2, count))
    a = rng.uniform(-math.pi, math.pi, count)
    return np.stack([r * np.cos(a), r * np.sin(a), np.zeros(count)], axis=1)


def test_forward_kinematics_is_the_hand_sum_of_the_bones():
    a, b = math.radians(30), math.radians(45)
    assert np.allclose(end([a, b]), [L1 * math.cos(a) + L2 * math.cos(a + b),
                                     L1 * math.sin(a) + L2 * math.sin(a + b), 0], atol=1e-15)


@pytest.mark.parametrize("solver,low,high", [(DLS, L1 - L2 + 0.01, L1 + L2 - 0.01),
                                             (CCD, 0.45, 1.6)])
def test_the_two_link_arm_reaches_reachable_targets_within_1e_9(solver, low, high):
    """Everywhere in the annulus with DLS; CCD (linear convergence) crawls where the arm is
    nearly folded or stretched (1.5e-6 off at 500 sweeps for a target 1.69 away) and is held
    to the same 1e-9 between 0.45 and 1.6."""
    targets = planar(np.random.default_rng(5), 400, low, high)
    theta = solve(targets, solver)
    misses = np.linalg.norm([end(t) for t in theta] - targets, axis=1)
    assert misses.max() < 1e-9, misses.max()


def test_targets_straight_along_the_stretched_arm_are_reached():
    """The rest pose (stretched along x) is singular: J's columns are at right angles to a
    target on the x axis, where DLS alone does not move."""
    for x in (0.31, 1.0, 1.69):
        theta = solve([[x, 0, 0]])[0]
        assert np.linalg.norm(end(theta) - [x, 0, 0]) < 1e-9


def test_unreachable_targets_stop_at_the_nearest_point():
    """Outside the reach the nearest point is the stretched arm pointing at the target;
    inside the hole of the annulus (closer than L1 - L2) the folded arm pointing at it."""
    rng = np.random.default_rng(7)
    far = planar(rng, 200, L1 + L2 + 0.05, 6.0)
    near = planar(rng, 200, 0.02, L1 - L2 - 0.05)
    for targets, reach in ((far, L1 + L2), (near, L1 - L2)):
        got = np.array([end(t) for t in solve(targets)])
        nearest = targets / np.linalg.norm(targets, axis=1, keepdims=True) * reach
        assert np.abs(got - nearest).max() < 1e-9


def test_joint_limits_hold_on_10000_random_targets_and_the_closed_form_is_found():
    """Shoulder in [-60°, 150°], elbow in [0°, 170°] (elbow up): every answer within the
    limits; where the closed-form elbow-up pose is inside them, that pose is the answer."""
    lo, hi = np.radians([-60.0, 0.0]), np.radians([150.0, 170.0])
    rng = np.random.default_rng(11)
    targets = rng.uniform(-2.0, 2.0, (10_000, 3))
    targets[:, 2] = 0.0
    theta = solve(targets, lo=lo, hi=hi)
    assert np.all(theta >= lo) and np.all(theta <= hi)
    d2 = (targets[:, :2] ** 2).sum(axis=1)
    c = (d2 - L1 ** 2 - L2 ** 2) / (2 * L1 * L2)
    inside = np.abs(c) < 0.999
    elbow = np.arccos(np.clip(c, -1, 1))
    shoulder = np.arctan2(targets[:, 1], targets[:, 0]) - np.arctan2(L2 * np.sin(elbow),
                                                                     L1 + L2 * np.cos(elbow))
    ok = inside & (elbow <= hi[1] - 1e-3) & (shoulder >= lo[0] + 1e-3) & (shoulder <= hi[0] - 1e-3)
    assert ok.sum() > 2500
    assert np.abs(theta[ok, 1] - elbow[ok]).max() < 1e-6          # ill-conditioned near |c| = 1
    misses = np.linalg.norm([end(t) for t in theta[ok]] - targets[ok], axis=1)
    assert misses.max() < 1e-9


def test_a_spatial_three_joint_arm_reaches_3d_targets():
    axes = np.array([[0.0, 1, 0], [0, 0, 1], [0, 0, 1]])        # a turntable, then two hinges
    bones = np.array([[0.0, 0.5, 0], [1, 0, 0], [0.8, 0, 0]])
    rng = np.random.default_rng(3)
    goal = rng.normal(size=(300, 3))
    goal = goal / np.linalg.norm(goal, axis=1, keepdims=True) * rng.uniform(0.6, 1.6, (300, 1))
    goal[:, 1] += 0.5                                            # around the shoulder
    theta = solve_many(BASE, axes, bones, np.zeros(3), np.full(3, -1e9), np.full(3, 1e9), goal,
                       DLS, 0.5, MAX_ITERATIONS)
    misses = np.linalg.norm([end(t, axes, bones) for t in theta] - goal, axis=1)
    assert misses.max() < 1e-9


ARM = """
name = "arm"
[[geometry]]
generator = "cube"
name = "upper"
transform = { scale = [0.5, 0.06, 0.06], translate = [0.5, 0, 0] }
[[geometry]]
generator = "cube"
name = "fore"
transform = { scale = [0.35, 0.05, 0.05], translate = [1.35, 0, 0] }
[[view]]
vrp = [0.5, 0.5, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-1.5, 1.5, -1.5, 1.5]
prp = [0, 0, 6]
front = 3
back = -3
[animation]
duration = 2
fps = 10
[[linkage]]
name = "arm"
[[linkage.joint]]
name = "shoulder"
bone = [1, 0, 0]
meshes = ["upper"]
[[linkage.joint]]
name = "elbow"
bone = [0.7, 0, 0]
min = 0
max = 170
meshes = ["fore"]
[[linkage.key]]
time = 0
angles = { shoulder = 30, elbow = 45 }
[[linkage.key]]
time = 2
target = [0.3, 1.2, 0]
"""


def test_the_file_moves_the_carried_meshes_to_the_solved_pose():
    keyed = read_scene_file(ARM.split("[[linkage.key]]\ntime = 2")[0], "arm.toml")
    fore = keyed.meshes[1].positions
    tip = np.flatnonzero(np.all(np.isclose(fore, [1.7, 0.05, 0.05]), axis=1))[0]
    a, b = math.radians(30), math.radians(75)
    at0 = animation_of(keyed).scene_at(1.0).meshes[1].positions[tip]     # the keyed angles
    hand = [math.cos(a) + 0.7 * math.cos(b), math.sin(a) + 0.7 * math.sin(b), 0]
    hand += np.array([-math.sin(b), math.cos(b), 0]) * 0.05 + [0, 0, 0.05]
    assert np.allclose(at0, hand, atol=1e-12)
    scene = read_scene_file(ARM, "arm.toml")                 # and a target keyed at t = 2
    anim = animation_of(scene)
    at2 = anim.scene_at(2.0).meshes[1].positions
    linkage = anim.movers[0]
    assert np.linalg.norm(linkage.end(linkage.angles_at(2.0)) - [0.3, 1.2, 0]) < 1e-9
    wrist = at2[np.flatnonzero(np.all(np.isclose(fore, [1.7, 0.0, 0.05], atol=0.051), axis=1))]
    assert np.min(np.linalg.norm(wrist[:, :2] - [0.3, 1.2], axis=1)) < 0.051 * math.sqrt(2)


@pytest.mark.parametrize("change,message", [
    (('name = "elbow"\n', 'name = "elbow"\nparent = "wrist"\n'), "linkage[1].joint[2].parent: no joint is named 'wrist'"),
    (('name = "shoulder"\n', 'name = "shoulder"\nparent = "elbow"\n'),
     "the joints' parents make a cycle (shoulder → elbow → shoulder)"),
    (("bone = [0.7, 0, 0]", "bone = [0, 0, 0]"), "linkage[1].joint[2].bone: the bone has zero length"),
    (('name = "elbow"\n', 'name = "elbow"\naxis = [0, 0, 0]\n'), "linkage[1].joint[2].axis: the joint's axis is the zero vector"),
    (("min = 0\nmax = 170", "min = 10\nmax = 170"), "linkage[1].joint[2]: the limits [10, 170] degrees must hold the rest pose"),
    (('meshes = ["fore"]', 'meshes = ["upper"]'), "linkage[1].joint[2].meshes[1]: 'upper' is moved already"),
    (('meshes = ["fore"]', 'meshes = ["hand"]'), "linkage[1].joint[2].meshes[1]: no geometry is named 'hand'"),
    (("[[linkage]]\n", '[[linkage]]\nsolver = "jacobian"\n'), "linkage[1].solver: 'jacobian' is not one of"),
    (("angles = { shoulder = 30, elbow = 45 }", "angles = { wrist = 30 }"), "linkage[1].key[1].angles.wrist: unknown key 'wrist'"),
])
def test_bad_linkages_get_one_clear_message(change, message):
    with pytest.raises(ReaderError) as error:
        read_scene_file(ARM.replace(*change), "arm.toml")
    assert message in str(error.value)


def test_the_scenes_linkages_together_are_bounded_in_joints():
    # every frame solves every joint (1,024 with IK targets: 0.17 s a frame here): at most that
    head = ARM.split("[[linkage]]")[0]
    chain = "".join(f'[[linkage.joint]]\nname = "j{k}"\nbone = [0.01, 0, 0]\n'
                    for k in range(256))
    linkages = "".join(f'[[linkage]]\nname = "arm {i}"\n' + chain for i in range(5))
    with pytest.raises(ReaderError, match=r"linkage\[5\]: 1,280 joints in the scene's linkages "
                                          r"by here; at most 1,024"):
        read_scene_file(head + linkages, "arms.toml")


def test_an_error_inside_a_joint_cites_the_joints_own_line():
    lines = ARM.replace("bone = [0.7, 0, 0]", 'bone = "long"').splitlines()
    wrong = next(i + 1 for i, line in enumerate(lines) if 'bone = "long"' in line)
    with pytest.raises(ReaderError, match=rf"^arm.toml:{wrong}: linkage\[1\]\.joint\[2\]\.bone: "):
        read_scene_file("\n".join(lines), "arm.toml")
