"""Gradient-shaded volumes are lit by their material's lighting model (core.volume.raymarch
through core.shading.models.dispatch.light_point), as every other renderer's surfaces are.

The data is a ramp falling along z, so every sample has the normal N = +z exactly (the
trilinear field of linear data is that data; its central differences are exact), and the
transfer function is one colour and one extinction: every sample along a ray is lit alike,
so the marched colour is ``lit · (1 − T)`` and ``C / (1 − T)`` is one sample's lit colour.
L and V are the Cook–Torrance tests' "tilted" pair (tests/core/shading/test_cook_torrance.py):
mirror images at cos 4/5 about N, so H = N, D = 1/(4 m²), G = 1, V·H = 4/5, and Phong's R is V.
"""

from __future__ import annotations

from fractions import Fraction as Q

import numpy as np
import pytest

from core import RenderSettings, render
from core.camera.view import View
from core.inspect import inspect_pixel
from core.scene.model import Light, Material, Scene
from core.shading import illumination as il
from core.shading.models import with_model
from core.volume.data import Volume, attach_volumes, volumes_of
from core.volume.raymarch import march_volume
from core.renderers.volume.draw import step_of

C, SIGMA = Q(1, 2), 1.0                # the sample's colour (grey) and extinction
KD, KS = Q(1, 4), Q(1, 2)
LIGHT, TOWARD_VIEWER = (0.6, 0.0, 0.8), (-0.6, 0.0, 0.8)
F0_RGB = (0.25, 0.5, 0.75)


def _ramp(material) -> Volume:
    """9³ samples over [−1, 1]³, value 8 − k: −∇f is +z."""
    k = np.arange(9, dtype=np.float32)
    values = np.broadcast_to(8.0 - k, (9, 9, 9)).astype(np.float32)
    c = float(C)
    return Volume(values=values, spacing=(0.25, 0.25, 0.25), lighting="gradient",
                  material=material, name="ramp",
                  transfer=np.array([[0.0, c, c, c, SIGMA], [8.0, c, c, c, SIGMA]]))


def _one_sample_colour(volume, lighting_model=None) -> np.ndarray:
    """The lit colour of the samples along the ray through the origin towards −V, kept a
    world length of 1 about the origin (its gradient probes stay inside the grid)."""
    v = np.array(TOWARD_VIEWER)
    color, through, _ = march_volume(
        volume, (2.0 * v)[None], (-v)[None], np.array([1.5]), np.array([2.5]),
        step_of(volume), il.pack_lights([Light(direction=LIGHT)]), np.zeros(3),
        np.array([il.EYE_DIRECTION, *TOWARD_VIEWER]), False, lighting_model)
    assert through[0] == pytest.approx(np.exp(-SIGMA * 1.0), rel=1e-12)
    return color[0] / (1.0 - through[0])


def _cook_torrance(m, f0) -> float:
    """The model by hand at this geometry: k_d O_d (N·L) + k_s F D G / (N·V)."""
    nl = nv = vh = Q(4, 5)
    d, g = 1 / (4 * m * m), 1
    f = Q(f0) + (1 - Q(f0)) * (1 - vh) ** 5
    return float(KD * C * nl + KS * f * d * g / nv)


def _material(**model) -> Material:
    plain = Material(ka=0.0, kd=float(KD), ks=float(KS), n=10)
    return with_model(plain, "cook-torrance", model) if model else plain


def test_a_phong_volume_sample_is_phongs_value_by_hand():
    # R = 2 (N·L) N − L = V: (R·V)^n = 1; O_s is white
    expected = float(KD * C * Q(4, 5) + KS)
    assert _one_sample_colour(_ramp(_material())) == pytest.approx([expected] * 3, rel=1e-12)


def test_a_volume_over_the_gradient_budget_differences_each_sample_to_the_same_value(
        monkeypatch):
    import core.volume.raymarch as raymarch
    monkeypatch.setattr(raymarch, "GRADIENT_VOXELS", 0)
    assert raymarch.sample_gradients(_ramp(_material())).shape == (1, 1, 1, 3)
    expected = float(KD * C * Q(4, 5) + KS)
    assert _one_sample_colour(_ramp(_material())) == pytest.approx([expected] * 3, rel=1e-12)


def test_a_cook_torrance_volume_sample_is_the_models_value_by_hand():
    got = _one_sample_colour(_ramp(_material(roughness=0.5, f0=F0_RGB)))
    expected = [_cook_torrance(Q(1, 2), f0) for f0 in F0_RGB]
    assert got == pytest.approx(expected, rel=1e-12)
    # the expected direction: Phong's white highlight (0.6 in every channel) becomes one
    # coloured by F0, dimmer in each channel, red least
    phong = _one_sample_colour(_ramp(_material()))
    assert np.all(got < phong) and got[0] < got[1] < got[2]


def test_the_override_lights_a_phong_volume_with_the_models_defaults():
    got = _one_sample_colour(_ramp(_material()), lighting_model="cook-torrance")
    # the registered defaults: roughness 0.3, f0 0.04
    assert got == pytest.approx([_cook_torrance(Q(3, 10), 0.04)] * 3, rel=1e-12)


def _scene(material) -> Scene:
    view = View(vrp=(0, 0, 0), vpn=TOWARD_VIEWER, vup=(0, 1, 0), window=(-0.5, 0.5, -0.5, 0.5),
                prp=(0, 0, 6), front=0.45, back=-0.45, label="inside the ramp")
    scene = Scene(name="ramp", meshes=[], views=[view], background=(0, 0, 0),
                  ambient=(0.0, 0.0, 0.0), lights=[Light(direction=LIGHT)])
    attach_volumes(scene, [_ramp(material)])
    return scene


def test_render_and_the_inspector_apply_the_override_to_volumes():
    def frame(scene, model=None):
        settings = RenderSettings.for_scene(scene, renderer="volume", size=(9, 9),
                                            projection="parallel", lighting_model=model)
        f = render(scene, scene.views[0], settings)
        assert f.message is None and f.stats["volumes marched"] == 1
        return f, settings

    phong = _scene(_material())
    overridden, settings = frame(phong, "cook-torrance")
    named, _ = frame(_scene(_material(roughness=0.3, f0=(0.04,) * 3)))
    plain, _ = frame(phong)
    assert np.array_equal(overridden.color, named.color)
    assert overridden.color[4, 4, 0] < plain.color[4, 4, 0]        # the dimmer highlight
    record = inspect_pixel(phong, phong.views[0], settings, 4, 4)
    assert record["color"] == overridden.color[4, 4].tolist()
    assert volumes_of(phong)[0].material.extra == {}               # the scene is not changed
