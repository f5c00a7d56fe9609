"""Phong's float32 pixel step (core.shading.wide) against the float64 textbook kernel.

The two are twins: the same model, float32 in 8-wide passes against float64 one pixel at a
time. The stated tolerance is one level of the byte (1/255) on every pixel, with few pixels
differing at all; extreme inputs (huge or tiny scenes, zero normals, a light on the surface)
fall back to float64 pixel by pixel and must match it exactly.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from app.distribution.warmup import shipped_scenes
from core.context import RenderContext
from core.paths import SCENES_DIR
from core.render import render
from core.scene.formats import load_scene
from core.settings import RenderSettings
from core.shading.wide import float32_is_exact_enough

SIZE = (160, 120)


def _both(scene, view=None, shading="phong", **overrides):
    # the z-buffer, whose shading modes the float32 passes serve, whatever the scene's own
    # renderer (the two-pass scene's would solve its radiosity for every picture)
    overrides.setdefault("renderer", "zbuffer")
    settings = RenderSettings.for_scene(scene, shading=shading, size=SIZE, **overrides)
    view = view or scene.views[0]
    wide = render(scene, view, settings, RenderContext())
    exact = render(scene, view, dataclasses.replace(settings, shading_precision="float64"),
                   RenderContext())
    return wide, exact


def _difference(a, b) -> np.ndarray:
    return np.abs(a.color.astype(int) - b.color.astype(int)).max(axis=2)


# Shipped scenes with no triangle to light (lines only, or a volume alone): no precision can
# change them (checked below).
LINES_ONLY = {"house.toml", "house_depth_cue.toml", "house_projections.toml", "volume_alone.toml"}


def test_the_scenes_left_out_have_nothing_to_light():
    for name in LINES_ONLY:
        assert load_scene(SCENES_DIR / name).triangle_count == 0, name


@pytest.mark.parametrize("path", [p for p in shipped_scenes() if p.name not in LINES_ONLY],
                         ids=lambda p: p.name)
def test_float32_is_within_one_level_of_float64_on_every_shipped_scene(path):
    scene = load_scene(path)
    assert scene.views and scene.triangle_count, path.name
    for projection, shading in (("perspective", "phong"), ("parallel", "phong"),
                                ("perspective", "flat"), ("perspective", "gouraud")):
        wide, exact = _both(scene, projection=projection, shading=shading)
        error = _difference(wide, exact)
        assert error.max() <= 1, (path.name, projection, shading, int(error.max()))
        # A level differs only where a value sits within float32's rounding of a half level.
        assert np.count_nonzero(error) <= 0.002 * error.size, (path.name, projection, shading)


def test_halfway_specular_and_two_sided_meshes_agree():
    scene = load_scene(SCENES_DIR / "interpenetrating.tri")      # open meshes: two-sided
    scene = dataclasses.replace(scene, specular="halfway")
    wide, exact = _both(scene)
    assert _difference(wide, exact).max() <= 1
    assert np.count_nonzero(wide.color != wide.color[0, 0]) > 1000   # something was drawn


@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
@pytest.mark.parametrize("scale", [1e-25, 1e25])
def test_extreme_scales_fall_back_to_float64_and_match_it(scale, shading):
    """Squares of 1e-25 or 1e25 leave float32's range: every pixel is flagged and done by
    the float64 model, so the picture is the textbook kernel's exactly."""
    from core.analysis.stability_kit import scaled_scene
    scene = scaled_scene(load_scene(SCENES_DIR / "torus.toml"), scale)
    wide, exact = _both(scene, shading=shading)
    assert np.count_nonzero(exact.color != exact.color[0, 0]) > 1000
    np.testing.assert_array_equal(wide.color, exact.color)


def test_fractional_exponents_use_the_float64_kernel():
    scene = load_scene(SCENES_DIR / "torus.toml")
    mesh = scene.meshes[0]
    material = dataclasses.replace(mesh.material, n=7.5)
    scene = dataclasses.replace(scene, meshes=[dataclasses.replace(mesh, material=material)]
                                + list(scene.meshes[1:]))
    from core.shading.illumination import pack_surfaces
    assert not float32_is_exact_enough(pack_surfaces([m.material for m in scene.meshes],
                                                     [False] * len(scene.meshes)))
    wide, exact = _both(scene)
    np.testing.assert_array_equal(wide.color, exact.color)


@pytest.mark.parametrize("intensity, fits", [(1.0, True), (1e29, True), (1e31, False),
                                              (1e308, False), (np.inf, False), (np.nan, False)])
def test_lights_past_float32_use_the_float64_kernels(intensity, fits):
    """I x k_d x O_d is formed in float32 by the passes: past 1e30 it would overflow, and
    inf x 0 is NaN where the light does not reach (the stability suite's 1e308 lights)."""
    from core.scene.model import Light, Material
    from core.shading.illumination import pack_ambient, pack_lights, pack_surfaces
    from core.shading.shade import float32_holds_the_terms
    surfaces = pack_surfaces([Material(ka=0.2, kd=0.6, ks=0.3, n=20.0)], [False])
    bright = pack_lights([Light(intensity=(intensity, 1.0, 1.0), position=(0.0, 0.0, 4.0))])
    normal = pack_lights([Light(intensity=(1.0, 1.0, 1.0), position=(0.0, 0.0, 4.0))])
    ambient = pack_ambient((0.1, 0.1, 0.1))
    assert float32_holds_the_terms(surfaces, bright, ambient) == fits
    assert float32_holds_the_terms(surfaces, normal, pack_ambient((intensity, 0, 0))) == fits
    far = normal.copy()
    far[0, 7:10] = (1.0, 0.0, intensity)           # an attenuation coefficient
    assert float32_holds_the_terms(surfaces, far, ambient) == fits


@pytest.mark.parametrize("shading", ["flat", "gouraud", "phong"])
def test_very_bright_lights_light_every_face_finite(shading):
    """Lit in the vertex step (a small scene), every face or vertex colour is a number."""
    from core.analysis.stability_cases import _lit_sphere
    from core.scene.model import Light, Material
    lights = [Light(intensity=(1e308,) * 3, position=(0.0, 0.0, 4.0)),
              Light(intensity=(1e308,) * 3, direction=(0.0, 0.0, 1.0))]
    scene = _lit_sphere(Material(ka=0.2, kd=0.6, ks=0.3, n=20.0), lights)
    seen = {}
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, shading=shading,
                                                                   size=SIZE),
                   RenderContext(), inspect=lambda stage, found: seen.update(found))
    for name in ("face_rgb", "vertex_attrs"):
        if name in seen:
            assert np.all(np.isfinite(seen[name])), name
    covered = np.any(frame.color != frame.color[0, 0], axis=2)
    assert covered.sum() > 500 and np.all(frame.color[covered] == 255)


def test_the_setting_is_checked():
    with pytest.raises(ValueError, match="shading_precision must be one of float32, float64"):
        RenderSettings(shading_precision="float16")


def test_the_bench_times_both_precisions():
    from app.bench.bench import bench_scene, format_precision, precision_rows
    rows = precision_rows([bench_scene(1000)], "perspective", (64, 48), frames=2, warmup=1)
    assert [r["shading"] for r in rows] == ["flat", "gouraud", "phong"]
    for r in rows:
        for key in ("float32 pixel step ms", "float64 pixel step ms", "float32 frame ms",
                    "float64 frame ms"):
            assert r[key] > 0.0, (r["shading"], key)
    text = format_precision(rows)
    assert "float32 passes against the float64 kernels" in text and "phong" in text
