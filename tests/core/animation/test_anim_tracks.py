"""In-betweening of keyed values: linear, ease, Catmull–Rom, Kochanek–Bartels, double
interpolant, arc length."""

from __future__ import annotations

import numpy as np
import pytest

from core.animation.tracks import Track

TIMES = np.array([0.0, 1.0, 2.5, 3.0, 5.0])          # unequal spacing on purpose
VALUES = np.array([[0, 0, 0], [2, 1, 0], [3, -1, 2], [5, 0, 1], [4, 3, 0]], dtype=float)


def derivative(track, t, h=1e-6):
    return (track(t + h) - track(t - h)) / (2 * h)


def test_linear_is_the_notes_formula():
    track = Track(TIMES, VALUES, "linear")
    # V_t = V_i (1 - u) + u V_f on [1.0, 2.5] at u = 0.4
    assert np.allclose(track(1.6), VALUES[1] * 0.6 + 0.4 * VALUES[2], atol=1e-15)
    assert np.array_equal(track(-1.0), VALUES[0]) and np.array_equal(track(9.0), VALUES[-1])


@pytest.mark.parametrize("method", ["linear", "ease", "catmull-rom", "kochanek-bartels", "double"])
def test_every_method_passes_through_its_keys(method):
    track = Track(TIMES, VALUES, method, tension=0.3, continuity=0.2, bias=-0.4)
    for t, v in zip(TIMES, VALUES):
        assert np.allclose(track(t), v, atol=1e-12)


def test_catmull_rom_derivative_is_continuous_at_the_keys():
    track = Track(TIMES, VALUES, "catmull-rom")
    h = 1e-6
    for i in range(1, len(TIMES) - 1):
        t = TIMES[i]
        left = (track(t) - track(t - h)) / h
        right = (track(t + h) - track(t)) / h
        expected = (VALUES[i + 1] - VALUES[i - 1]) / (TIMES[i + 1] - TIMES[i - 1])
        assert np.allclose(left, expected, atol=1e-4)
        assert np.allclose(right, expected, atol=1e-4)
    # linear in-betweening, for contrast, has a corner at every key
    lin = Track(TIMES, VALUES, "linear")
    t = TIMES[1]
    assert not np.allclose((lin(t) - lin(t - h)) / h, (lin(t + h) - lin(t)) / h, atol=1e-2)


def test_kochanek_bartels_zero_parameters_is_catmull_rom_and_tension_slows_keys():
    cr = Track(TIMES, VALUES, "catmull-rom")
    kb = Track(TIMES, VALUES, "kochanek-bartels")
    for t in np.linspace(0, 5, 37):
        assert np.allclose(kb(t), cr(t), atol=1e-14)
    tight = Track(TIMES, VALUES, "kochanek-bartels", tension=1.0)     # T = 1: zero tangents
    assert np.allclose(derivative(tight, 1.0), 0.0, atol=1e-5)
    # C != 0 breaks the derivative at a key on purpose (a corner)
    corner = Track(TIMES, VALUES, "kochanek-bartels", continuity=-0.8)
    h = 1e-6
    assert not np.allclose((corner(1.0) - corner(1.0 - h)) / h, (corner(1.0 + h) - corner(1.0)) / h,
                           atol=1e-2)


def test_ease_stops_at_each_key():
    track = Track(TIMES, VALUES, "ease")
    for t in TIMES[1:-1]:
        assert np.allclose(derivative(track, t), 0.0, atol=1e-4)


def test_double_interpolant_separates_shape_from_timing():
    """The path is the Catmull–Rom spline through the keys against the key number; moving a
    key in time changes when the path is travelled, never the path, and it never runs back."""
    shape = Track(np.arange(len(VALUES), dtype=float), VALUES, "catmull-rom")
    ks = np.linspace(0, len(VALUES) - 1, 40001)
    curve = np.array([shape(k) for k in ks])
    for times in (TIMES, [0.0, 0.5, 3.5, 4.0, 5.0]):
        track = Track(times, VALUES, "double")
        ts = np.linspace(0, 5, 401)
        nearest = []
        for t in ts:
            d = np.linalg.norm(curve - track(t), axis=1)
            assert d.min() < 1e-3                      # on the shape curve
            nearest.append(int(d.argmin()))
        assert np.all(np.diff(nearest) >= 0)            # monotone timing: never backwards
    a, b = Track(TIMES, VALUES, "double"), Track([0.0, 0.5, 3.5, 4.0, 5.0], VALUES, "double")
    assert np.linalg.norm(a(2.0) - b(2.0)) > 0.3         # the timing did change (0.41)


def test_arc_length_gives_constant_speed():
    track = Track(TIMES, VALUES, "catmull-rom", constant_speed=True)
    ts = np.linspace(0, 5, 501)
    points = np.array([track(t) for t in ts])
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    assert steps.std() / steps.mean() < 2e-3
    assert np.allclose(points[0], VALUES[0]) and np.allclose(points[-1], VALUES[-1])
    plain = Track(TIMES, VALUES, "catmull-rom")
    plain_steps = np.linalg.norm(np.diff([plain(t) for t in ts], axis=0), axis=1)
    assert plain_steps.std() / plain_steps.mean() > 0.2       # without it, speed varies a lot


def test_bad_tracks_are_refused_with_a_reason():
    with pytest.raises(ValueError, match="increase"):
        Track([0.0, 0.0], [[1.0], [2.0]])
    with pytest.raises(ValueError, match="not one of"):
        Track([0.0, 1.0], [[1.0], [2.0]], "cubic")
