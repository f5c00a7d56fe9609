"""The ray tracer as a renderer: agreement with the z-buffer's Phong image, the notes' shadow
options, energy, the ray tree's cut-offs, bad input, tiles, and scene files with primitives."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from core.camera.view import View
from core.raytrace.geometry import traced_primitives as geometry_primitives
from core.renderers.raytrace.draw import (TraceOptions, prepare, render_image, render_raw,
                                          tiles, trace_rays, trace_tile)
from core.raytrace.whitted import COUNTERS
from core.scene.model import Light, Material, Scene
from core.scene.primitives import Plane, Sphere
from core.settings import RenderSettings

from tests.conftest import ROOT
SCENES = ROOT / "scenes"


def _bunny_path() -> Path | None:
    for folder in ROOT.parents:
        candidate = folder / "shared" / "data" / "stanford-bunny" / "bun_zipper.ply"
        if candidate.exists():
            return candidate
    return None


BUNNY = _bunny_path()
NO_GLOBAL = TraceOptions(shadows="off")
COUNT = {name: i for i, name in enumerate(COUNTERS)}


# --------------------------------------------------------------------------- the z-buffer

def _agreement(path: str, projection: str, size=(240, 240)):
    from core.render import render
    from core.scene.formats import load_scene
    scene = load_scene(path)
    settings = RenderSettings(projection=projection, shading="phong", size=size)
    zbuffer = render(scene, scene.views[0], settings).color.astype(int)
    traced, _, stats = render_image(scene, scene.views[0], projection, size, NO_GLOBAL)
    traced = traced.astype(int)
    background = np.floor(np.asarray(scene.background) * 255 + 0.5).astype(int)
    covered_z = np.any(zbuffer != background, axis=2)
    covered_t = np.any(traced != background, axis=2)
    difference = np.abs(zbuffer - traced).max(axis=2)
    return difference, covered_z, covered_t, stats


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("name", ["bunny", "few_triangles.tri", "interpenetrating.tri"])
def test_same_picture_as_the_zbuffer_without_global_terms(name, projection):
    """No mirrors, no glass, shadows off: the traced image is the rasterizer's Phong image.

    Both evaluate phong_point with the same normals at the same pixel centres; the only
    differences beyond 1/255 allowed are ties — a pixel centre on an edge or on the line where
    two triangles cross — at most 0.01 % of the pixels. Measured at 300 x 300: the bunny differs
    by at most 1/255 everywhere with identical coverage in both projections; at 240 x 240 one
    pixel centre falls on an edge (18/255)."""
    if name == "bunny":
        if BUNNY is None:
            pytest.skip("the Stanford bunny (shared/data/stanford-bunny) is not on this machine")
        path = str(BUNNY)
    else:
        path = str(SCENES / name)
    difference, covered_z, covered_t, stats = _agreement(path, projection)
    pixels = difference.size
    assert covered_z.sum() > 0.02 * pixels                  # the picture shows something
    # Measured at 240 x 240: beyond 1/255 on at most 2 pixels (a centre on an edge), coverage
    # apart on at most 1; the bound is 0.01 % (5 pixels).
    assert np.count_nonzero(covered_z != covered_t) <= 0.0001 * pixels
    assert np.count_nonzero(difference > 1) <= 0.0001 * pixels
    assert stats["rays"]["primary"] == pixels and stats["rays"]["shadow"] == 0


# --------------------------------------------------------------------------- shadows

def _shadow_scene(blocker_kt: float, background=(0.2, 0.3, 0.4)) -> Scene:
    """A white diffuse floor (k_d = 1) under a light straight above; a sphere halfway."""
    floor = Material(ka=0.0, kd=1.0, ks=0.0, od=(1.0, 1.0, 1.0))
    blocker = Material(ka=0.0, kd=0.5, ks=0.0, od=(0.5, 0.6, 0.7), kt=blocker_kt, ior=1.0)
    return Scene(name="shadow", meshes=[], views=[], ambient=(0.0, 0.0, 0.0),
                 background=background, lights=[Light(position=(0.0, 10.0, 0.0))],
                 primitives=[Plane((0, 0, 0), (0, 1, 0), floor), Sphere((0, 2, 0), 0.5, blocker)])


def _one_ray(scene, origin, direction, options):
    view = View((0, 0, 0), (0, 0, 1), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 5), 1, -1)
    setup = prepare(scene, view, "parallel", (1, 1), options)
    raw = trace_rays(setup, np.array([origin], float), np.array([direction], float),
                     np.array([0.0]), np.array([np.inf]))
    return raw[0], setup.counts


@pytest.mark.parametrize("mode, kt, expected", [
    ("off", 0.0, (1.0, 1.0, 1.0)),                 # no shadow rays: fully lit
    ("background", 0.0, (0.2, 0.3, 0.4)),          # the notes' (a): the background colour
    ("object", 0.0, (0.15, 0.18, 0.21)),           # (b): a fraction (0.3) of the object's O_d
    ("transmit", 0.0, (0.0, 0.0, 0.0)),            # (c) through an opaque sphere: nothing
    ("transmit", 0.8, (0.64, 0.64, 0.64)),         # (c) through glass: k_t at each crossing
])
def test_the_notes_three_shadow_options(mode, kt, expected):
    s = 1 / math.sqrt(2)
    # A ray from the side onto the floor point right under the sphere (N·L = 1, f_att = 1).
    rgb, counts = _one_ray(_shadow_scene(kt), (1.0, 1.0, 0.0), (-s, -s, 0.0),
                           TraceOptions(shadows=mode))
    assert tuple(rgb) == pytest.approx(expected, abs=1e-12)
    assert counts[COUNT["shadow"]] == {"off": 0, "transmit": 1 + 2 * (kt > 0)}.get(mode, 1)


def test_unshadowed_point_is_lit_in_every_mode():
    for mode in ("background", "object", "transmit"):
        s = 1 / math.sqrt(2)
        rgb, _ = _one_ray(_shadow_scene(0.0), (4.0, 1.0, 0.0), (-s, -s, 0.0), TraceOptions(shadows=mode))
        # The floor point (3, 0, 0): lit at N·L = 10/√109 by the light at (0, 10, 0).
        assert rgb[0] == pytest.approx(10 / math.sqrt(109), rel=1e-12)


# --------------------------------------------------------------------------- energy

def test_k_r_plus_k_t_at_most_one_keeps_every_pixel_in_range():
    """With k_a + k_d + k_s + k_r + k_t ≤ 1, I_a ≤ 1 and one light of I_p ≤ 1, each I_local is
    at most k_a + k_d + k_s, so Whitted's sum is at most 1 at every depth: the raw (unclamped)
    colours must stay in [0, 1] for any materials, with and without Fresnel."""
    from core.scene.formats import load_scene
    rng = np.random.default_rng(3)
    base = load_scene(str(SCENES / "whitted.toml"))
    for trial in range(3):
        primitives = []
        spheres, planes = geometry_primitives(base)
        assert len(planes) == 1
        for p in spheres + planes:
            k = rng.dirichlet(np.ones(6))[:5]              # k_a, k_d, k_s, k_r, k_t: sum < 1
            material = Material(ka=k[0], kd=k[1], ks=k[2], kr=k[3], kt=k[4], n=30.0,
                                od=tuple(rng.uniform(0, 1, 3)), ior=float(rng.uniform(1.0, 2.4)))
            primitives.append(Sphere(p.center, p.radius, material) if isinstance(p, Sphere)
                              else Plane(p.point, p.normal, material, p.checker, p.checker_color))
        scene = Scene(name="energy", meshes=[], views=base.views, primitives=primitives,
                      ambient=(1.0, 1.0, 1.0), background=(1.0, 1.0, 1.0),
                      lights=[Light(position=(4, 8, 6), intensity=(1.0, 1.0, 1.0))])
        for fresnel in (False, True):
            options = TraceOptions(adaptive_epsilon=0.0, fresnel=fresnel)
            _, raw, stats = render_image(scene, scene.views[0], "perspective", (60, 60), options)
            assert np.all(np.isfinite(raw))
            assert raw.min() >= 0.0 and raw.max() <= 1.0 + 1e-12
            assert stats["rays"]["reflected"] > 0 and stats["rays"]["refracted"] > 0


# --------------------------------------------------------------------------- the ray tree

def _mirror_corridor(kr: float) -> Scene:
    mirror = Material(ka=0.0, kd=0.0, ks=0.0, kr=kr)
    return Scene(name="corridor", meshes=[], views=[], ambient=(1.0, 1.0, 1.0), lights=[],
                 primitives=[Plane((0, 0, 1), (0, 0, -1), mirror), Plane((0, 0, -1), (0, 0, 1), mirror)])


def test_recursion_that_would_never_end_is_stopped_by_depth():
    """Two facing mirrors, a ray bouncing between them for ever: the tree stops at max_depth."""
    for depth in (1, 7, 20):
        _, counts = _one_ray(_mirror_corridor(1.0), (0, 0, 0), (0, 0, 1.0),
                             TraceOptions(max_depth=depth, adaptive_epsilon=0.0))
        assert counts[COUNT["primary"]] == 1
        assert counts[COUNT["reflected"]] == depth - 1
        assert counts[COUNT["cut by depth"]] == 1


def test_adaptive_depth_control_stops_when_the_product_of_ks_is_small():
    # k_r = 0.5: the n-th reflection weighs 0.5^n, below ε = 1e-3 from n = 10 on.
    _, counts = _one_ray(_mirror_corridor(0.5), (0, 0, 0), (0, 0, 1.0),
                         TraceOptions(max_depth=64, adaptive_epsilon=1e-3))
    assert counts[COUNT["reflected"]] == 9
    assert counts[COUNT["cut by adaptive control"]] == 1 and counts[COUNT["cut by depth"]] == 0


def test_options_are_checked():
    for bad in (dict(max_depth=0), dict(max_depth=2.5), dict(adaptive_epsilon=-1.0),
                dict(shadows="sometimes"), dict(medium=0.0), dict(medium=float("nan"))):
        with pytest.raises(ValueError):
            TraceOptions(**bad)


# --------------------------------------------------------------------------- bad input

def test_camera_inside_a_closed_mesh():
    """From inside a closed sphere every ray hits its inner side, lit from a light inside."""
    from core.scene.generators import uv_sphere
    mesh = uv_sphere(2.0, 48, 24)
    assert mesh.closed
    scene = Scene(name="inside", meshes=[mesh], views=[], ambient=(0.1, 0.1, 0.1),
                  lights=[Light(position=(0.5, 0.5, 0.5))])
    view = View((0, 0, 0), (0, 0, 1), (0, 1, 0), (-0.5, 0.5, -0.5, 0.5), (0, 0, 1.0), 0.5, -3.0)
    image, raw, stats = render_image(scene, view, "perspective", (40, 40), TraceOptions())
    assert np.all(np.isfinite(raw)) and stats["rays"]["primary"] == 1600
    # Every pixel sees the wall, lit (more than the ambient 0.1 * k_a * O_d) and unshadowed.
    assert raw.min() > 0.1 * 0.2 * 0.25 + 0.05


def test_degenerate_triangles_in_a_scene_render():
    from core.scene.model import Mesh
    mesh = Mesh(positions=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]],
                triangles=[[0, 1, 2], [0, 1, 3], [2, 2, 2]], name="with slivers")
    scene = Scene(name="degenerate", meshes=[mesh], views=[])
    view = View((0.3, 0.3, 0), (0, 0, 1), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 3), 1, -1)
    _, raw, _ = render_image(scene, view, "perspective", (30, 30), TraceOptions())
    assert np.all(np.isfinite(raw))


def test_invalid_view_is_refused():
    from core.camera.view import ViewError
    scene = _shadow_scene(0.0)
    bad = View((0, 0, 0), (0, 0, 0), (0, 1, 0), (-1, 1, -1, 1), (0, 0, 5), 1, -1)
    with pytest.raises(ViewError):
        render_image(scene, bad, "perspective", (10, 10))


# --------------------------------------------------------------------------- tiles, scenes

def test_tiles_make_the_whole_picture():
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    setup = prepare(scene, scene.views[0], "perspective", (70, 50))
    whole = render_raw(setup)
    pieces = np.full_like(whole, np.nan)
    order = tiles(70, 50, tile=16)
    assert order[0] == (16, 32, 32, 48)                     # the centre first
    for r0, r1, c0, c1 in order:
        pieces[r0:r1, c0:c1] = trace_tile(setup, r0, r1, c0, c1)
    assert np.array_equal(pieces, whole)


def test_the_whole_frame_is_traced_in_bands_of_bounded_rays(monkeypatch):
    """render_raw holds about RAYS_PER_BAND rays at once (a 500 x 500 x 64 frame in one band
    held 1.7 GB), and the bands give the one-band picture exactly, stats included."""
    from core.camera.film import sample_offsets
    from core.renderers.raytrace import draw as renderer
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    assert renderer.band_rows(500, 64) == 32 and renderer.band_rows(10**6, 64) == 1
    four = sample_offsets(4, "regular", 0)
    whole = prepare(scene, scene.views[0], "perspective", (70, 50), offsets=four)
    one_band = renderer.render_raw(whole)
    monkeypatch.setattr(renderer, "RAYS_PER_BAND", 70 * 4 * 3)       # bands of 3 rows
    calls = []
    monkeypatch.setattr(renderer, "trace_tile",
                        lambda setup, *box: calls.append(box) or trace_tile(setup, *box))
    banded = prepare(scene, scene.views[0], "perspective", (70, 50), offsets=four)
    assert np.array_equal(renderer.render_raw(banded), one_band)
    assert calls[0] == (0, 3, 0, 70) and calls[-1] == (48, 50, 0, 70) and len(calls) == 17
    assert np.array_equal(banded.counts, whole.counts)

def test_whitted_scene_reads_and_renders_in_both_renderers():
    from core.render import render
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    kinds = sorted(type(p).__name__ for p in scene.primitives)
    assert kinds == ["Sphere", "Sphere"]              # the plane: through its tessellation
    glass = [p for p in scene.primitives if isinstance(p, Sphere) and p.material.kt > 0][0]
    assert glass.material.ior == 1.52
    # The z-buffer draws the tessellation: three meshes' worth (two checker colours).
    assert all(m.tessellates is not None for m in scene.meshes) and len(scene.meshes) == 4
    zbuffer = render(scene, scene.views[0],
                     RenderSettings(shading="phong", size=(80, 80))).color
    traced, raw, stats = render_image(scene, scene.views[0], "perspective", (80, 80))
    assert stats["bvh"]["triangles"] == 0                   # the primitives are traced exactly
    assert stats["rays"]["reflected"] > 0 and stats["rays"]["refracted"] > 0
    assert stats["rays"]["shadow"] > 0
    # Away from the spheres (the bottom rows: the floor), both renderers see the same checker.
    rows = slice(70, 80)
    assert np.mean(np.abs(zbuffer[rows].astype(int) - traced[rows].astype(int)).max(axis=2) <= 2) > 0.6


def test_primitive_errors_name_the_key():
    from core.scene.formats.errors import ReaderError
    from core.scene.formats.scenefile import read_scene_file
    for text, key in [('[[geometry]]\nprimitive = "cone"\n', "geometry[1].primitive"),
                      ('[[geometry]]\nprimitive = "sphere"\nradius = -1\n', "geometry[1].radius"),
                      ('[[geometry]]\nprimitive = "plane"\nnormal = [0, 0, 0]\n', "geometry[1].normal"),
                      ('[[geometry]]\nprimitive = "sphere"\nnormal = [0, 1, 0]\n', "geometry[1].normal"),
                      ('[[geometry]]\nprimitive = "sphere"\nmaterial = { kr = 2 }\n',
                       "geometry[1].material.kr")]:
        with pytest.raises(ReaderError, match=key.replace("[", r"\[").replace("]", r"\]")):
            read_scene_file(text, "prim.toml")


def test_camera_rays_are_the_primary_rays_between_the_front_and_back_planes():
    # One camera_rays for the tracer, the path tracer and radiosity's display: the camera's
    # primary rays; perspective ones keep their origin, parallel ones start on the front
    # plane (n = F along VPN) and end on the back one; outside the viewport t_min is inf.
    from core.camera.rays import camera_rays, primary_rays
    from core.camera.view import vrc_basis
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    view = scene.views[0]
    offsets = [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]]
    n_axis = vrc_basis(view)[2]
    for projection in ("perspective", "parallel"):
        o, d, inside = primary_rays(view, projection, 40, 30, offsets, True)
        origins, directions, t_min, t_max = camera_rays(view, projection, 40, 30, offsets, True)
        assert np.array_equal(directions, d) and not inside.all() and inside.any()
        assert np.all(np.isinf(t_min[~inside]))
        if projection == "perspective":
            assert np.array_equal(origins, o) and np.all(t_min[inside] >= 0)
        else:
            n_start = (origins[inside] - np.asarray(view.vrp)) @ n_axis
            np.testing.assert_allclose(n_start, view.front, atol=1e-9)
            n_end = (origins[inside] + t_max[inside, None] * directions[inside]
                     - np.asarray(view.vrp)) @ n_axis
            np.testing.assert_allclose(n_end, view.back, atol=1e-9)


def test_a_kernel_s_own_camera_ray_is_camera_rays_ray():
    """``clipped_ray`` (one ray, in a kernel: the path tracer's) against ``camera_rays`` (the
    numpy twin): the same origin and direction to the bit, the same t interval within 1e-12
    (numpy's matrix product may round the plane distances differently), and a sample outside
    the viewport at t_min = inf in both; perspective and parallel, with a letterbox."""
    from core.camera.rays import camera_rays, clipped_ray, pack_camera, pixel_point
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    view = scene.views[0]
    width, height, offset = 40, 30, (0.25, 0.75)
    for projection in ("perspective", "parallel"):
        o, d, t_min, t_max = camera_rays(view, projection, width, height, [offset], True)
        cam = pack_camera(view, projection, width, height, True)
        ours = np.array([clipped_ray(cam, *pixel_point(width, height, p, *offset))
                         for p in range(width * height)])
        assert np.array_equal(ours[:, 0:3], o) and np.array_equal(ours[:, 3:6], d)
        outside = np.isinf(t_min)
        assert outside.any() and not outside.all()
        assert np.array_equal(np.isinf(ours[:, 6]), outside)
        np.testing.assert_allclose(ours[~outside, 6], t_min[~outside], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(ours[~outside, 7], t_max[~outside], rtol=1e-12)


def test_registered_renderer_through_the_front_door():
    from core import render
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    settings = RenderSettings.for_scene(scene, renderer="raytrace", size=(64, 48), samples=4)
    frame = render(scene, scene.views[0], settings)
    assert frame.message is None and frame.color.shape == (48, 64, 3)
    assert frame.stats["rays"]["primary"] == 64 * 48 * 4        # the window stretched over all
    assert frame.stats["samples per pixel"] == 4
    direct, _, _ = render_image(scene, scene.views[0], "perspective", (64, 48), samples=4)
    assert np.array_equal(frame.color, direct)
    boxed = render(scene, scene.views[0], settings.replace(keep_aspect=True))
    assert boxed.stats["rays"]["primary"] == 48 * 48 * 4        # the square window letterboxed
    direct, _, _ = render_image(scene, scene.views[0], "perspective", (64, 48), samples=4,
                                keep_aspect=True)
    assert np.array_equal(boxed.color, direct)
    # The settings reach the tracer: no shadow rays when shadows are off.
    off = render(scene, scene.views[0], settings.replace(shadows="off", samples=1))
    assert off.stats["rays"]["shadow"] == 0


@pytest.mark.parametrize("name, kinds", [("whitted.toml", ("reflected", "refracted")),
                                         ("house_mirror.toml", ("reflected",)),
                                         ("refraction.toml", ("refracted",)),
                                         ("glass_bunny.toml", ("refracted", "total internal reflections"))])
def test_shipped_ray_tracing_scenes_render(name, kinds):
    from core.scene.formats.scenefile import read_scene_file
    path = SCENES / name
    scene = read_scene_file(path.read_text(), str(path), path.parent)
    for view in scene.views:
        _, raw, stats = render_image(scene, view, scene.projection, (40, 40))
        assert np.all(np.isfinite(raw)) and raw.min() >= 0.0
    assert all(stats["rays"][k] > 0 for k in kinds)


def test_samples_per_pixel_regular_and_jittered():
    """The film's samples: 4 regular or 4 jittered rays a pixel, box-filtered; a flat-coloured
    region keeps its colour, an edge gets in-between values."""
    from core.scene.formats import load_scene
    scene = load_scene(str(SCENES / "whitted.toml"))
    one, _, s1 = render_image(scene, scene.views[0], "perspective", (40, 40), NO_GLOBAL)
    for pattern in ("regular", "jittered"):
        four, raw, s4 = render_image(scene, scene.views[0], "perspective", (40, 40), NO_GLOBAL,
                                     samples=4, pattern=pattern, seed=2)
        assert s4["rays"]["primary"] == 4 * s1["rays"]["primary"]
        assert np.all(np.isfinite(raw))
        # The sky (top rows: background only) is the same colour with any sampling.
        assert np.array_equal(four[:3], one[:3])
        # Along the spheres' silhouettes the filtered picture differs from one sample a pixel.
        assert np.count_nonzero(np.abs(four.astype(int) - one.astype(int)).max(axis=2) > 8) > 20
