"""The toy ``normals`` renderer: a sphere's pixels coloured (N + 1) / 2."""

import numpy as np

from core import RenderSettings, render
from core.camera.view import View
from core.scene.generators import uv_sphere
from core.scene.model import Scene


def test_a_sphere_seen_along_z_is_blue_in_the_middle_and_red_on_the_right():
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1.25, 1.25, -1.25, 1.25),
                prp=(0, 0, 5), front=2, back=-2, label="front")
    scene = Scene(name="s", meshes=[uv_sphere(1.0, segments=64, rings=32)], views=[view])
    color = render(scene, view, RenderSettings(renderer="normals", projection="parallel",
                                               size=(41, 41))).color.astype(int)
    # N = (0, 0, 1) at the centre: (0.5, 0.5, 1) -> 128, 128, 255; the facet there is tilted
    # by up to half a facet, pi/64 ~ 0.05 rad: within 0.05 / 2 x 255 ~ 7 levels
    assert np.abs(color[20, 20] - [128, 128, 255]).max() <= 7
    # near the right edge (x = 0.95): N close to +x, red high, blue low
    assert color[20, 36, 0] > 230 and color[20, 36, 2] < 200
    assert list(color[0, 0]) == [0, 0, 0]           # the background
