"""Reflection and refraction against hand values (the notes of April 9: Snell's law,
T = αI + βN), total internal reflection at the critical angle, a glass slab's lateral shift
traced through the whole renderer, and bad indices refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.raytrace import optics
from core.raytrace.optics import AIR, GLASS, WATER


def test_named_indices_are_the_notes():
    assert (AIR, WATER, GLASS) == (1.0003, 1.33, 1.52)
    assert optics.index_of_refraction("glass") == 1.52
    assert optics.index_of_refraction("Water") == 1.33


def test_reflection_hand_values():
    s = 1 / math.sqrt(2)
    # 45° onto the floor: (s, -s, 0) leaves as (s, s, 0).
    assert optics.reflect(s, -s, 0.0, 0.0, 1.0, 0.0) == (s, s, 0.0)
    # Head on: straight back.
    assert optics.reflect(0.0, 0.0, -1.0, 0.0, 0.0, 1.0) == (0.0, 0.0, 1.0)


def test_refraction_hand_values():
    # Air (1.0) into glass (1.5) at 30°: sin θ_t = sin 30° / 1.5 = 1/3.
    i = (math.sin(math.radians(30)), -math.cos(math.radians(30)), 0.0)
    ok, tx, ty, tz = optics.refract(*i, 0.0, 1.0, 0.0, 1.0, 1.5)
    assert ok
    assert tx == pytest.approx(1 / 3, abs=1e-15)
    assert ty == pytest.approx(-math.sqrt(1 - 1 / 9), abs=1e-15)
    assert tz == 0.0
    # The notes' α and β: T = αI + βN with α = 1/1.5, β = α cos θ_i − sqrt(1 − α²(1 − cos²θ_i)).
    alpha = 1 / 1.5
    cos_i = math.cos(math.radians(30))
    beta = alpha * cos_i - math.sqrt(1 - alpha ** 2 * (1 - cos_i ** 2))
    assert (tx, ty) == pytest.approx((alpha * i[0], alpha * i[1] + beta), abs=1e-15)
    # Normal incidence passes straight through, for any pair of indices.
    assert optics.refract(0.0, 0.0, -1.0, 0.0, 0.0, 1.0, AIR, WATER) == (True, 0.0, 0.0, -1.0)


def test_total_internal_reflection_at_the_critical_angle():
    critical = math.asin(1.0 / 1.5)                        # glass → air (1.0): 41.81°
    for angle, expect_ok in [(critical - 1e-6, True), (critical + 1e-6, False),
                             (math.radians(60), False)]:
        i = (math.sin(angle), -math.cos(angle), 0.0)
        ok, tx, ty, _ = optics.refract(*i, 0.0, 1.0, 0.0, 1.5, 1.0)
        assert ok == expect_ok
        if ok:                                             # just below: T grazes the surface
            assert tx == pytest.approx(1.0, abs=1e-5) and -2e-3 < ty <= 0.0
    # Exactly at it (up to rounding) the square root's argument is ~0: T along the surface.
    i = (math.sin(critical), -math.cos(critical), 0.0)
    ok, tx, ty, _ = optics.refract(*i, 0.0, 1.0, 0.0, 1.5, 1.0)
    assert not ok or (tx == pytest.approx(1.0, abs=1e-7) and abs(ty) < 1e-7)


def test_schlick_hand_values():
    f0 = ((1.0 - 1.5) / 2.5) ** 2                          # 0.04
    assert optics.schlick(1.0, 1.0, 1.0, 1.5) == pytest.approx(f0)
    assert optics.schlick(0.0, 0.5, 1.0, 1.5) == pytest.approx(1.0)
    # Leaving the denser medium, the angle on the rarer (transmitted) side counts.
    assert optics.schlick(0.9, 0.3, 1.5, 1.0) == pytest.approx(f0 + (1 - f0) * 0.7 ** 5)


@pytest.mark.parametrize("bad", [0.0, -1.5, float("nan"), float("inf"), "honey", None, True])
def test_bad_index_is_refused_with_a_message(bad):
    with pytest.raises(ValueError, match="ior"):
        optics.index_of_refraction(bad, "ior")


def test_bad_material_refused_by_the_renderer():
    from core.raytrace import geometry
    from core.scene.model import Material, Mesh, Scene
    mesh = Mesh(positions=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles=[[0, 1, 2]],
                material=Material(kt=0.5, ior=float("nan")), name="pane")
    with pytest.raises(ValueError, match="mesh 'pane': ior"):
        geometry.pack(Scene(name="s", meshes=[mesh], views=[]))
    mesh.material = Material(kr=1.5)
    with pytest.raises(ValueError, match="kr must be a number in"):
        geometry.pack(Scene(name="s", meshes=[mesh], views=[]))


def test_bad_index_in_a_scene_file_names_the_key_and_line():
    from core.scene.formats.errors import ReaderError
    from core.scene.formats.scenefile import read_scene_file
    text = ('[[geometry]]\nprimitive = "sphere"\nradius = 1.0\n'
            'material = { kt = 0.9, ior = -1.0 }\n')
    with pytest.raises(ReaderError) as caught:
        read_scene_file(text, "glass.toml")
    message = str(caught.value)
    assert "geometry[1].material.ior" in message and "positive" in message and ":4:" in message
    with pytest.raises(ReaderError, match="unknown medium 'honey'"):
        read_scene_file(text.replace("-1.0", '"honey"'), "glass.toml")


# --------------------------------------------------------------------------- through the renderer

def _slab_scene(edge_x: float, thickness: float, ior: float):
    """A glass slab (two planes, y = 2 and y = 2 − h, pure transmission) above a floor whose
    checker edge lies at x = edge_x: ambient-only colours A (x > edge) and B (x < edge)."""
    from core.scene.model import Light, Material, Scene
    from core.scene.primitives import Plane
    glass = Material(ka=0.0, kd=0.0, ks=0.0, kt=1.0, ior=ior)
    floor = Material(ka=1.0, kd=0.0, ks=0.0, od=(1.0, 0.0, 0.0))
    planes = [Plane((0.0, 2.0, 0.0), (0.0, 1.0, 0.0), glass),
              Plane((0.0, 2.0 - thickness, 0.0), (0.0, -1.0, 0.0), glass),
              Plane((edge_x, 0.0, 0.0), (0.0, 1.0, 0.0), floor, checker=100.0,
                    checker_color=(0.0, 0.0, 1.0))]
    return Scene(name="slab", meshes=[], views=[], primitives=planes, ambient=(1.0, 1.0, 1.0),
                 lights=[Light(position=(0.0, 50.0, 0.0))])


def _trace_one(scene, origin, direction, medium):
    from core.camera.view import View
    from core.renderers.raytrace.draw import TraceOptions, prepare, trace_rays
    view = View((0, 0, 0), (0, 0, 1), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 5), 1, -1)
    setup = prepare(scene, view, "parallel", (1, 1),
                    TraceOptions(shadows="off", medium=medium, adaptive_epsilon=0.0))
    raw = trace_rays(setup, np.array([origin]), np.array([direction]), np.array([0.0]),
                     np.array([np.inf]))
    return raw[0], setup.counts


def test_glass_slab_shifts_a_ray_by_the_analytic_offset():
    theta, h, n = math.radians(40), 1.0, 1.52
    origin = (0.0, 10.0, -50.0)                           # mid-square along z (e2 = -z)
    direction = (math.sin(theta), -math.cos(theta), 0.0)
    theta_t = math.asin(math.sin(theta) / n)              # Snell, with a vacuum outside
    straight = 10.0 * math.tan(theta)                     # where the ray meets y = 0 unbent
    # Through the slab the ray runs h tan θ_t sideways instead of h tan θ; measured across
    # the ray, that is the textbook shift d = h sin(θ − θ_t) / cos θ_t.
    expected = straight - h * (math.tan(theta) - math.tan(theta_t))
    assert (straight - expected) * math.cos(theta) == pytest.approx(
        h * math.sin(theta - theta_t) / math.cos(theta_t), rel=1e-12)
    # The floor's checker edge placed 1e-7 to either side of the expected point: the traced
    # ray must land on the matching side both times.
    for edge, colour in [(expected - 1e-7, (1.0, 0.0, 0.0)), (expected + 1e-7, (0.0, 0.0, 1.0))]:
        rgb, counts = _trace_one(_slab_scene(edge, h, n), origin, direction, 1.0)
        assert tuple(rgb) == colour
        assert counts[3] == 2                              # refracted in, refracted out
    # Without the slab's bending (index 1): the ray lands at the unbent point.
    rgb, _ = _trace_one(_slab_scene(straight - 1e-7, h, 1.0), origin, direction, 1.0)
    assert tuple(rgb) == (1.0, 0.0, 0.0)


def test_total_internal_reflection_in_the_renderer():
    """A ray inside glass meeting the surface beyond the critical angle is reflected whole."""
    from core.scene.model import Material, Scene
    from core.scene.primitives import Plane
    glass = Material(ka=0.0, kd=0.0, ks=0.0, kt=1.0, ior=1.5)
    scene = Scene(name="tir", meshes=[], views=[], ambient=(1.0, 1.0, 1.0), lights=[],
                  background=(0.0, 1.0, 0.0),
                  primitives=[Plane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0), glass)])
    angle = math.radians(60)                              # beyond 41.8°
    rgb, counts = _trace_one(scene, (0.0, -1.0, 0.0), (math.sin(angle), math.cos(angle), 0.0), 1.0)
    # Starting below the plane = inside the glass; the ray is turned back down to the sky.
    assert counts[4] == 1 and counts[2] == 1 and counts[3] == 0
    assert tuple(rgb) == (0.0, 1.0, 0.0)
