"""Quaternions as the notes define them, held against rotation matrices; slerp and squad."""

from __future__ import annotations

import numpy as np
import pytest

from core.animation import quaternion as qt
from core.transforms import rotate_x, rotate_y, rotate_z


def euler_matrix(rx, ry, rz):
    """The scene files' rotation R_z R_y R_x (degrees), 3 x 3."""
    return (rotate_z(np.radians(rz)) @ rotate_y(np.radians(ry)) @ rotate_x(np.radians(rx)))[:3, :3]


def test_product_is_the_notes_formula_by_hand():
    # (1, (2,3,4)) (5, (6,7,8)): scalar 5 - (12+21+32) = -60;
    # vector 1(6,7,8) + 5(2,3,4) + (2,3,4)x(6,7,8) = (6,7,8)+(10,15,20)+(-4,8,-4) = (12,30,24)
    assert np.array_equal(qt.multiply(qt.quat(1, 2, 3, 4), qt.quat(5, 6, 7, 8)),
                          [-60.0, 12.0, 30.0, 24.0])
    i, j, k = qt.quat(0, 1, 0, 0), qt.quat(0, 0, 1, 0), qt.quat(0, 0, 0, 1)
    assert np.array_equal(qt.multiply(i, j), k)              # Hamilton: ij = k, ji = -k
    assert np.array_equal(qt.multiply(j, i), -k)
    assert np.array_equal(qt.multiply(qt.multiply(i, j), k), [-1, 0, 0, 0])   # ijk = -1


@pytest.mark.parametrize("axis,matrix", [((1, 0, 0), rotate_x), ((0, 1, 0), rotate_y),
                                         ((0, 0, 1), rotate_z)])
@pytest.mark.parametrize("degrees", [30.0, 90.0, -135.0, 180.0])
def test_q_inverse_v_q_equals_the_rotation_matrix(axis, matrix, degrees):
    q = qt.from_axis_angle(axis, np.radians(degrees))
    r = matrix(np.radians(degrees))[:3, :3]
    rng = np.random.default_rng(1)
    for v in rng.normal(size=(5, 3)):
        assert np.allclose(qt.rotate(q, v), r @ v, atol=1e-14)


def test_composition_and_matrix_round_trip():
    rng = np.random.default_rng(2)
    for _ in range(50):
        rx, ry, rz = rng.uniform(-180, 180, 3)
        q = qt.from_euler_degrees(rx, ry, rz)
        assert np.allclose(qt.to_matrix(q), euler_matrix(rx, ry, rz), atol=1e-14)
        back = qt.from_matrix(euler_matrix(rx, ry, rz))
        assert qt.angle_between(back, q) < 1e-7
        assert np.allclose(qt.to_matrix(back), euler_matrix(rx, ry, rz), atol=1e-14)


def test_inverse_is_the_notes_formula_for_any_length():
    q = qt.quat(2.0, -1.0, 0.5, 3.0)
    assert np.allclose(qt.multiply(q, qt.inverse(q)), qt.IDENTITY, atol=1e-15)
    assert np.allclose(qt.multiply(qt.inverse(q), q), qt.IDENTITY, atol=1e-15)


def test_slerp_has_constant_angular_speed():
    q0 = qt.from_euler_degrees(10, 20, 30)
    q1 = qt.from_euler_degrees(-40, 70, 150)
    total = qt.angle_between(q0, q1)
    for u in np.linspace(0, 1, 21):
        q = qt.slerp(q0, q1, u)
        assert abs(np.linalg.norm(q) - 1) < 1e-14
        assert abs(qt.angle_between(q0, q) - u * total) < 1e-9
        assert abs(qt.angle_between(q, q1) - (1 - u) * total) < 1e-9


def test_slerp_takes_the_shortest_path_for_q_and_minus_q():
    q0 = qt.IDENTITY
    q1 = qt.from_axis_angle((0, 0, 1), np.radians(60))
    for target in (q1, -q1):                       # the same rotation written twice
        mid = qt.slerp(q0, target, 0.5)
        assert np.allclose(qt.to_matrix(mid), rotate_z(np.radians(30))[:3, :3], atol=1e-14)
    # without the check the arc through -q1 turns the long way: 150 degrees at the middle
    long_way = qt.slerp(q0, -q1, 0.5, shortest=False)
    assert abs(np.degrees(qt.angle_between(q0, long_way)) - 150.0) < 1e-9


def test_gimbal_lock_euler_twists_slerp_does_not():
    """From no rotation to (90, 90, 90): that orientation is 90 degrees about y alone (at
    pitch 90 the x and z turns act about the same axis and cancel). Slerp turns about y the
    whole way; Euler in-betweening rolls out of the plane and back."""
    q0, q1 = qt.IDENTITY, qt.from_euler_degrees(90, 90, 90)
    assert np.allclose(qt.to_matrix(q1), rotate_y(np.radians(90))[:3, :3], atol=1e-14)
    us = np.linspace(0, 1, 101)
    slerp_path = [qt.slerp(q0, q1, u) for u in us]
    euler_path = [qt.from_matrix(euler_matrix(90 * u, 90 * u, 90 * u)) for u in us]
    travelled = lambda path: sum(qt.angle_between(a, b) for a, b in zip(path, path[1:]))
    assert abs(np.degrees(travelled(slerp_path)) - 90.0) < 1e-6
    assert np.degrees(travelled(euler_path)) > 110.0      # 116.4: 29 % further
    half = qt.to_matrix(slerp_path[50])
    assert np.allclose(half, rotate_y(np.radians(45))[:3, :3], atol=1e-14)
    # the y axis stays fixed under slerp; the Euler middle tips it far away
    y = np.array([0.0, 1.0, 0.0])
    assert np.allclose(half @ y, y, atol=1e-14)
    assert np.degrees(np.arccos(qt.to_matrix(euler_path[50]) @ y @ y)) > 30.0   # 31.4


def test_squad_passes_through_keys_and_is_smooth():
    from core.animation.tracks import OrientationTrack
    keys = [qt.from_euler_degrees(*e) for e in [(0, 0, 0), (0, 90, 0), (45, 120, 30), (90, 180, 0)]]
    track = OrientationTrack([0.0, 1.0, 2.0, 3.0], keys, "squad")
    for t, q in zip([0.0, 1.0, 2.0, 3.0], keys):
        assert qt.angle_between(track(t), q) < 1e-7
    # C1: angular velocity on either side of an inner key agrees
    for t in (1.0, 2.0):
        h = 1e-5
        left = qt.angle_between(track(t - h), track(t)) / h
        right = qt.angle_between(track(t), track(t + h)) / h
        assert abs(left - right) < 1e-3 * max(left, 1.0)
        # and the direction of turn agrees: the rotation from t-h to t ≈ that from t to t+h
        d1 = qt.multiply(qt.inverse(track(t - h)), track(t))
        d2 = qt.multiply(qt.inverse(track(t)), track(t + h))
        assert qt.angle_between(d1, d2) < 1e-6
