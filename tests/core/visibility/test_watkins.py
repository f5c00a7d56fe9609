"""Watkins' scan-line visible-surface algorithm (``--renderer scanline``, FvDFH 15.6).

Oracles: hand-derived spans and crossings of a two-triangle frame (the depth lines cross at
x = 12 exactly), and the z-buffer, an independent visible-surface algorithm (per-pixel depth
test, tiles, hierarchical z) that shares only the fill rule's fixed-point setup. The bound
stated in docs/scanline.md: at least 99.9 % of pixels identical, and every differing pixel on
a triangle edge of either picture or where the two winners tie in depth (within 1e-12).
"""

from __future__ import annotations

import numpy as np
import pytest

from core import RenderSettings, render
from core.inspect import inspect_pixel
from core.inspect.text import describe
from core.pipeline.raster import rasterize as zbuffer_rasterize
from core.scene.formats import load_scene
from core.visibility import watkins
from app.distribution.warmup import shipped_scenes

SHADINGS = ("flat", "gouraud", "phong")


def _two_triangles():
    """A: z = -0.5, the right triangle (0.25, 0.25), (15.75, 0.25), (15.75, 7.75);
    B: covers the 16 x 8 frame, z = -0.9 + 0.05 (x - 4), nearer than A for x > 12."""
    zb = lambda x: -0.9 + 0.05 * (x - 4.0)                      # noqa: E731
    xy_z = np.array([[0.25, 0.25, -0.5], [15.75, 0.25, -0.5], [15.75, 7.75, -0.5],
                     [-20.0, -20.0, zb(-20.0)], [40.0, -20.0, zb(40.0)], [10.0, 60.0, zb(10.0)]])
    return xy_z, np.ones(6), np.array([[0, 1, 2], [3, 4, 5]])


def test_hand_derived_aet_and_spans_on_one_scan_line():
    xy_z, inv_w, tris = _two_triangles()
    record = []
    vis = watkins.rasterize(xy_z, inv_w, tris, 16, 8, record_row=3, record=record)
    rec = record[0]
    # device row 3 (centre y = 3.5): B's left edge x = -20 + 30 (23.5 / 80), A's hypotenuse
    # x = 0.25 + 15.5 (3.25 / 7.5), A's right edge 15.75, B's right edge 40 - 30 (23.5 / 80)
    crossings = sorted(rec.aet[:, 2])
    assert crossings == pytest.approx([-11.1875, 0.25 + 15.5 * 3.25 / 7.5, 15.75, 31.1875],
                                      abs=1e-12)
    assert list(rec.aet[:, 3]) == sorted(rec.aet[:, 3])          # the AET is sorted in x
    assert list(rec.aet[:2, 0]) == [1, 0] and list(rec.aet[:2, 1]) == [1, 1]   # two left edges
    # pixels 0-6 only B (no depth); 7-15 both: A nearest at 7, B at 15, cut where
    # d0 = 0.225, d1 = -0.175 give 7 + floor(8 * 0.5625) = 11
    assert rec.spans.tolist() == [[0, 6, 1, 1, 0], [7, 11, 0, 2, 2], [12, 15, 1, 2, 2]]
    assert vis.tri[8 - 1 - 3].tolist() == [1] * 7 + [0] * 5 + [1] * 4
    assert rec.stats["penetration splits"] >= 1
    expected_depth = [-0.9 + 0.05 * (i + 0.5 - 4) for i in range(7)] + [-0.5] * 5 + [
        -0.9 + 0.05 * (i + 0.5 - 4) for i in range(12, 16)]
    assert vis.depth[4] == pytest.approx(expected_depth, abs=1e-12)


def test_equals_the_zbuffer_on_random_interpenetrating_triangles():
    rng = np.random.default_rng(7)
    n, width, height = 400, 83, 57
    xy_z = np.column_stack([rng.uniform(-6, width + 6, 3 * n), rng.uniform(-6, height + 6, 3 * n),
                            rng.uniform(-1, 0, 3 * n)])
    inv_w = rng.uniform(0.2, 1.0, 3 * n)
    tris = np.arange(3 * n).reshape(-1, 3)
    record = []
    ours = watkins.rasterize(xy_z, inv_w, tris, width, height, record=record)
    ref = zbuffer_rasterize(xy_z, inv_w, tris, width, height, parallel=False)
    assert record[0].stats["penetration splits"] > 10           # they do interpenetrate
    assert np.array_equal(ours.tri, ref.tri)
    drawn = ref.tri >= 0
    assert np.array_equal(ours.depth[drawn], ref.depth[drawn])
    assert np.array_equal(ours.b1[drawn], ref.b1[drawn])
    assert np.array_equal(ours.b2[drawn], ref.b2[drawn])


