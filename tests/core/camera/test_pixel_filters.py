"""Reconstruction filters for supersampled frames against hand values: a vertical edge's
coverage under a tent of radius 1 (the integral of the tent over the covered part, worked by
hand), the filters' own shapes at chosen distances, and the messages for bad radii."""

from __future__ import annotations

import numpy as np
import pytest

from core import RenderSettings, render
from core.camera.filters import reconstruct, regular_grid, weight
from core.scene.formats import load_scene


def _edge_samples(edge_x: float, width: int = 6, height: int = 3, side: int = 16):
    """A white half-plane x < edge_x sampled on a side x side grid per pixel (255 / 0)."""
    xs = (np.arange(width * side) + 0.5) / side
    big = np.where(xs < edge_x, 255, 0).astype(np.uint8)
    return np.repeat(np.repeat(big[None, :, None], height * side, axis=0), 3, axis=2)


def test_a_tent_of_radius_one_gives_the_analytic_coverage():
    # the edge at x = 2.75: pixel 2 (centre 2.5) is covered up to 0.25 right of its centre
    big = _edge_samples(2.75)
    out = reconstruct(*regular_grid(big, 16), "tent", 1.0)[1]
    # ∫ tent over (-1, 0.25) = 1 - (1 - 0.25)^2 / 2; pixel 3 (centre 3.5): ∫ over (-1, -0.75)
    assert abs(out[2, 0] - 255 * (1 - 0.75 ** 2 / 2)) <= 1.0
    assert abs(out[3, 0] - 255 * (0.25 ** 2 / 2)) <= 1.0
    assert out[1, 0] == pytest.approx(255.0) and out[4, 0] == pytest.approx(0.0)
    half = reconstruct(*regular_grid(_edge_samples(2.5), 16), "tent", 1.0)[1]
    assert abs(half[2, 0] - 127.5) <= 1.0           # half covered: exactly half


def test_the_box_of_half_a_pixel_is_the_film_mean():
    big = _edge_samples(2.3)
    out = reconstruct(*regular_grid(big, 16), "box", 0.5)[1]
    assert out[2, 0] == pytest.approx(255 * 5 / 16)     # 5 of 16 sample columns below 2.3


def test_the_filter_shapes_by_hand():
    assert weight("tent", [0, 0.5, 1.0], 1.0).tolist() == [1.0, 0.5, 0.0]
    assert weight("gaussian", [0.5], 1.5)[0] == pytest.approx(np.exp(-0.5))   # sigma 0.5
    # Mitchell-Netravali, B = C = 1/3: k(0) = (6 - 2B)/6 = 8/9, k(1) = 1/18, k(2) = 0
    assert weight("mitchell", [0.0, 1.0, 1.999999], 2.0) == pytest.approx([8 / 9, 1 / 18, 0],
                                                                         abs=1e-5)
    assert weight("mitchell", [1.5], 2.0)[0] < 0                   # its negative lobe


def test_a_filtered_frame_through_the_front_door():
    scene = load_scene("scenes/cube.toml")
    settings = RenderSettings.for_scene(scene, size=(48, 36), samples=16)
    box = render(scene, scene.views[0], settings)
    same = render(scene, scene.views[0], settings.replace(pixel_filter="box", filter_radius=0.49))
    assert np.abs(box.color.astype(int) - same.color.astype(int)).max() <= 1
    tent = render(scene, scene.views[0], settings.replace(pixel_filter="tent"))
    assert tent.stats["pixel filter"] == "tent, radius 1"
    assert 0 < np.abs(tent.color.astype(int) - box.color.astype(int)).max() < 128


@pytest.mark.parametrize("radius", [0, 1e9, -1])
def test_a_bad_radius_is_one_message(radius):
    with pytest.raises(ValueError, match=r"the filter radius must be above 0 and at most 8 "
                                         r"pixels, not "):
        RenderSettings(pixel_filter="tent", filter_radius=radius)


@pytest.mark.parametrize("samples", [0, 1_000_000])
def test_a_bad_sample_count_is_one_message(samples):
    with pytest.raises(ValueError, match=r"samples per pixel must be a whole number from 1 to "
                                         r"256, not "):
        RenderSettings(samples=samples)


def test_the_ray_tracer_reconstructs_with_the_same_filters():
    scene = load_scene("scenes/whitted.toml")
    settings = RenderSettings.for_scene(scene, size=(40, 30), samples=4, renderer="raytrace")
    box = render(scene, scene.views[0], settings).color.astype(int)
    same = render(scene, scene.views[0],
                  settings.replace(filter_radius=0.49)).color.astype(int)   # the same samples
    assert np.abs(box - same).max() <= 1
    tent = render(scene, scene.views[0], settings.replace(pixel_filter="gaussian"))
    assert tent.stats["pixel filter"] == "gaussian, radius 1.5"
    assert 0 < np.abs(tent.color.astype(int) - box).max() < 160
