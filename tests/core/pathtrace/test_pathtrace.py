"""The path tracer against Mitsuba 3, and radiosity against the path tracer, on the
Cornell box: both path tracers well converged at the same sample count, compared away from
edges (every pixel of a 2 x 2 block sees one surface through its whole 3 x 3 neighbourhood)."""

from __future__ import annotations


import numpy as np
import pytest

from tools import unavailable

from app.oracles import mitsuba_oracle
from core.context import RenderContext
from core.pathtrace.compare import block_relative_error, interior_mask, surface_ids
from core.renderers.pathtrace.draw import render_passes
from core.renderers.radiosity.draw import radiosity_image
from core.radiosity.solution import Options, solve
from core.scene.formats import load_scene
from core.settings import RenderSettings

from tests.conftest import ROOT

SIZE, SAMPLES = 32, 1024


@pytest.fixture(scope="module")
def cornell():
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    view = scene.views[0]
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(SIZE, SIZE))
    ours, _ = render_passes(scene, view, settings, RenderContext(), samples=SAMPLES)
    ids, mesh = surface_ids(scene, view, "perspective", SIZE, SIZE, with_meshes=True)
    walls = [i for i, m in enumerate(scene.meshes) if "wall" in m.name]
    return scene, view, ours, ids, interior_mask(ids), np.isin(mesh, walls)


def test_path_tracer_matches_mitsuba(cornell):
    if not mitsuba_oracle.available():
        unavailable("mitsuba is not installed (pip install mitsuba): the path tracer's oracle")
    scene, view, ours, _, mask, _ = cornell
    reference = mitsuba_oracle.render(scene, view, SIZE, SIZE, SAMPLES, seed=1)
    error, blocks = block_relative_error(ours, reference, mask, block=2)
    assert blocks > 50
    assert error < 0.02, error
    # and the light reaching the picture as a whole agrees closely
    assert ours[mask].mean(axis=0) == pytest.approx(reference[mask].mean(axis=0), rel=0.01)


def test_radiosity_walls_match_the_path_tracer(cornell):
    scene, view, ours, ids, mask, on_walls = cornell
    solution = solve(scene, Options(form_factors="raycast", max_elements=2000, converge=1e-3,
                                    adaptive=False))
    image = radiosity_image(solution, view, "perspective", SIZE, SIZE)
    checked = 0
    for surface in np.unique(ids[mask & on_walls]):          # floor, ceiling, back, red, green
        sel = mask & (ids == surface)
        ours_mean, radiosity_mean = ours[sel].mean(axis=0), image[sel].mean(axis=0)
        error = np.abs(radiosity_mean - ours_mean) / ours_mean
        assert error.max() < 0.05, (surface, radiosity_mean, ours_mean)
        checked += 1
    assert checked >= 5


def test_inspect_pixel_retraces_the_pixel():
    from core.renderers.pathtrace.inspect import inspect_pixel
    from core.render import render
    scene = load_scene(ROOT / "scenes" / "cornell_box.toml")
    settings = RenderSettings.for_scene(scene, renderer="pathtrace", size=(24, 24), samples=4)
    context = RenderContext()
    frame = render(scene, scene.views[0], settings, context)
    record = inspect_pixel(scene, scene.views[0], settings, 12, 20, context)
    assert record["color"] == frame.color[20, 12].tolist()
    path = record["path (first sample)"]
    assert path[0]["kind"] == "camera" and path[0]["hit"] is not None
    assert all(p["kind"] == "diffuse or glossy (BSDF sample)" for p in path[1:])
    # the contributions add up to the first sample's radiance
    assert sum(np.array(p["contribution"]) for p in path).min() >= 0
