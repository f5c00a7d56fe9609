"""pytest-benchmark timings of the clipper and the scan conversion.

The bench scene (a sphere plus a torus, perspective, 500 x 500) at 1k and 100k triangles:
clip with everything inside (the trivial-accept path), clip with a front plane through the
meshes (Sutherland–Hodgman on thousands of triangles), and rasterize, parallel and serial.

The default run passes ``--benchmark-disable``: each benchmark runs once as a plain test and
asserts what the stage produced, never a time. ``pytest tests/core/pipeline/test_bench_raster.py
--benchmark-enable`` times them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from core.pipeline import project
from core.pipeline.clip_polygon import clip_triangles, outcodes
from core.scene.generators import sphere_torus
from core.pipeline.raster import VisibilityBuffer, rasterize
from core.transforms import apply
from core.camera.view import normalizing_transform

SIZE = (500, 500)


@dataclass
class Prepared:
    canonical: np.ndarray          # (V, 3) after N_per, a strided view as the renderer has it
    triangles: np.ndarray          # (T, 3) front-facing triangles
    attrs: np.ndarray              # (V, 3) an attribute per vertex (here: the world position)
    n: np.ndarray                  # N_per
    z_min: float
    device: np.ndarray             # (V, 3) after the perspective-to-parallel divide, viewport
    inv_w: np.ndarray


def _prepare(n_triangles: int) -> Prepared:
    scene = sphere_torus(n_triangles)
    offsets = np.cumsum([0] + [len(m.positions) for m in scene.meshes])
    positions = np.concatenate([m.positions for m in scene.meshes])
    triangles = np.concatenate([m.triangles + o for m, o in zip(scene.meshes, offsets)])
    view = scene.views[0]
    n, z_min = normalizing_transform(view, "perspective")
    canonical = apply(n, positions)[:, :3]
    device, inv_w = project.project_triangles(canonical, "perspective", z_min,
                                              project.viewport(view.window, *SIZE))
    a, b, c = (device[triangles[:, k], :2] for k in range(3))
    area = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    front = triangles[area > 0]
    return Prepared(canonical, front, positions.copy(), n, z_min, device, inv_w)


@pytest.fixture(scope="module")
def scene_100k() -> Prepared:
    return _prepare(100_000)


@pytest.fixture(scope="module")
def scene_1k() -> Prepared:
    return _prepare(1_000)


def test_clip_everything_inside(benchmark, scene_100k):
    s = scene_100k
    clipped = benchmark(clip_triangles, s.canonical, s.triangles, s.attrs, "perspective",
                        s.z_min)
    # trivial accept for the whole mesh: the inputs come back as they are
    assert clipped.triangles is s.triangles and clipped.attrs is s.attrs
    assert np.array_equal(clipped.source, np.arange(len(s.triangles)))


def test_clip_front_plane_through_the_meshes(benchmark, scene_100k):
    s = scene_100k
    z_cut = float(np.median(s.canonical[:, 2]))        # a front plane halfway into the scene
    clipped = benchmark(clip_triangles, s.canonical, s.triangles, s.attrs, "perspective", z_cut)
    used = np.unique(clipped.triangles)
    assert np.all(np.isfinite(clipped.points[used]))
    assert not np.any(outcodes(clipped.points[used], "perspective", z_cut))
    assert len(clipped.points) > len(s.canonical)      # crossings were appended
    # the attribute (world position) moved with the point: N_per still maps one to the other
    assert np.allclose(apply(s.n, clipped.attrs[used])[:, :3], clipped.points[used], atol=1e-9)
    kept = np.unique(clipped.source)
    assert 0.2 * len(s.triangles) < len(kept) < 0.9 * len(s.triangles)


@pytest.mark.parametrize("parallel", [True, False])
def test_rasterize_100k(benchmark, scene_100k, parallel):
    s = scene_100k
    out = VisibilityBuffer.allocate(*SIZE)
    vis = benchmark(rasterize, s.device, s.inv_w, s.triangles, *SIZE, out=out, parallel=parallel)
    assert vis is out
    covered = vis.tri >= 0
    assert 0.1 < covered.mean() < 0.6
    assert np.all(np.isfinite(vis.depth[covered])) and np.all(vis.depth[~covered] == -np.inf)
    assert np.all((vis.b1[covered] >= 0) & (vis.b2[covered] >= 0))


def test_rasterize_1k(benchmark, scene_1k):
    s = scene_1k
    out = VisibilityBuffer.allocate(*SIZE)
    vis = benchmark(rasterize, s.device, s.inv_w, s.triangles, *SIZE, out=out)
    assert 0.1 < (vis.tri >= 0).mean() < 0.6
