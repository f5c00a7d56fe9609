"""Lighting models (core.shading.models): the registry, the generated seam, the scene keys,
and the Cook–Torrance model against values derived by hand (FvDFH 16.7).

The hand-derived cases put N along z and choose L and V so that the half vector and the
cosines are simple fractions; the expected values are computed from those fractions in exact
rational arithmetic (Fraction), with Beckmann's exponential the one transcendental factor.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from core.scene.model import Light, Material, Mesh, Scene
from core.camera.view import View
from core.shading import illumination as il
from core.shading.models import (lighting_model_names, model_id, with_model)
from core.shading.models.dispatch import dispatch_source, illuminate


def _material(model: str | None = None, **parameters) -> Material:
    m = Material(ka=0.0, kd=0.0, ks=0.5, n=20.0, od=(0.8, 0.8, 0.8))
    return with_model(m, model, parameters) if model else m


def test_phong_is_model_zero_and_the_default():
    assert lighting_model_names()[0] == "phong"
    assert model_id("phong") == 0
    assert il.pack_surfaces([Material()], [False])[0, il.MODEL] == 0.0
    with pytest.raises(ValueError, match="lighting model must be one of phong"):
        model_id("no-such-model")


def test_the_generated_seam_has_one_branch_per_model():
    source = dispatch_source(("phong", "a-b", "c"))
    assert "if model == 1:\n        return a_b_point(" in source
    assert "if model == 2:\n        return c_point(" in source
    # model 0 (and any number no model has) falls through to Phong
    assert "    return phong_point(px, py, pz" in source
    # the calling seam: the same branches, the models after Phong called, not inlined
    calling = source[source.index("def light_point_calling("):source.index("def glossy(")]
    assert "if model == 1:\n        return a_b_point_call(" in calling
    assert "    return phong_point(px, py, pz" in calling
    assert source.count("def ") == 4


def test_the_calling_seam_lights_as_the_inlined_one():
    """light_point_calling (the ray tracers' and the ray marcher's: Cook-Torrance called)
    against light_point (the z-buffer's: inlined), a consistency check of one model's two
    compiled forms: Phong and Cook-Torrance rows, both halfway settings, within 1e-12."""
    import numba

    from core.shading.models.dispatch import light_point, light_point_calling

    @numba.njit
    def both(p, n, which, surfaces, lights, ambient, eye, halfway, out):
        for i in range(p.shape[0]):
            a = light_point(p[i, 0], p[i, 1], p[i, 2], n[i, 0], n[i, 1], n[i, 2], which[i],
                            surfaces, lights, ambient, eye, halfway)
            b = light_point_calling(p[i, 0], p[i, 1], p[i, 2], n[i, 0], n[i, 1], n[i, 2],
                                    which[i], surfaces, lights, ambient, eye, halfway)
            for c in range(3):
                out[i, c], out[i, 3 + c] = a[c], b[c]

    rng = np.random.default_rng(5)
    p, n = rng.normal(size=(300, 3)), rng.normal(size=(300, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    surfaces = il.pack_surfaces([_material(), _material("cook-torrance", roughness=0.3)],
                                [False, True])
    lights = il.pack_lights([Light(position=(2, 3, 4)), Light(direction=(0, 1, 1))])
    eye = np.array([il.EYE_POINT, 0.5, 0.2, 6.0])
    which = rng.integers(0, 2, 300)
    for halfway in (False, True):
        out = np.empty((300, 6))
        both(p, n, which, surfaces, lights, np.array([0.2, 0.2, 0.2]), eye, halfway, out)
        assert np.abs(out[:, :3] - out[:, 3:]).max() <= 1e-12
        assert out[which == 1, 3:].max() > 0.05           # the Cook-Torrance rows are lit


def test_a_phong_row_lights_as_phong_point_does():
    """The seam's numpy entry and the Phong model's own give the same bits."""
    rng = np.random.default_rng(3)
    p = rng.normal(size=(200, 3))
    n = rng.normal(size=(200, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    surfaces = il.pack_surfaces([Material(), Material(ka=0.1, ks=0.9, n=7)], [False, True])
    lights = il.pack_lights([Light(position=(2, 3, 4)), Light(direction=(0, 1, 1))])
    eye = np.array([il.EYE_POINT, 0.5, 0.2, 6.0])
    which = rng.integers(0, 2, 200)
    for halfway in (False, True):
        a = illuminate(p, n, which, surfaces, lights, np.array([0.2, 0.2, 0.2]), eye, halfway)
        b = il.illuminate(p, n, which, surfaces, lights, np.array([0.2, 0.2, 0.2]), eye, halfway)
        assert np.array_equal(a, b)
