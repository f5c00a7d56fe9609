"""The three polygon clippers (``--clipper``) against each other: Sutherland–Hodgman in the
canonical volume (the default), with Liang–Barsky's parametric tests, and in homogeneous clip
space; on 100,000 random triangles in each canonical volume, by hand, on bad input, and in
the pictures they give."""

from __future__ import annotations

import numpy as np
import pytest

from core import RenderSettings, render
from core.pipeline.clip_polygon import clip_triangles
from core.pipeline.project import triangle_matrix
from core.scene.formats import load_scene
from core.settings import CLIPPERS
UNIT = (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)           # the unit viewport: device = NPC


def _inside_points(rng, n, projection, z_min):
    z = rng.uniform(-1.0, z_min if projection == "perspective" else 0.0, n)
    half = -z if projection == "perspective" else np.ones(n)
    return np.stack([rng.uniform(-1, 1, n) * half, rng.uniform(-1, 1, n) * half, z], axis=1)


def _on_a_plane(rng, p, projection, z_min):
    """Each point moved onto one of the six planes (chosen at random), inside the others."""
    p = p.copy()
    k = rng.integers(0, 6, len(p))
    z = p[:, 2]
    side = -z if projection == "perspective" else np.ones(len(p))
    for plane, (axis, value) in enumerate([(1, side), (1, -side), (0, side), (0, -side)]):
        p[k == plane, axis] = value[k == plane]
    p[k == 4, 2] = -1.0
    p[k == 5, 2] = z_min if projection == "perspective" else 0.0
    if projection == "perspective":          # the side planes move with z: stay on them
        on_side = k >= 4
        p[on_side, :2] = np.clip(p[on_side, :2], p[on_side, 2:3], -p[on_side, 2:3])
    return p


def random_triangles(n, projection, z_min, seed=35):
    """n triangles: a quarter crossing planes at random, a quarter wholly inside, a quarter
    wholly outside one plane, a quarter with corners on planes (inside, crossing or out)."""
    rng = np.random.default_rng(seed)
    q = n // 4
    crossing = rng.uniform(-2.0, 1.0, (q, 3, 3))
    inside = _inside_points(rng, 3 * q, projection, z_min).reshape(q, 3, 3)
    outside = _inside_points(rng, 3 * q, projection, z_min).reshape(q, 3, 3)
    axis = rng.integers(0, 3, q)
    outside[np.arange(q), :, axis] += rng.choice([-3.0, 3.0], q)[:, None]
    on = _on_a_plane(rng, _inside_points(rng, 3 * (n - 3 * q), projection, z_min),
                     projection, z_min).reshape(-1, 3, 3)
    mixed = rng.random((len(on), 3)) < 0.3            # some corners thrown anywhere
    on[mixed] = rng.uniform(-2.0, 1.0, (int(mixed.sum()), 3))
    points = np.concatenate([crossing, inside, outside, on]).reshape(-1, 3)
    return points, np.arange(len(points)).reshape(-1, 3)


def npc(points, projection, z_min):
    h = np.concatenate([points, np.ones((len(points), 1))], axis=1) @ triangle_matrix(
        projection, z_min, UNIT).T
    return h[:, :3] / h[:, 3:4]


def polygons(clipped, projection, z_min, n_triangles):
    """Per input triangle: its clipped polygon's vertices (NPC and attributes, padded with NaN
    to 9) and its area in NPC; the input triangles that kept something."""
    corners = np.stack([np.repeat(clipped.source, 3), clipped.triangles.ravel()], axis=1)
    corners = np.unique(corners, axis=0)                    # by source, then vertex index
    sources, first, count = np.unique(corners[:, 0], return_index=True, return_counts=True)
    rank = np.arange(len(corners)) - np.repeat(first, count)
    used = clipped.points[corners[:, 1]]
    values = np.concatenate([npc(used, projection, z_min), clipped.attrs[corners[:, 1]]], axis=1)
    vertices = np.full((n_triangles, 9, values.shape[1]), np.nan)
    vertices[corners[:, 0], rank] = values
    a, b, c = (npc(clipped.points[clipped.triangles[:, i]], projection, z_min) for i in range(3))
    area = np.zeros(n_triangles)
    np.add.at(area, clipped.source, 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1))
    return vertices, area, sources


