"""The camera's hands (core.camera.orbit) held to hand-derived values.

The arcball's quaternion against Shoemake's construction worked by hand; orbits that undo
themselves; pan, dolly and zoom against the window's and the PRP's arithmetic; F and B against
the box's corners; and 10,000 random gestures that never leave a NaN or a degenerate view.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.camera import orbit as o
from core.camera.view import View, n_per_factors, problems, vrc_basis
from core.transforms import apply

FRONT = View(vrp=(0.0, 0.0, 0.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0),
             window=(-2.0, 2.0, -2.0, 2.0), prp=(0.0, 0.0, 6.0), front=3.0, back=-3.0)
LO, HI = np.array([-1.0, -1.0, -1.0]), np.array([1.0, 1.0, 1.0])
S45 = math.sqrt(0.5)


def test_a_90_degree_drag_about_the_vertical_turns_vpn_to_the_side():
    # From the ball's centre to 45 degrees right along its equator: Shoemake's quaternion
    # turns the scene by twice the arc, 90 degrees about v, so the camera goes the other way
    # round and looks from -x: VPN (0, 0, 1) -> (-1, 0, 0), VUP stays (0, 1, 0).
    p0, p1 = o.ball_point(0.0, 0.0), o.ball_point(S45, 0.0)
    assert np.allclose(p1, [S45, 0.0, S45], atol=0, rtol=1e-15)
    q = o.arcball(p0, p1)
    # notes' form of a 90-degree turn about +y: (cos 45, -sin 45 * (0, 1, 0))
    assert np.allclose(q, [S45, 0.0, -S45, 0.0], atol=1e-15)
    assert np.allclose(o.q_rotate(q, p0), [1.0, 0.0, 0.0], atol=1e-15)   # p0 onto the arc's end
    turned = o.orbit(FRONT, q)
    assert np.abs(np.array(turned.vpn) - [-1.0, 0.0, 0.0]).max() <= 1e-12
    assert np.abs(np.array(turned.vup) - [0.0, 1.0, 0.0]).max() <= 1e-12
    assert turned.vrp == FRONT.vrp and turned.prp == FRONT.prp and turned.window == FRONT.window
    # the other way: +x
    back = o.orbit(FRONT, o.arcball(p0, o.ball_point(-S45, 0.0)))
    assert np.abs(np.array(back.vpn) - [1.0, 0.0, 0.0]).max() <= 1e-12


def test_the_axis_angle_form_is_the_notes():
    q = o.q_from_axis_angle((0, 0, 2), math.pi / 2)        # 90 degrees ccw about z
    assert np.allclose(o.q_rotate(q, [1.0, 0.0, 0.0]), [0.0, 1.0, 0.0], atol=1e-15)
    assert np.allclose(o.q_matrix(q), [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)


def test_the_scene_turns_as_the_ball_does():
    # After the orbit, a point of the scene seen in the new VRC sits where the ball's turn
    # puts it in the old VRC: the camera's turn is the inverse of the scene's.
    p0, p1 = o.ball_point(0.1, -0.2), o.ball_point(0.5, 0.3)
    q = o.arcball(p0, p1)
    turned = o.orbit(FRONT, q)
    point = np.array([0.3, -0.7, 0.4])
    old = np.array(vrc_basis(FRONT)) @ point          # VRC coordinates (VRP at 0)
    new = np.array(vrc_basis(turned)) @ point
    assert np.allclose(new, o.q_rotate(q, old), atol=1e-14)


def test_an_orbit_and_its_reverse_return_the_start():
    view = View(vrp=(1.0, 2.0, -3.0), vpn=(1.0, 0.8, 1.2), vup=(0.0, 1.0, 0.0),
                window=(-2.0, 2.0, -1.5, 1.5), prp=(0.4, 0.3, 5.0), front=2.0, back=-3.0)
    start = o.orbit(view, o.arcball(o.ball_point(0, 0), o.ball_point(0, 0)))   # VUP made v
    a, b = o.ball_point(-0.3, 0.2), o.ball_point(0.6, -0.4)
    there = o.orbit(start, o.arcball(a, b))
    again = o.orbit(there, o.arcball(b, a))
    assert not np.allclose(there.vpn, start.vpn, atol=1e-3)
    assert np.abs(again.numbers - start.numbers).max() <= 1e-12
    # round the vertical in four quarter turns
    quarter = o.arcball(o.ball_point(0.0, 0.0), o.ball_point(S45, 0.0))
    round_trip = start
    for _ in range(4):
        round_trip = o.orbit(round_trip, quarter)
    assert np.abs(round_trip.numbers - start.numbers).max() <= 1e-12


def test_pan_moves_the_view_plane_by_the_windows_units_per_pixel():
    # 400 px over a 4-unit window: 0.01 units a pixel; 50 px right and 20 px down move the
    # VRP by -0.5 u and +0.2 v.
    moved = o.pan(FRONT, 50, 20, 400, 400)
    assert moved.vrp == pytest.approx((-0.5, 0.2, 0.0), abs=1e-15)
    # a point on the view plane moves 50 px right and 20 px down on screen
    point = np.array([[0.3, 0.1, 0.0]])
    def pixel(view):
        f = n_per_factors(view)
        ndc = apply(f["N_per"], point)[0]
        return np.array([(ndc[0] / -ndc[2] + 1) * 200, (1 - ndc[1] / -ndc[2]) * 200])
    assert pixel(moved) - pixel(FRONT) == pytest.approx([50.0, 20.0], abs=1e-9)


def test_dolly_moves_the_prp_along_vpn_and_keeps_the_field_of_view():
    nearer = o.dolly(FRONT, 0.5, "perspective")
    assert nearer.prp == (0.0, 0.0, 3.0) and nearer.window == (-1.0, 1.0, -1.0, 1.0)
    # an off-axis PRP: the window scales about the PRP's foot, the rays keep their directions
    view = o._with(FRONT, prp=(1.0, 0.5, 4.0))
    d = o.dolly(view, 0.25, "perspective")
    assert d.prp == (1.0, 0.5, 1.0)
    assert d.window == (1.0 + 0.25 * -3.0, 1.0 + 0.25 * 1.0, 0.5 + 0.25 * -2.5, 0.5 + 0.25 * 1.5)
    # everything in front of the eye grows monotonically as the eye comes nearer
    point = np.array([[0.5, 0.5, -2.0]])
    sizes = []
    for k in range(6):
        v = o.dolly(FRONT, 0.8 ** k, "perspective")
        v = o.follow_bounds(v, LO, HI, "perspective")
        ndc = apply(n_per_factors(v)["N_per"], point)[0]
        sizes.append(ndc[0] / -ndc[2])
    assert all(b > a for a, b in zip(sizes, sizes[1:]))
    # parallel: the window about its centre
    assert o.dolly(FRONT, 2.0, "parallel").window == (-4.0, 4.0, -4.0, 4.0)
    assert o.zoom(o._with(FRONT, window=(0.0, 2.0, 1.0, 2.0)), 0.5).window == (0.5, 1.5, 1.25, 1.75)


def test_front_and_back_follow_the_bounds():
    # The unit cube seen along z from VRP 0: depths -1..1, margin 0.02 * sqrt(3).
    m = o.DEPTH_MARGIN * math.sqrt(3.0)
    fb = o.follow_bounds(FRONT, LO, HI, "parallel")
    assert (fb.front, fb.back) == pytest.approx((1.0 + m, -1.0 - m), abs=1e-15)
    # the eye inside the box: F stays a thousandth of the eye's reach (at least of the
    # bounding sphere's radius) in front of it
    inside = o.follow_bounds(o._with(FRONT, prp=(0.0, 0.0, 0.5)), LO, HI, "perspective")
    near = o.NEAR_FRACTION * max(0.5 - (-1.0 - m), math.sqrt(3.0))
    assert inside.front == pytest.approx(0.5 - near, abs=1e-15)
    assert inside.back == pytest.approx(-1.0 - m, abs=1e-15)
    assert problems(inside, "perspective") == []


def test_fit_frames_the_bounding_sphere():
    view = o._with(FRONT, vrp=(10.0, 0.0, 0.0), window=(-1.0, 3.0, 0.0, 2.0), prp=(0.3, 0.0, 2.0))
    fitted = o.fit(view, LO + 5, HI + 5, "perspective")
    r = math.sqrt(3.0)
    angle = math.atan2(1.0, 2.0)                            # the view's half angle, short side
    assert fitted.vrp == (5.0, 5.0, 5.0)
    assert fitted.prp == pytest.approx((0.0, 0.0, r / math.sin(angle)), rel=1e-15)
    half = r / math.cos(angle)
    assert fitted.window == pytest.approx((-2 * half, 2 * half, -half, half), rel=1e-15)
    # the sphere's tangent cone from the eye has the window's short half angle
    assert math.asin(r / fitted.prp[2]) == pytest.approx(math.atan2(half, fitted.prp[2]), rel=1e-12)
    assert problems(fitted, "perspective") == []


def test_degenerate_poses_are_named():
    assert "PRP_n" in " ".join(o.pose_problems(o._with(FRONT, prp=(0.0, 0.0, 0.0)),
                                               "perspective", LO, HI))
    assert "parallel to VPN" in " ".join(o.pose_problems(o._with(FRONT, vup=(0.0, 0.0, 2.0)),
                                                         "parallel", LO, HI))
    tiny = o.follow_bounds(o.dolly(FRONT, 1e-11, "perspective"), LO, HI, "perspective")
    assert any("narrower" in p or "view plane" in p for p in
               o.pose_problems(tiny, "perspective", LO, HI))
    assert o.pose_problems(o.zoom(FRONT, 1e12), "parallel", LO, HI) != []
    assert o.pose_problems(FRONT, "perspective", LO, HI) == []


def test_ten_thousand_random_gestures_never_degenerate():
    # Each gesture is kept only if pose_problems accepts it (as the window does); every kept
    # view is finite, its frame orthonormal, and drawable in both projections.
    rng = np.random.default_rng(34)
    view = o.follow_bounds(FRONT, LO, HI, "perspective")
    kept = 0
    for step in range(10_000):
        projection = "perspective" if step % 3 else "parallel"
        kind = rng.integers(4)
        if kind == 0 or kind == 3:
            a, b = rng.uniform(-1.6, 1.6, 2), rng.uniform(-1.6, 1.6, 2)
            new = o.orbit(view, o.arcball(o.ball_point(*a), o.ball_point(*b)))
        elif kind == 1:
            new = o.pan(view, *rng.uniform(-300, 300, 2), 320, 240)
        else:
            new = o.dolly(view, float(0.9 ** rng.integers(-8, 9)), projection)
        new = o.follow_bounds(new, LO, HI, projection)
        assert np.all(np.isfinite(new.numbers))
        if not o.pose_problems(new, projection, LO, HI):
            view, kept = new, kept + 1
    assert kept > 9000
    u, v, n = vrc_basis(view)
    assert np.allclose(np.array([u, v, n]) @ np.array([u, v, n]).T, np.eye(3), atol=1e-12)
    assert np.linalg.norm(view.vpn) == pytest.approx(1.0, abs=1e-12)
    assert abs(np.dot(view.vpn, view.vup)) <= 1e-12


def test_a_90_degree_orbit_about_a_pivot_carries_the_vrp_round_it():
    # The same 90-degree turn about v, about the pivot (0, 0, -2) instead of the VRP (the
    # origin): the VRP goes from 2 in front of the pivot along +z to 2 along -x, by hand.
    q = o.arcball(o.ball_point(0.0, 0.0), o.ball_point(S45, 0.0))
    turned = o.orbit(FRONT, q, pivot=(0.0, 0.0, -2.0))
    assert np.abs(np.array(turned.vrp) - [-2.0, 0.0, -2.0]).max() <= 1e-12
    assert np.abs(np.array(turned.vpn) - [-1.0, 0.0, 0.0]).max() <= 1e-12
    assert turned.prp == FRONT.prp and turned.window == FRONT.window
    # the eye (VRP + PRP_n n) keeps its distance to the pivot: 2 + 6 = 8 before and after
    eye = np.array(turned.vrp) + 6.0 * np.array(turned.vpn)
    assert abs(np.linalg.norm(eye - [0.0, 0.0, -2.0]) - 8.0) <= 1e-12
    # about the VRP itself it is the plain orbit
    same = o.orbit(FRONT, q, pivot=FRONT.vrp)
    assert np.abs(np.array(same.vrp) - np.array(FRONT.vrp)).max() <= 1e-15
