"""The compiled wireframe (core/pipeline/wireframe.py) draws exactly the pixels of the numpy
reference stages: clip.clip_lines -> project.project_lines -> raster_lines.draw_lines."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.view import normalizing_transform
from core.paths import SCENES_DIR
from core.pipeline import clip, project, raster_lines
from core.pipeline.wireframe import draw_edges
from core.scene.formats import load_scene
from core.transforms import apply

WHITE = np.array([255, 255, 255], np.uint8)


def _both(points, edges, projection, z_min, size, keep_aspect=False):
    width, height = size
    vp = (0.0, float(width), 0.0, float(height)) if not keep_aspect else (40.0, width - 40.0,
                                                                          10.0, height - 10.0)
    ref = np.zeros((height, width, 3), np.uint8)
    q0, q1 = clip.clip_lines(points[edges[:, 0]], points[edges[:, 1]], projection, z_min)
    raster_lines.draw_lines(ref, project.project_lines(q0, projection, vp),
                            project.project_lines(q1, projection, vp), WHITE)
    ours = np.zeros_like(ref)
    m = project.m_vv3dv(*vp)
    if projection == "perspective":
        m = m @ project.m_per(-1.0)
    drawn = draw_edges(points, edges, clip.planes(projection, z_min), m, ours, WHITE)
    return ref, ours, drawn, len(q0)


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("size", [(500, 500), (333, 217)])
def test_every_house_view_draws_the_same_pixels(projection, size):
    scene = load_scene(SCENES_DIR / "house.toml")
    mesh = scene.meshes[0]
    for view in scene.views:
        try:
            n, z_min = normalizing_transform(view, projection)
        except ValueError:
            continue                      # invalid for this projection
        points = apply(n, mesh.positions)[:, :3]
        ref, ours, drawn, expected = _both(points, mesh.all_edges(), projection, z_min, size)
        assert drawn == expected
        assert np.array_equal(ref, ours), view.label


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_random_segments_through_the_volume(projection):
    rng = np.random.default_rng(3)
    points = rng.uniform(-2.5, 1.5, (600, 3))
    edges = rng.integers(0, 600, (2000, 2))
    for keep in (False, True):
        ref, ours, drawn, expected = _both(points, edges, projection, -0.1, (257, 190), keep)
        assert drawn == expected and 0 < drawn < len(edges)
        assert np.array_equal(ref, ours)