def hausdorff(a, b, chunk=20_000):
    """Per polygon, the largest distance (max-norm) from a vertex of one to the nearest
    vertex of the other, both ways (NaN padding ignored)."""
    out = np.zeros(len(a))
    for s in range(0, len(a), chunk):
        d = np.abs(a[s:s + chunk, :, None, :] - b[s:s + chunk, None, :, :]).max(axis=3)
        d = np.where(np.isnan(d), np.inf, d)
        ab = np.where(np.isnan(a[s:s + chunk, :, 0]), 0.0, d.min(axis=2)).max(axis=1)
        ba = np.where(np.isnan(b[s:s + chunk, :, 0]), 0.0, d.min(axis=1)).max(axis=1)
        out[s:s + chunk] = np.maximum(ab, ba)
    return out


@pytest.mark.parametrize("projection, z_min", [("parallel", 0.0), ("perspective", -0.1)])
def test_the_polygon_clippers_keep_the_same_polygons_to_1e12_in_npc(projection, z_min):
    points, triangles = random_triangles(100_000, projection, z_min)
    attrs = np.random.default_rng(7).normal(size=(len(points), 2))
    n = len(triangles)
    today = clip_triangles(points, triangles, attrs, projection, z_min)
    ref_vertices, ref_area, ref_sources = polygons(today, projection, z_min, n)
    assert 30_000 < len(ref_sources) < 90_000           # accepted, rejected and cut ones
    assert len(today.points) > len(points) + 50_000      # many new crossing vertices
    for clipper in CLIPPERS[1:]:
        other = clip_triangles(points, triangles, attrs, projection, z_min, clipper=clipper)
        vertices, area, sources = polygons(other, projection, z_min, n)
        assert np.array_equal(sources, ref_sources), clipper
        assert hausdorff(vertices[sources], ref_vertices[sources]).max() <= 1e-12, clipper
        assert np.abs(area - ref_area).max() <= 1e-12, clipper
        assert np.all(np.isfinite(other.points[other.triangles]))


@pytest.mark.parametrize("projection, z_min", [("parallel", 0.0), ("perspective", -0.1)])
def test_the_line_clippers_agree_on_segments_with_ends_on_planes(projection, z_min):
    # tests/core/pipeline/test_clippers.py draws its 100,000 segments uniformly (no end lands
    # on a plane): here one edge of each random triangle above, a quarter of them with ends on
    # planes.
    from core.pipeline import clip
    from core.pipeline.project import project_lines
    points, triangles = random_triangles(100_000, projection, z_min)
    p0, p1 = points[triangles[:, 0]], points[triangles[:, 1]]
    assert len(p0) == 100_000
    cs = clip.clip_lines(p0, p1, projection, z_min)
    assert 40_000 < len(cs[0]) < 90_000
    for clipper in CLIPPERS[1:]:
        q = clip.clip_lines_with(clipper, p0, p1, projection, z_min)
        assert len(q[0]) == len(cs[0]), clipper
        for a, b in zip(cs, q):
            assert np.abs(project_lines(a, projection, UNIT)
                          - project_lines(b, projection, UNIT)).max() <= 1e-12, clipper


def test_a_triangle_clipped_by_hand():
    # parallel, z = -0.5: (-3, 0) (3, 0) (0, 3) cut by x = +-1 is the pentagon (-1, 0) (1, 0)
    # (1, 2) (0, 3) (-1, 2); y = 1 then leaves the square (-1, 0) (1, 0) (1, 1) (-1, 1), area 2
    points = np.array([[-3, 0, -0.5], [3, 0, -0.5], [0, 3, -0.5]], float)
    for clipper in CLIPPERS:
        c = clip_triangles(points, [[0, 1, 2]], None, "parallel", clipper=clipper)
        used = c.points[np.unique(c.triangles)]
        corners = sorted(map(tuple, np.round(used[:, :2], 15)))
        assert corners == [(-1, 0), (-1, 1), (1, 0), (1, 1)], (clipper, corners)
        a, b, d = (c.points[c.triangles[:, i]] for i in range(3))
        assert np.isclose(0.5 * np.linalg.norm(np.cross(b - a, d - a), axis=1).sum(), 2.0)


