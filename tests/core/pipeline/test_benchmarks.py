"""pytest-benchmark timings of the pipeline's stages, so that a regression shows.

Stages, on the bench's sphere + torus at 100k triangles, 500 x 500, perspective:
transform (N_per on every vertex), clip (Sutherland–Hodgman, once with everything inside and
once with a view that cuts the meshes), scan (the z-buffer scan conversion), shade (the vertex
step and the pixel resolve of flat, Gouraud and Phong), and the full frame
(``core.render.render``) at 10k and 100k.

The default test run passes ``--benchmark-disable``: each benchmark then runs once as a plain
test, and what it asserts is a real outcome (what the stage produced), never a time. Run
``pytest tests/core/pipeline/test_benchmarks.py --benchmark-enable`` to time them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pytest

from app.bench.bench import bench_scene
from core.pipeline import project
from core.shading import shade
from core.pipeline.clip_polygon import clip_triangles
from core.pipeline.raster import rasterize
from core.shading.illumination import to_uint8
from core.render import render
from core.settings import RenderSettings
from core.transforms import apply
from core.camera.view import View, normalizing_transform

SIZE = (500, 500)
PROJECTION = "perspective"


@dataclass
class Staged:
    """One frame's intermediate arrays, computed once, so each benchmark times one stage."""

    scene: object
    n: np.ndarray
    z_min: float
    viewport: tuple
    canonical: np.ndarray          # (V, 3) every vertex after N_per
    kept: np.ndarray               # indices of the triangles facing the viewer
    device: np.ndarray             # (V, 3) projected vertices (the scene is inside the volume)
    inv_w: np.ndarray


def _all_triangles(scene) -> np.ndarray:
    """Every mesh's triangles over one vertex array (meshes in scene order)."""
    offsets = np.cumsum([0] + [len(m.positions) for m in scene.meshes])
    return np.concatenate([m.triangles + o for m, o in zip(scene.meshes, offsets)])


def _stage(scene) -> Staged:
    view = scene.views[0]
    n, z_min = normalizing_transform(view, PROJECTION)
    vp = project.viewport(view.window, *SIZE)
    prepared = shade.prepare("flat", scene, shade.eye_from_view(view, PROJECTION))
    canonical = apply(n, prepared.positions)[:, :3]
    device, inv_w = project.project_triangles(canonical, PROJECTION, z_min, vp)
    t = prepared.triangles
    a, b, c = (device[t[:, k], :2] for k in range(3))
    # Closed meshes: keep the faces that wind counter-clockwise on the device (facing us).
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    return Staged(scene, n, z_min, vp, canonical, np.flatnonzero(area > 0), device, inv_w)


@pytest.fixture(scope="module")
def staged_100k() -> Staged:
    return _stage(bench_scene(100_000))


def test_transform(benchmark, staged_100k):
    s = staged_100k
    positions = np.concatenate([m.positions for m in s.scene.meshes])
    canonical = benchmark(lambda: apply(s.n, positions)[:, :3])
    assert canonical.shape == positions.shape
    # The bench scene lies inside the canonical perspective volume.
    x, y, z = canonical.T
    assert np.all((z <= x) & (x <= -z) & (z <= y) & (y <= -z) & (z >= -1) & (z <= s.z_min))


def test_clip_all_inside(benchmark, staged_100k):
    s = staged_100k
    triangles = _all_triangles(s.scene)
    triangles = triangles[s.kept]
    clipped = benchmark(clip_triangles, s.canonical, triangles, np.zeros((len(s.canonical), 0)),
                        PROJECTION, s.z_min)
    assert len(clipped.triangles) == len(triangles)          # trivially accepted, all of them
    assert np.array_equal(np.sort(clipped.source), np.arange(len(triangles)))


def test_clip_cutting_view(benchmark):
    """A view whose window and front plane cut through both meshes: many triangles clipped."""
    scene = bench_scene(100_000)
    view = scene.views[0]
    u_min, u_max, v_min, v_max = view.window
    cut = View(vrp=view.vrp, vpn=view.vpn, vup=view.vup,
               window=(u_min / 2.5, u_max / 2.5, v_min / 2.5, v_max / 2.5), prp=view.prp,
               front=0.2, back=view.back, label="cutting view")
    scene = replace(scene, views=[cut])
    n, z_min = normalizing_transform(cut, PROJECTION)
    positions = np.concatenate([m.positions for m in scene.meshes])
    triangles = _all_triangles(scene)
    canonical = apply(n, positions)[:, :3]
    attrs = np.ascontiguousarray(positions)                   # 3 attributes carried through
    clipped = benchmark(clip_triangles, canonical, triangles, attrs, PROJECTION, z_min)
    assert 0 < len(clipped.triangles)
    used = np.unique(clipped.triangles)
    p = clipped.points[used]
    tol = 1e-9
    assert np.all((p[:, 2] >= -1 - tol) & (p[:, 2] <= z_min + tol))
    assert np.all((p[:, 0] >= p[:, 2] - tol) & (p[:, 0] <= -p[:, 2] + tol))
    # Attributes are interpolated with the same t as the points: N maps them onto the points.
    assert np.allclose(apply(n, clipped.attrs[used])[:, :3], p, atol=1e-9)


def test_scan(benchmark, staged_100k):
    s = staged_100k
    triangles = _all_triangles(s.scene)
    triangles = np.ascontiguousarray(triangles[s.kept])
    vis = benchmark(rasterize, s.device, s.inv_w, triangles, *SIZE)
    covered = vis.tri >= 0
    assert 0.1 < covered.mean() < 0.9
    assert np.all(np.isfinite(vis.depth[covered])) and np.all(vis.depth[~covered] == -np.inf)


@pytest.mark.parametrize("mode", ["flat", "gouraud", "phong"])
def test_shade(benchmark, staged_100k, mode):
    """The vertex step and the pixel resolve of one mode, on an already scanned frame."""
    s = staged_100k
    view = s.scene.views[0]
    eye = shade.eye_from_view(view, PROJECTION)
    prepared = shade.prepare(mode, s.scene, eye)
    triangles = np.ascontiguousarray(prepared.triangles[s.kept])
    vis = rasterize(s.device, s.inv_w, triangles, *SIZE)

    def step():
        p = shade.prepare(mode, s.scene, eye)
        return shade.resolve(p, vis, triangles, p.vertex_attrs, s.kept, s.scene.background)

    image = benchmark(step)
    covered = vis.tri >= 0
    assert image.shape == (SIZE[1], SIZE[0], 3)
    assert np.all(image[~covered] == to_uint8(s.scene.background))
    assert image[covered].max() > 100                        # lit surfaces


@pytest.mark.parametrize("mode", ["flat", "gouraud", "phong"])
@pytest.mark.parametrize("triangles", [10_000, 100_000])
def test_full_frame(benchmark, triangles, mode):
    scene = bench_scene(triangles)
    settings = RenderSettings(projection=PROJECTION, shading=mode, size=SIZE)
    frame = benchmark(render, scene, scene.views[0], settings)
    assert frame.message is None
    covered = np.any(frame.color != to_uint8(scene.background), axis=2)
    assert 0.1 < covered.mean() < 0.9
