"""Spheres past the triangle budget are kept analytic, not tessellated: the ray tracer draws
every one (held to the exact ray caster), the z-buffer says which it leaves out, and the ray
tracer's own limit is named when even that is passed."""

from __future__ import annotations

import numpy as np
import pytest

from core.render import render
from core.scene.formats import load_scene
from core.scene.formats.errors import ReaderError
from core.settings import RenderSettings

HEAD = """name = "many spheres"
size = [64, 64]
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-1.2, 1.2, -1.2, 1.2]
prp = [0, 0, 4]
front = 3
back = -3
[[light]]
position = [3, 4, 5]
"""


def _scene_file(path, count: int, seed: int = 3):
    rng = np.random.default_rng(seed)
    lines = [HEAD]
    for x, y, z in rng.uniform(-1, 1, (count, 3)):
        lines.append(f'[[geometry]]\nprimitive = "sphere"\ncenter = [{x:.4f}, {y:.4f}, '
                     f'{z:.4f}]\nradius = 0.03\nsegments = 32\n')
    path.write_text("\n".join(lines))
    return path


@pytest.fixture
def small_budget(monkeypatch):
    """A budget of 100,000 triangles (the real 4,000,000 would take this process past 2 GB,
    which the memory tests' children then inherit as their peak)."""
    import core.scene.generators as generators
    monkeypatch.setattr(generators, "MAX_TRIANGLES", 100_000)


def test_spheres_past_the_budget_are_traced_exactly_and_the_zbuffer_says_so(tmp_path,
                                                                           small_budget):
    scene = load_scene(_scene_file(tmp_path / "many.toml", 1000))
    # 960 triangles a sphere: 104 fit in 100,000; the other 896 stay analytic
    assert len(scene.untessellated) == 896 and len(scene.primitives) == 1000
    assert sum(len(m.triangles) for m in scene.meshes) == 104 * 960
    traced = render(scene, scene.views[0], RenderSettings.for_scene(scene, renderer="raytrace",
                                                                    shadows="off"))
    exact = render(scene, scene.views[0], RenderSettings.for_scene(scene, renderer="raycast"))
    drawn = traced.color.max(axis=2) > 0
    assert drawn.mean() > 0.3
    # the same spheres at the same pixels as the exact ray caster (edges may differ by a pixel)
    assert np.mean(drawn != (exact.color.max(axis=2) > 0)) < 0.02
    zbuffer = render(scene, scene.views[0], RenderSettings.for_scene(scene))
    notes = zbuffer.stats["not drawn"]
    assert any(n.startswith("896 spheres past the triangle budget, which were not "
                            "tessellated: raycast and raytrace draw them") for n in notes)
    assert (zbuffer.color.max(axis=2) > 0).mean() < drawn.mean()


def test_past_the_ray_tracers_own_limit_the_reader_names_it(tmp_path, monkeypatch,
                                                            small_budget):
    import core.scene.formats.scenefile as scenefile
    monkeypatch.setattr(scenefile, "MAX_ANALYTIC", 100)
    with pytest.raises(ReaderError, match=r"more than 100 spheres past the triangle budget: "
                                          r"the ray tracer traces at most 100 analytic spheres"):
        load_scene(_scene_file(tmp_path / "more.toml", 600))


def test_spheres_within_the_budget_are_tessellated_as_before(tmp_path):
    scene = load_scene(_scene_file(tmp_path / "few.toml", 20))
    assert scene.untessellated == [] and len(scene.meshes) == 20
    assert [id(m.tessellates) for m in scene.meshes] == [id(p) for p in scene.primitives]