def _visible(scene, settings):
    kept = {}
    frame = render(scene, scene.views[0], settings,
                   inspect=lambda stage, arrays: kept.update(
                       {k: arrays[k].copy() for k in ("tri", "depth") if k in arrays}))
    return frame, kept


def _check_against_zbuffer(scene, settings):
    """The bound: >= 99.9 % identical; every difference on an edge or a depth tie."""
    zf, zk = _visible(scene, settings.replace(renderer="zbuffer"))
    sf, sk = _visible(scene, settings.replace(renderer="scanline"))
    assert sf.message is None and sf.stats["renderer"] == "scanline"
    differ = (zf.color != sf.color).any(axis=-1)
    assert differ.mean() <= 1e-3, f"{scene.name}: {differ.sum()} pixels differ"
    if differ.any():
        tri = np.pad(zk["tri"], 1, mode="edge")
        edge = np.zeros_like(differ)
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                edge |= tri[dy:dy + differ.shape[0], dx:dx + differ.shape[1]] != zk["tri"]
        tie = np.abs(zk["depth"] - sk["depth"]) <= 1e-12
        assert (edge | tie)[differ].all(), f"{scene.name}: a difference inside a triangle"
    return differ.sum()


def _triangle_scenes():
    out = []
    for path in shipped_scenes():
        if path.name == "glass_bunny.toml":
            continue                      # the bunny has its own test (the full scan)
        if load_scene(path).triangle_count == 0:
            continue                      # lines only: no surface to find
        out.append(path)
    return out


@pytest.mark.parametrize("path", _triangle_scenes(), ids=lambda p: p.name)
def test_every_shipped_scene_as_the_zbuffer_draws_it(path):
    scene = load_scene(path)
    shading = SHADINGS[sum(map(ord, path.name)) % 3]       # each scene in one of the three
    settings = RenderSettings.for_scene(scene, shading=shading, size=(64, 48), samples=1)
    _check_against_zbuffer(scene, settings)


@pytest.mark.parametrize("projection", ("perspective", "parallel"))
def test_the_bunny_and_the_interpenetrating_scenes_in_every_shading(bunny_path, projection):
    scenes = [load_scene(bunny_path)] + [load_scene(f"scenes/{name}") for name in
                                             ("interpenetrating.tri", "pierced_triangles.tri")]
    for scene in scenes:
        for shading in SHADINGS:
            settings = RenderSettings.for_scene(scene, shading=shading, size=(160, 120),
                                                samples=1, projection=projection)
            _check_against_zbuffer(scene, settings)


def test_plan_and_stats_say_what_the_tables_did():
    scene = load_scene("scenes/interpenetrating.tri")
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, size=(120, 120), renderer="scanline"))
    stage = next(s for s in frame.plan if s.name == "scan-line visible surface")
    assert stage.runs and "active edge table sorted in x" in stage.reason
    assert "z-buffer scan conversion" not in [s.name for s in frame.plan]
    counts = frame.stats["scan line"]
    assert f"penetration splits {counts['penetration splits']}" in stage.reason
    assert counts["polygons"] == 5 and counts["penetration splits"] > 0
    # one-polygon spans need no depth: the evaluations come from the others (2 per piece)
    assert counts["depth evaluations"] >= 4 * (counts["spans"] - counts["one-polygon spans"])


def test_inspector_shows_the_scan_lines_aet_and_spans():
    scene = load_scene("scenes/interpenetrating.tri")
    settings = RenderSettings.for_scene(scene, size=(200, 200), renderer="scanline")
    frame = render(scene, scene.views[0], settings)
    ys, xs = np.nonzero(frame.color.any(axis=-1))
    x, y = int(xs[len(xs) // 2]), int(ys[len(ys) // 2])
    record = inspect_pixel(scene, scene.views[0], settings, x, y)
    assert record["renderer"] == "scanline"
    assert record["color"] == [int(c) for c in frame.color[y, x]]
    line = record["scan line"]
    xs_aet = [e["x"] for e in line["aet"]]
    assert xs_aet == sorted(xs_aet) and len(xs_aet) % 2 == 0
    here = [s for s in line["spans"] if s["pixels"][0] <= x <= s["pixels"][1]]
    assert len(here) == 1 and here[0]["visible triangle"] == record["scene triangle"]
    text = "\n".join(describe(record))
    assert f"scan line {y}" in text and "spans:" in text


def test_bad_vertex_index_is_one_clear_message():
    xy_z, inv_w, tris = _two_triangles()
    with pytest.raises(ValueError, match=r"1 triangles name a vertex outside 0\.\.5"):
        watkins.rasterize(xy_z, inv_w, np.array([[0, 1, 9]]), 16, 8)
