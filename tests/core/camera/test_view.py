"""The normalizing transformations: the notes' worked example factor by factor, and properties."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.transforms import apply, rotate_x, rotate_y, rotate_z, scale, shear_xy, translate
from core.camera.view import View, ViewError, check, n_par_factors, n_per_factors, problems, vrc_basis

WORKED = View(vrp=(0, 0, 54), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 17),
              prp=(8, 6, 30), front=10, back=-50, label="worked example")


def test_worked_example_factor_by_factor():
    f = n_per_factors(WORKED)
    t_vrp = np.eye(4)
    t_vrp[2, 3] = -54
    assert np.array_equal(f["T_vrp"], t_vrp)
    assert np.array_equal(f["R"], np.eye(4))
    assert np.array_equal(f["T_prp"], translate(-8, -6, -30))
    sh = np.eye(4)
    sh[1, 2] = 1 / 15                                    # shy = -DOP_y/DOP_z = -2/-30
    assert np.array_equal(f["SH_par"], sh)
    assert np.array_equal(f["S_per"], np.diag([1 / 24, 1 / 24, 1 / 80, 1]))
    assert f["z_min"] == pytest.approx(-(-30 + 10) / (-30 - 50))        # -0.25
    composite = f["S_per"] @ f["SH_par"] @ f["T_prp"] @ f["R"] @ f["T_vrp"]
    assert np.array_equal(f["N_per"], composite)


def test_worked_example_composite_against_exact_fractions():
    # N_per by hand in rational arithmetic: rows of S_per · SH_par · T(-PRP) · T(-VRP).
    F = Fraction
    expected = [[F(1, 24), 0, 0, F(-8, 24)],
                [0, F(1, 24), F(1, 24) * F(1, 15), F(1, 24) * (-6 + F(1, 15) * (-84))],
                [0, 0, F(1, 80), F(-84, 80)],
                [0, 0, 0, 1]]
    got = n_per_factors(WORKED)["N_per"]
    assert np.allclose(got, np.array(expected, dtype=float), rtol=0, atol=1e-15)


def test_transform_primitives():
    p = np.array([[1.0, 2.0, 3.0]])
    assert np.allclose(apply(translate(1, -2, 5), p), [[2, 0, 8, 1]])
    assert np.allclose(apply(scale(2, 3, 4), p), [[2, 6, 12, 1]])
    assert np.allclose(apply(rotate_z(np.pi / 2), [[1, 0, 0]]), [[0, 1, 0, 1]])
    assert np.allclose(apply(rotate_x(np.pi / 2), [[0, 1, 0]]), [[0, 0, 1, 1]])
    assert np.allclose(apply(rotate_y(np.pi / 2), [[0, 0, 1]]), [[1, 0, 0, 1]])
    assert np.allclose(apply(shear_xy(0.5, -1), p), [[2.5, -1, 3, 1]])


def test_vrc_basis_is_right_handed_and_orthonormal():
    view = View((16, 0, 54), (1, 0, 1), (-0.17, 0.98, 0.17), (-20, 20, -5, 35), (0, 25, 28), 1, -35)
    u, v, n = vrc_basis(view)
    m = np.array([u, v, n])
    assert np.allclose(m @ m.T, np.eye(3))
    assert np.allclose(np.cross(u, v), n)
    assert np.allclose(n, np.array([1, 0, 1]) / np.sqrt(2))


@pytest.mark.parametrize("changes, message", [
    (dict(vpn=(0, 0, 0)), "VPN is zero"),
    (dict(vup=(0, 0, 0)), "VUP is zero"),
    (dict(vup=(0, 0, -4)), "VUP is parallel to VPN"),
    (dict(prp=(8, 6, 0)), "PRP lies on the view plane"),
    (dict(window=(17, -1, -1, 17)), "u_max (-1) <= u_min (17)"),
    (dict(window=(-1, 17, 3, 3)), "v_max (3) <= v_min (3)"),
    (dict(front=-50, back=10), "B (10) is not behind F (-50)"),
    (dict(front=float("nan")), "NaN or infinite"),
    (dict(vrp=(float("inf"), 0, 0)), "NaN or infinite"),
])
def test_every_invalid_kind_has_its_message(changes, message):
    fields = dict(vrp=WORKED.vrp, vpn=WORKED.vpn, vup=WORKED.vup, window=WORKED.window,
                  prp=WORKED.prp, front=WORKED.front, back=WORKED.back, label="view 7 (line 40)")
    fields.update(changes)
    view = View(**fields)
    assert any(message in p for p in problems(view))
    with pytest.raises(ViewError, match=r"view 7 \(line 40\)"):
        check(view, "parallel")


def test_front_plane_behind_eye_is_invalid_for_perspective_only():
    view = View(WORKED.vrp, WORKED.vpn, WORKED.vup, WORKED.window, WORKED.prp, 40, -50)
    assert problems(view, "parallel") == []
    assert any("not in front of the eye" in p for p in problems(view, "perspective"))


def test_overflowing_view_is_reported_not_nan():
    view = View((1e200, 0, 0), (0, 0, 1), (0, 1, 0), (-1e-200, 1e-200, -1, 1), (0, 0, 1), 0, -1)
    assert any("overflows" in p for p in problems(view, "parallel"))


# --- properties over random valid views -----------------------------------------------------

finite = st.floats(-100, 100, allow_nan=False, allow_infinity=False)
unit = st.tuples(finite, finite, finite).filter(lambda v: np.linalg.norm(v) > 1e-2)


@st.composite
def views(draw, projection):
    vpn = draw(unit)
    vup = draw(unit.filter(lambda w: np.linalg.norm(np.cross(w, vpn))
                           > 0.05 * np.linalg.norm(w) * np.linalg.norm(vpn)))
    u_min = draw(finite)
    v_min = draw(finite)
    u_max = u_min + draw(st.floats(0.5, 50))
    v_max = v_min + draw(st.floats(0.5, 50))
    prp_n = draw(st.floats(1, 100)) * draw(st.sampled_from([1, -1] if projection == "parallel" else [1]))
    prp = (draw(finite), draw(finite), prp_n)
    if projection == "perspective":
        front = prp_n - draw(st.floats(0.1, 50))
    else:
        front = draw(finite)
    back = front - draw(st.floats(0.1, 100))
    return View(tuple(draw(st.tuples(finite, finite, finite))), vpn, vup,
                (u_min, u_max, v_min, v_max), prp, front, back)


def _to_world(view, uvn):
    u, v, n = vrc_basis(view)
    return np.asarray(view.vrp) + uvn[:, :1] * u + uvn[:, 1:2] * v + uvn[:, 2:3] * n


def _volume_corners(view, projection):
    """The 8 corners of the finite view volume in VRC, and where they must land."""
    u_min, u_max, v_min, v_max = view.window
    prp = np.asarray(view.prp, dtype=float)
    vrc, canonical = [], []
    z_min = ((prp[2] - view.front) / (view.back - prp[2])    # = -(vrp'_z+F)/(vrp'_z+B)
             if projection == "perspective" else 0.0)
    for plane, z_can in ((view.front, z_min if projection == "perspective" else 0.0),
                         (view.back, -1.0)):
        for (u, su) in ((u_min, -1), (u_max, 1)):
            for (v, sv) in ((v_min, -1), (v_max, 1)):
                corner = np.array([u, v, 0.0])
                if projection == "perspective":        # along the ray from the eye
                    point = prp + (corner - prp) * (plane - prp[2]) / (0.0 - prp[2])
                    scale_xy = -z_can
                else:                                  # along the direction of projection
                    dop = np.array([(u_min + u_max) / 2, (v_min + v_max) / 2, 0.0]) - prp
                    point = corner + dop * (plane / dop[2])
                    scale_xy = 1.0
                vrc.append(point)
                canonical.append([su * scale_xy, sv * scale_xy, z_can])
    return np.array(vrc), np.array(canonical)


@settings(max_examples=150, deadline=None)
@given(views("perspective"))
def test_n_per_maps_the_view_volume_onto_the_canonical_one(view):
    vrc, expected = _volume_corners(view, "perspective")
    got = apply(n_per_factors(view)["N_per"], _to_world(view, vrc))
    assert np.allclose(got[:, 3], 1.0)
    assert np.allclose(got[:, :3], expected, atol=1e-7)


@settings(max_examples=150, deadline=None)
@given(views("parallel"))
def test_n_par_maps_the_view_volume_onto_the_canonical_one(view):
    vrc, expected = _volume_corners(view, "parallel")
    got = apply(n_par_factors(view)["N_par"], _to_world(view, vrc))
    assert np.allclose(got[:, :3], expected, atol=1e-7)
