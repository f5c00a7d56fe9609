"""Depth shading (the notes: colour from depth alone, darker at lower elevations) and the
generated terrain."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.view import View
from core.context import RenderContext
from core.plan import plan
from core.render import render
from core.scene.generators import terrain
from core.scene.model import Mesh, Scene
from core.settings import RenderSettings
from core.shading.depth import GREY, TERRAIN, colour_map

LOW = tuple(int(255 * c + 0.5) for c in TERRAIN[0][1:])     # the map's ends, rounded half up
HIGH = tuple(int(255 * c + 0.5) for c in TERRAIN[-1][1:])


def _steps() -> Scene:
    """Two horizontal squares seen from above: the left at height 0, the right at height 1."""
    meshes = []
    for x, y in ((-1.5, 0.0), (1.5, 1.0)):
        p = np.array([[x - 1, y, -1], [x + 1, y, -1], [x + 1, y, 1], [x - 1, y, 1]])
        meshes.append(Mesh(positions=p, triangles=[[0, 2, 1], [0, 3, 2]]))
    view = View(vrp=(0, 0, 0), vpn=(0, 1, 0), vup=(0, 0, -1), window=(-3, 3, -3, 3),
                prp=(0, 0, 10), front=5.0, back=-5.0)
    return Scene(name="steps", meshes=meshes, views=[view], shading="depth")


@pytest.mark.parametrize("renderer", ["zbuffer", "bsp", "depth-sort"])
@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_height_through_the_terrain_map(renderer, projection):
    scene = _steps()
    frame = render(scene, scene.views[0], RenderSettings.for_scene(
        scene, renderer=renderer, projection=projection, size=(60, 60)), RenderContext())
    assert tuple(frame.color[30, 15]) == LOW        # height 0: the lowest colour (dark)
    assert tuple(frame.color[30, 45]) == HIGH       # height 1: the highest (snow)
    assert sum(LOW) < sum(HIGH)                     # "darker colours at lower elevations"


def test_view_depth_is_brighter_nearer():
    scene = _steps()
    frame = render(scene, scene.views[0], RenderSettings.for_scene(
        scene, size=(60, 60), depth_shading="view"), RenderContext())
    near, far = frame.color[30, 45].astype(int), frame.color[30, 15].astype(int)
    assert near.sum() > far.sum() and near[0] == near[1] == near[2]     # grey, brighter nearer
    grey = colour_map(GREY)
    assert np.allclose(grey[0], GREY[0][1:]) and np.allclose(grey[-1], GREY[-1][1:])


def test_plan_says_no_light():
    stages = {s.name: s for s in plan(_steps(), "perspective", "depth")}
    assert stages["depth shading"].runs
    assert not stages["illuminate pixels"].runs and not stages["vertex normals"].runs
    assert "no light" in stages["vertex normals"].reason


def test_terrain_generator():
    mesh = terrain(size=4.0, resolution=8, height=2.0, seed=3)
    assert mesh.positions.shape == (81, 3) and mesh.triangles.shape == (128, 3)
    assert np.isclose(mesh.positions[:, 1].min(), 0.0) and np.isclose(mesh.positions[:, 1].max(), 2.0)
    assert np.allclose(np.ptp(mesh.positions[:, [0, 2]], axis=0), 4.0)
    assert np.array_equal(mesh.positions, terrain(size=4.0, resolution=8, height=2.0, seed=3).positions)
    assert not np.array_equal(mesh.positions, terrain(size=4.0, resolution=8, height=2.0, seed=4).positions)
    with pytest.raises(ValueError, match="resolution must lie in"):
        terrain(resolution=0)