def test_crossing_the_eye_plane_in_clip_space():
    # perspective: one corner in front (W > 0), two behind the eye (W < 0); the homogeneous
    # clipper cuts it without dividing by W and keeps the part the default clipper keeps.
    points = np.array([[0, 0, -0.5], [0.2, 0, 2.0], [0, 0.2, 2.0]])
    for clipper in CLIPPERS:
        c = clip_triangles(points, [[0, 1, 2]], None, "perspective", -0.1, clipper=clipper)
        used = c.points[np.unique(c.triangles)]
        assert len(used) and np.all(np.isfinite(used)) and np.all(used[:, 2] <= -0.1 + 1e-15)


def test_nan_vertices_are_dropped_and_an_unknown_clipper_is_one_message():
    points = np.array([(0, 0, -0.5), (np.nan, 0, -0.5), (0, 0.5, -0.5),
                       (0, 0, -0.5), (np.inf, 0, -0.5), (0, 0.5, -0.5),
                       (0, 0, -0.5), (0.5, 0, -0.5), (0, 0.5, -0.5)])
    for clipper in CLIPPERS:
        c = clip_triangles(points, np.arange(9).reshape(3, 3), np.ones((9, 1)), "parallel",
                           clipper=clipper)
        assert c.source.tolist() == [2] and np.all(np.isfinite(c.points[c.triangles]))
    with pytest.raises(ValueError, match="clipper must be one of cohen-sutherland, "
                                         "liang-barsky, homogeneous, not 'weiler'"):
        clip_triangles(points, [[0, 1, 2]], None, "parallel", clipper="weiler")


def _counting(monkeypatch):
    """Count the triangles each polygon kernel is given to cut."""
    from core.pipeline import clip_polygon
    cut = dict.fromkeys(CLIPPERS, 0)

    def counted(name, kernel):
        def run(points, triangles, attrs, codes, todo, perspective, z_min):
            cut[name] += len(todo)
            return kernel(points, triangles, attrs, codes, todo, perspective, z_min)
        return run
    monkeypatch.setattr(clip_polygon, "_KERNELS",
                        {k: counted(k, v) for k, v in clip_polygon._KERNELS.items()})
    return cut


@pytest.mark.parametrize("name, frames", [("house_flyaround.toml", 6),
                                          ("crossing_front_plane.tri", 1)])
def test_every_polygon_clipper_draws_the_same_solid(name, frames, monkeypatch):
    cut = _counting(monkeypatch)
    scene = load_scene(f"scenes/{name}")
    for view in scene.views[:frames]:
        for projection in ("perspective", "parallel"):
            settings = RenderSettings.for_scene(scene, size=(96, 96), projection=projection)
            today = render(scene, view, settings).color
            for clipper in CLIPPERS[1:]:
                other = render(scene, view, settings.replace(clipper=clipper)).color
                assert np.array_equal(other, today), (view.label, projection, clipper)
    assert cut["cohen-sutherland"] > 0 and cut["liang-barsky"] == cut["homogeneous"] == \
        cut["cohen-sutherland"]


def test_each_clippers_kernel_can_be_cached():
    """The shared loop (clip_polygon.clip_and_fan) takes each clipper's steps as functions; a
    kernel that passed them on as values would hold Python objects' addresses, which numba
    will not cache (every process would compile the clippers again)."""
    from core.pipeline import clip_polygon
    rng = np.random.default_rng(3)
    points = rng.uniform(-1.5, 0.5, (30, 3))
    for clipper, kernel in clip_polygon._KERNELS.items():
        c = clip_triangles(points, np.arange(30).reshape(10, 3), None, "perspective", -0.1,
                           clipper=clipper)
        assert len(c.triangles) > 0
        compiled = kernel.overloads.values()
        assert compiled and not any(o.library.has_dynamic_globals for o in compiled), clipper
