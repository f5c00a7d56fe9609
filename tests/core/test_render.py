"""The assembled pipeline: golden images of every shading mode, the plan against what ran."""

from __future__ import annotations

import numpy as np
import pytest

from core.scene.formats import load_scene
from core.paths import SCENES_DIR
from core.plan import plan

from core.render import render
from core.settings import SHADINGS, RenderSettings

MODES = SHADINGS


@pytest.mark.parametrize("shading", MODES)
@pytest.mark.parametrize("name", ["torus.toml", "interpenetrating.tri"])
def test_golden_shading(golden, name, shading):
    scene = load_scene(SCENES_DIR / name)
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, projection="perspective", shading=shading, size=(500, 500)))
    assert frame.message is None
    golden(f"{name.split('.')[0]}_{shading}", frame.color)


def test_flat_plan_computes_no_vertex_normals():
    scene = load_scene(SCENES_DIR / "torus.toml")
    stages = {s.name: s for s in plan(scene, "perspective", "flat")}
    assert not stages["vertex normals"].runs and stages["face normals"].runs
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, projection="perspective", shading="flat", size=(64, 64)))
    assert "vertex normals" not in frame.stats["computed"]
    assert "face normals" in frame.stats["computed"]
    assert frame.stats["allocated"] == ["color", "depth"]


def test_gouraud_computes_no_per_pixel_lighting_and_phong_does():
    scene = load_scene(SCENES_DIR / "interpenetrating.tri")     # no normals in the file
    gouraud = {s.name: s for s in plan(scene, "perspective", "gouraud")}
    assert gouraud["vertex normals"].runs and gouraud["illuminate vertices"].runs
    assert not gouraud["illuminate pixels"].runs
    phong = {s.name: s for s in plan(scene, "perspective", "phong")}
    assert phong["illuminate pixels"].runs and not phong["illuminate vertices"].runs
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, projection="perspective", shading="gouraud", size=(64, 64)))
    assert "vertex normals" in frame.stats["computed"]
    torus = load_scene(SCENES_DIR / "torus.toml")               # analytic normals given
    assert {s.name: s for s in plan(torus, "perspective", "phong")}["vertex normals"].reason \
        .startswith("given with the mesh")


def test_closed_mesh_culls_back_faces_and_open_soup_does_not():
    torus = load_scene(SCENES_DIR / "torus.toml")
    frame = render(torus, torus.views[0],
                   RenderSettings.for_scene(torus, projection="perspective", shading="flat", size=(64, 64)))
    assert 0.3 < frame.stats["culled"] / frame.stats["triangles in"] < 0.7
    soup = load_scene(SCENES_DIR / "interpenetrating.tri")
    assert not {s.name: s for s in plan(soup, "perspective", "flat")}["cull back faces"].runs
    assert "culled" not in render(soup, soup.views[0],
                                  RenderSettings.for_scene(soup, projection="perspective", shading="flat", size=(64, 64))).stats


def test_culling_does_not_change_the_picture():
    scene = load_scene(SCENES_DIR / "torus.toml")
    culled = render(scene, scene.views[0],
                    RenderSettings.for_scene(scene, projection="perspective", shading="phong", size=(200, 200))).color
    for mesh in scene.meshes:
        mesh.closed = False               # now every face is drawn (and lit two-sided)
    drawn = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, projection="perspective", shading="phong", size=(200, 200))).color
    # Two-sided lighting only changes faces seen from behind, which the z-buffer hides here.
    assert np.count_nonzero(np.any(culled != drawn, axis=2)) < 0.001 * culled.shape[0] * culled.shape[1]


def test_every_shipped_scene_renders_every_view_in_every_mode():
    for path in sorted(SCENES_DIR.glob("*")):
        if path.suffix not in (".toml", ".tri") or path.name == "big.toml":
            continue
        scene = load_scene(path)
        for k in range(len(scene.views)):
            for shading in MODES:
                frame = render(scene, scene.views[k],
                               RenderSettings.for_scene(scene, projection=None, shading=shading, size=(48, 48)))
                assert frame.color.shape == (48, 48, 3), (path.name, k, shading)
                assert frame.message is None or "invalid" in frame.message, frame.message


@pytest.mark.parametrize("samples", [
    {"samples": 4},                                       # a regular grid, drawn as one pass
    {"samples": 2, "sample_pattern": "jittered"},         # one frame per sample
    {"samples": 4, "pixel_filter": "tent"},               # the filtered film
])
@pytest.mark.parametrize("renderer", ["radiosity", "twopass"])
def test_a_refusal_reaches_the_frame_through_supersampling(renderer, samples):
    """A renderer that refuses a scene says why in the frame, however many samples a pixel
    takes: the whitted scene's 20,352 triangles are more than radiosity meshes."""
    scene = load_scene(SCENES_DIR / "whitted.toml")
    settings = RenderSettings.for_scene(scene, renderer=renderer, size=(32, 24)).replace(
        **samples)
    frame = render(scene, scene.views[0], settings)
    assert "too many for radiosity" in (frame.message or "")
    assert frame.color.max() == 0
