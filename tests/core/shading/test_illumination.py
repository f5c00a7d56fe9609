"""The Phong illumination model against hand-computed values, and its numpy and numba forms
against each other (core/shading/illumination.py).

The set-up of most tests: a surface point at the origin with normal +z; material
k_a = 0.2, k_d = 0.5, k_s = 0.25, n = 10, O_d = (1, 0.5, 0.2), O_s = 1; ambient I_a = 0.2;
one white point light with f_att = 1 unless the test says otherwise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.shading import illumination as il
from core.scene.model import Light, Material
from core.camera.view import View

OD = np.array([1.0, 0.5, 0.2])
MATERIAL = Material(ka=0.2, kd=0.5, ks=0.25, n=10.0, od=tuple(OD), os=(1.0, 1.0, 1.0))
AMBIENT = np.array([0.2, 0.2, 0.2])
UP = np.array([0.0, 0.0, 1.0])


def model(light: Light, eye=(0.0, 0.0, 5.0), normal=UP, point=(0.0, 0.0, 0.0),
          material: Material = MATERIAL, two_sided=False, halfway=False, parallel=False,
          ambient=AMBIENT):
    """RGB of the numpy model at one point (and check the numba twin agrees exactly)."""
    surfaces = il.pack_surfaces([material], [two_sided])
    lights = il.pack_lights([light])
    e = il.Eye(None, np.asarray(eye, float)) if parallel else il.Eye(np.asarray(eye, float), None)
    eye_row = il.pack_eye(e)
    p = np.asarray(point, float)[None, :]
    n = np.asarray(normal, float)[None, :]
    rgb = il.illuminate(p, n, np.zeros(1, np.int64), surfaces, lights, ambient, eye_row, halfway)[0]
    twin = il.phong_point(*p[0], *n[0], 0, surfaces, lights, ambient, eye_row, halfway)
    assert np.array_equal(rgb, np.array(twin))
    return rgb


def test_light_straight_above():
    # L = N = V = +z: N.L = 1, R = N, R.V = 1, so I = 0.2*0.2*O_d + 0.5*O_d + 0.25.
    rgb = model(Light(position=(0.0, 0.0, 10.0)))
    np.testing.assert_allclose(rgb, 0.04 * OD + 0.5 * OD + 0.25, rtol=0, atol=1e-15)
    np.testing.assert_allclose(rgb, [0.79, 0.52, 0.358], atol=1e-15)


def test_light_at_45_degrees_eye_straight_above():
    # L = (1, 0, 1)/sqrt 2: N.L = cos 45°; R = (-1, 0, 1)/sqrt 2, R.V = cos 45° = 2^-1/2,
    # so the specular term is k_s (2^-1/2)^10 = 0.25 / 32.
    rgb = model(Light(position=(10.0, 0.0, 10.0)))
    expected = 0.04 * OD + 0.5 * OD * math.sqrt(0.5) + 0.25 / 32.0
    np.testing.assert_allclose(rgb, expected, rtol=0, atol=1e-15)


def test_light_at_45_degrees_eye_on_the_mirror_direction():
    # V = R = (-1, 0, 1)/sqrt 2: the full highlight, R.V = 1.
    rgb = model(Light(position=(10.0, 0.0, 10.0)), eye=(-5.0, 0.0, 5.0))
    np.testing.assert_allclose(rgb, 0.04 * OD + 0.5 * OD * math.sqrt(0.5) + 0.25, atol=1e-15)


def test_light_behind_the_surface_gives_ambient_only():
    # N.L = -1: no diffuse and no specular, even though R.V would be positive here.
    rgb = model(Light(position=(0.0, 0.0, -10.0)), eye=(0.0, 0.0, 5.0))
    np.testing.assert_allclose(rgb, 0.04 * OD, atol=1e-15)
    rgb = model(Light(position=(1.0, 0.0, -1.0)), eye=(-1.0, 0.0, -1.0))
    np.testing.assert_allclose(rgb, 0.04 * OD, atol=1e-15)


def test_two_sided_lighting_flips_the_normal_to_the_viewer():
    below = Light(position=(0.0, 0.0, -10.0))
    # One-sided: seen from below, lit from below, normal up: ambient only.
    np.testing.assert_allclose(model(below, eye=(0, 0, -5)), 0.04 * OD, atol=1e-15)
    # Two-sided: the normal turns to the viewer and the face is lit as if from above.
    np.testing.assert_allclose(model(below, eye=(0, 0, -5), two_sided=True),
                               0.04 * OD + 0.5 * OD + 0.25, atol=1e-15)
    # Two-sided, viewer above and light below: the visible side is dark.
    np.testing.assert_allclose(model(below, eye=(0, 0, 5), two_sided=True), 0.04 * OD, atol=1e-15)


@pytest.mark.parametrize("attenuation, distance, f_att", [
    ((1.0, 0.5, 0.25), 2.0, 1.0 / 3.0),      # 1 + 0.5*2 + 0.25*4 = 3
    ((0.0, 0.0, 1.0), 4.0, 1.0 / 16.0),      # inverse square
    ((0.25, 0.0, 0.0), 2.0, 1.0),            # 1/0.25 = 4, capped at 1
    ((0.0, 0.0, 0.0), 3.0, 1.0),             # no attenuation at all: no division by zero
])
def test_attenuation(attenuation, distance, f_att):
    dark = Material(ka=0.0, kd=1.0, ks=0.0, n=1.0, od=(1.0, 1.0, 1.0))
    rgb = model(Light(position=(0.0, 0.0, distance), attenuation=attenuation), material=dark)
    np.testing.assert_allclose(rgb, [f_att] * 3, rtol=1e-15)


def test_directional_light_is_not_attenuated():
    dark = Material(ka=0.0, kd=1.0, ks=0.0, n=1.0, od=(1.0, 1.0, 1.0))
    rgb = model(Light(direction=(0.0, 0.0, 3.0), attenuation=(0.0, 0.0, 100.0)), material=dark)
    np.testing.assert_allclose(rgb, [1.0, 1.0, 1.0])
    rgb = model(Light(direction=(0.0, 1.0, 1.0)), material=dark)       # normalised: cos 45°
    np.testing.assert_allclose(rgb, [math.sqrt(0.5)] * 3, rtol=1e-15)


@pytest.mark.parametrize("n", [1.0, 10.0, 100.0, 1e4])
def test_specular_exponent(n):
    # Light straight above (R = N); the eye 30° off the normal: specular = k_s cos^n 30°.
    spec_only = Material(ka=0.0, kd=0.0, ks=1.0, n=n, od=(1, 1, 1), os=(1.0, 0.5, 0.25))
    eye = (5.0 * math.sin(math.radians(30)), 0.0, 5.0 * math.cos(math.radians(30)))
    rgb = model(Light(position=(0.0, 0.0, 10.0)), eye=eye, material=spec_only)
    np.testing.assert_allclose(rgb, np.cos(np.radians(30)) ** n * np.array([1.0, 0.5, 0.25]),
                               rtol=1e-12, atol=1e-300)
    # On the mirror direction the highlight is k_s O_s whatever the exponent (1e4 included).
    rgb = model(Light(position=(0.0, 0.0, 10.0)), eye=(0, 0, 5), material=spec_only)
    np.testing.assert_allclose(rgb, [1.0, 0.5, 0.25], rtol=1e-15)


def test_halfway_form():
    # L at 45°, V straight above: H is 22.5° off N, so (N.H)^n = cos^n 22.5°, while the
    # reflect form gives (R.V)^n = cos^n 45°.
    spec_only = Material(ka=0.0, kd=0.0, ks=1.0, n=10.0, od=(1, 1, 1))
    light = Light(position=(10.0, 0.0, 10.0))
    rgb = model(light, material=spec_only, halfway=True)
    np.testing.assert_allclose(rgb, [math.cos(math.radians(22.5)) ** 10] * 3, rtol=1e-14)
    rgb = model(light, material=spec_only, halfway=False)
    np.testing.assert_allclose(rgb, [math.cos(math.radians(45)) ** 10] * 3, rtol=1e-14)


def test_parallel_eye_uses_a_constant_view_direction():
    # The same point seen along +z (parallel) and from (0, 0, 5) (perspective) agree.
    light = Light(position=(10.0, 0.0, 10.0))
    np.testing.assert_array_equal(model(light, eye=(0, 0, 1), parallel=True), model(light))


def test_several_lights_add_and_the_result_is_clamped():
    surfaces = il.pack_surfaces([MATERIAL], [False])
    lights = il.pack_lights([Light(position=(0, 0, 10)), Light(direction=(0, 0, 1),
                                                               intensity=(0.5, 0.0, 0.0))])
    rgb = il.illuminate(np.zeros((1, 3)), UP[None], np.zeros(1, np.int64), surfaces, lights,
                        AMBIENT, il.pack_eye(il.Eye(np.array([0, 0, 5.0]), None)), False)[0]
    one = 0.04 * OD + 0.5 * OD + 0.25
    np.testing.assert_allclose(rgb, np.minimum(one + [0.5 * (0.5 * 1.0 + 0.25), 0, 0], 1.0))
    assert rgb[0] == 1.0                                  # 0.79 + 0.375 clamped


def test_degenerate_cases_stay_finite():
    # A light exactly at the surface point: ambient only (L is undefined there).
    np.testing.assert_allclose(model(Light(position=(0.0, 0.0, 0.0))), 0.04 * OD, atol=1e-15)
    # The point exactly at the eye: V = N, finite.
    rgb = model(Light(position=(0.0, 0.0, 10.0)), eye=(0.0, 0.0, 0.0))
    np.testing.assert_allclose(rgb, 0.04 * OD + 0.5 * OD + 0.25, atol=1e-15)
    # A zero normal: ambient only.
    np.testing.assert_allclose(model(Light(position=(0, 0, 10)), normal=(0, 0, 0)), 0.04 * OD)
    # Zero and enormous intensities.
    np.testing.assert_allclose(model(Light(position=(0, 0, 10), intensity=(0, 0, 0))), 0.04 * OD)
    assert np.array_equal(model(Light(position=(0, 0, 10), intensity=(1e308, 1e308, 1e308))),
                          [1.0, 1.0, 1.0])
    # Halfway form with L = -V (light above, viewer straight below): N·L = 1, and H = L + V
    # is the zero vector, so no highlight: ambient plus diffuse, finite.
    rgb = model(Light(position=(0.0, 0.0, 10.0)), eye=(0.0, 0.0, -5.0), halfway=True)
    np.testing.assert_allclose(rgb, 0.04 * OD + 0.5 * OD, atol=1e-15)
    # Tiny and huge coordinates: unit vectors without underflow or overflow.
    rgb = model(Light(position=(0.0, 0.0, 1e-200)), eye=(0.0, 0.0, 1e-200))
    np.testing.assert_allclose(rgb, 0.04 * OD + 0.5 * OD + 0.25, atol=1e-15)
    rgb = model(Light(position=(0.0, 0.0, 1e200)), eye=(0.0, 0.0, 1e200))
    np.testing.assert_allclose(rgb, 0.04 * OD + 0.5 * OD + 0.25, atol=1e-15)


SHINY_1E4 = Material(ka=0.1, kd=0.5, ks=0.8, n=1e4, od=(1, 0.2, 0.3), os=(0.9, 1, 1))


@pytest.mark.parametrize("material, tolerance", [(MATERIAL, 1e-14), (SHINY_1E4, 1e-11)])
def test_the_one_model_in_float64_agrees_with_itself_run_exactly(material, tolerance):
    """Random points and normals, a point light and a directional one, both eyes and both
    specular forms, degenerate rows included (a zero normal, the point at the light, the point
    at the eye): the compiled model (through the numpy entry point) against the same source run
    in rational arithmetic (core.analysis.exact.phong). The tolerance is a few ulps, scaled by
    the exponent n for the shiny material (d(x^n)/x^n = n dx/x)."""
    from core.analysis import exact
    rng = np.random.default_rng(7)
    count = 60
    p = rng.normal(size=(count, 3)) * 3.0
    n, _ = il.unit_rows(rng.normal(size=(count, 3)))
    n[0] = 0.0
    light_position = np.array([1.0, 2.0, 3.0])
    eye_point = np.array([0.0, -1.0, 8.0])
    p[1], p[2] = light_position, eye_point
    lights = [Light(position=tuple(light_position), attenuation=(0.5, 0.1, 0.01)),
              Light(direction=(0.0, 1.0, 1.0), intensity=(0.5, 0.4, 0.3))]
    packed_lights = il.pack_lights(lights)
    for two_sided in (False, True):
        surfaces = il.pack_surfaces([material], [two_sided])
        for eye in (il.Eye(eye_point, None), il.Eye(None, np.array([0.0, 0.3, 1.0]) / np.hypot(0.3, 1))):
            packed = il.pack_eye(eye)
            for halfway in (False, True):
                ours = il.illuminate(p, n, np.zeros(count, np.int64), surfaces, packed_lights,
                                     AMBIENT, packed, halfway)
                truth = [exact_phong(exact, p[i], n[i], material, lights, eye, halfway, two_sided)
                         for i in range(count)]
                assert np.abs(ours - np.array(truth, dtype=float)).max() <= tolerance
                assert np.all((ours >= 0.0) & (ours <= 1.0))



def exact_phong(exact, point, normal, material, lights, eye, halfway, two_sided):
    return exact.phong(point, normal, material, lights, AMBIENT,
                       None if eye.point is None else eye.point,
                       None if eye.direction is None else eye.direction, halfway, two_sided)


def test_the_numpy_entry_point_is_the_compiled_model_point_by_point():
    rng = np.random.default_rng(3)
    p = rng.normal(size=(50, 3))
    n, _ = il.unit_rows(rng.normal(size=(50, 3)))
    surfaces = il.pack_surfaces([MATERIAL], [True])
    lights = il.pack_lights([Light(position=(1.0, 2.0, 3.0))])
    eye = il.pack_eye(il.Eye(np.array([0.0, 0.0, 5.0]), None))
    many = il.illuminate(p, n, np.zeros(50, np.int64), surfaces, lights, AMBIENT, eye, False)
    one = [il.phong_point(*p[i], *n[i], 0, surfaces, lights, AMBIENT, eye, False) for i in range(50)]
    assert np.array_equal(many, np.array(one))


def test_to_uint8_rounds_half_up_and_clamps():
    values = np.array([0.0, 0.49 / 255, 0.5 / 255, 1.5 / 255, 254.5 / 255, 1.0, 1.7, -0.3])
    assert to_list(il.to_uint8(values)) == [0, 0, 1, 2, 255, 255, 255, 0]
    assert il.quantize(0.5 / 255) == 1 and il.quantize(-1.0) == 0 and il.quantize(2.0) == 255


def to_list(a):
    return [int(x) for x in a]


def test_eye_from_view_the_notes_example():
    # VRP (0,0,54), VPN +z, VUP +y, window (-1,17,-1,17), PRP (8,6,30): the PRP in world
    # coordinates is (8, 6, 84); the DOP is CW - PRP = (8,8,0) - (8,6,30) = (0, 2, -30).
    view = View(vrp=(0, 0, 54), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 17),
                prp=(8, 6, 30), front=10, back=-50)
    eye = il.eye_from_view(view, "perspective")
    np.testing.assert_allclose(eye.point, [8, 6, 84])
    assert eye.direction is None
    eye = il.eye_from_view(view, "parallel")
    assert eye.point is None
    np.testing.assert_allclose(eye.direction, np.array([0, -2, 30]) / math.sqrt(904))


def test_eye_from_a_rotated_view():
    # VPN = +x, VUP = +y: u = VUP x n = (0,0,-1), v = n x u = (0,1,0). PRP (0, 0, 10) in VRC
    # is VRP + 10 n.
    view = View(vrp=(1, 2, 3), vpn=(2, 0, 0), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                prp=(0, 0, 10), front=1, back=-1)
    np.testing.assert_allclose(il.eye_from_view(view, "perspective").point, [11, 2, 3])
    np.testing.assert_allclose(il.eye_from_view(view, "parallel").direction, [1, 0, 0])


def test_packing_rejects_a_light_without_position_or_direction():
    with pytest.raises(ValueError, match="light 2"):
        il.pack_lights([Light(position=(0, 0, 1)), Light(direction=(0, 0, 0))])


def test_unit_vectors_of_subnormal_and_huge_components():
    """1/m of a subnormal m overflows: both unit-vector forms divide instead, so a light
    1e-310 away, or a direction of 1e-310, still has a direction (and no NaN)."""
    from core.transforms import unit_rows
    from core.vectors import unit3
    for v in ([0.0, 3e-310, 4e-310], [3e300, 4e300, 0.0], [0.0, 0.0, 5e-324]):
        expected = np.array(v) / np.max(np.abs(v))
        expected /= np.linalg.norm(expected)
        x, y, z, length = unit3(*v)
        assert np.allclose([x, y, z], expected) and length > 0.0
        rows, lengths = unit_rows(np.array([v]))
        assert np.allclose(rows[0], expected) and lengths[0] > 0.0
