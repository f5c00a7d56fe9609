"""A scene whose material has k_t > 0 is drawn with interpolated transparency by the z-buffer
family unless it or the user says otherwise (``--transparency off``); the plan says why.

Oracle for the blend: the opaque frame and the frame without the glass, combined by hand with
FvDFH's I = (1 - k_t) I_near + k_t I_far at pixels where the glass is the only layer in front.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from core import RenderSettings, render
from core.scene.formats import load_scene
from core.scene.formats.scenefile import read_scene_file
from core.settings import needed_transparency

PANE = """
name = "pane over a floor"
shading = "flat"
background = [0, 0, 0]
[[light]]
direction = [0, 0, 1]
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-1, 1, -1, 1]
prp = [0, 0, 5]
front = 2
back = -3
[[geometry]]
name = "floor"
generator = "plane"
params = { size = 6 }
transform = { rotate = [90, 0, 0], translate = [0, 0, -1] }
material = { ka = 0, kd = 1, ks = 0, od = [1, 0, 0] }
[[geometry]]
name = "glass"
generator = "plane"
params = { size = 1 }
transform = { rotate = [90, 0, 0] }
material = { ka = 0, kd = 1, ks = 0, od = [0, 0, 1], kt = 0.25 }
"""


def _scene(extra: str = ""):
    return read_scene_file(extra + PANE, "pane.toml")


def test_a_transparent_material_turns_interpolated_transparency_on():
    scene = _scene()
    assert scene.transparency is None and needed_transparency(scene) == "interpolated"
    settings = RenderSettings.for_scene(scene, size=(40, 40))
    assert settings.transparency == "interpolated"
    frame = render(scene, scene.views[0], settings)
    stage = next(s for s in frame.plan if s.name == "transparency")
    assert stage.runs and "glass has k_t > 0, so the scene needs it" in stage.reason
    assert not any("transparency" in note for note in frame.stats["not drawn"])
    opaque = render(scene, scene.views[0], settings.replace(transparency="off"))
    off = next(s for s in opaque.plan if s.name == "transparency")
    assert not off.runs and off.reason.startswith("off: glass (k_t > 0) drawn opaque")
    behind = dataclasses.replace(scene, meshes=scene.meshes[:1])
    floor = render(behind, behind.views[0], settings).color.astype(float)
    # the centre pixel: glass (blue 1 * N.L) over the red floor
    y, x = 20, 20
    expected = 0.75 * opaque.color[y, x].astype(float) + 0.25 * floor[y, x]
    assert np.abs(frame.color[y, x] - expected).max() <= 1.0


def test_what_the_file_says_wins_and_opaque_scenes_stay_opaque():
    scene = _scene('transparency = "off"\n')
    assert RenderSettings.for_scene(scene).transparency == "off"
    cube = read_scene_file('[[geometry]]\ngenerator = "cube"\n', "cube.toml")
    assert RenderSettings.for_scene(cube).transparency == "off"
    stage = next(s for s in render(cube, cube.views[0], RenderSettings.for_scene(
        cube, size=(16, 16))).plan if s.name == "transparency")
    assert not stage.runs and stage.reason == "no material has k_t > 0"


def test_the_shipped_glass_scenes_and_the_ray_tracer():
    scene = load_scene("scenes/whitted.toml")
    assert RenderSettings.for_scene(scene, renderer="zbuffer").transparency == "interpolated"
    traced = render(scene, scene.views[0], RenderSettings.for_scene(scene, size=(16, 12)))
    stage = next(s for s in traced.plan if s.name == "transparency")
    assert traced.stats["renderer"] == "raytrace" and not stage.runs
    assert stage.reason == "raytrace refracts through k_t > 0 itself"
