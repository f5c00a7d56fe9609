"""The front door ``core.render(scene, view, settings)``: any view, settings, the film, rays,
renderers by name."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core import RenderContext, RenderSettings, View, render
from core.camera.film import Film, sample_offsets
from core.camera.rays import primary_rays
from core.paths import SCENES_DIR
from core.renderers import get_renderer, register_renderer, renderer_names
from core.renderers.raycast.draw import render_reference
from core.scene.formats import load_scene
from core.scene.model import Light, Material, Scene
from core.scene.primitives import Sphere

# The notes' worked example (VRP (0, 0, 54), PRP (8, 6, 30), window -1..17, F 1, B -23).
WORKED = View(vrp=(0.0, 0.0, 54.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0),
              window=(-1.0, 17.0, -1.0, 17.0), prp=(8.0, 6.0, 30.0), front=1.0, back=-23.0)


def _lerp_view(a: View, b: View, t: float) -> View:
    mix = lambda p, q: tuple((1 - t) * np.asarray(p, float) + t * np.asarray(q, float))  # noqa: E731
    return View(vrp=mix(a.vrp, b.vrp), vpn=mix(a.vpn, b.vpn), vup=mix(a.vup, b.vup),
                window=mix(a.window, b.window), prp=mix(a.prp, b.prp),
                front=(1 - t) * a.front + t * b.front, back=(1 - t) * a.back + t * b.back,
                label="in between")


@pytest.mark.parametrize("shading", ["wireframe", "gouraud", "phong"])
def test_a_view_that_is_not_in_the_scene_draws_like_the_same_view_added_to_it(shading):
    scene = load_scene(SCENES_DIR / "torus.toml")
    between = _lerp_view(scene.views[0], scene.views[-1], 0.37)
    assert between not in scene.views
    settings = RenderSettings.for_scene(scene, shading=shading, size=(160, 120))
    free = render(scene, between, settings).color.copy()
    with_it = dataclasses.replace(scene, views=[*scene.views, between])
    listed = render(with_it, with_it.views[-1], settings, RenderContext()).color
    assert np.array_equal(free, listed)
    assert (free != free[0, 0]).any(axis=2).mean() > 0.02             # it drew something


def test_settings_refuse_what_no_renderer_can_do():
    with pytest.raises(ValueError, match="projection must be one of perspective, parallel"):
        RenderSettings(projection="fisheye")
    with pytest.raises(ValueError, match="whole number from 1 to 256"):
        RenderSettings(samples=0)
    with pytest.raises(ValueError, match="renderer must be one of"):
        render(load_scene(SCENES_DIR / "cube.toml"), WORKED, RenderSettings(renderer="pov"))


def test_an_invalid_view_gives_a_message_and_the_background():
    scene = load_scene(SCENES_DIR / "cube.toml")
    bad = dataclasses.replace(WORKED, vup=(0.0, 0.0, 1.0), label="tilted")
    frame = render(scene, bad, RenderSettings(size=(8, 6)))
    assert "VUP is parallel to VPN" in frame.message
    assert frame.color.shape == (6, 8, 3) and (frame.color == frame.color[0, 0]).all()


def test_regular_and_jittered_offsets_put_one_sample_in_each_stratum():
    assert np.allclose(sample_offsets(1), [[0.5, 0.5]])
    assert np.allclose(sample_offsets(4), [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]])
    jittered = sample_offsets(16, "jittered", seed=7)
    cell = np.floor(jittered * 4).astype(int)
    assert len({tuple(c) for c in cell}) == 16
    assert np.array_equal(jittered, sample_offsets(16, "jittered", seed=7))     # reproducible
    with pytest.raises(ValueError, match="square number"):
        sample_offsets(3, "regular")


def test_film_box_filter_rounds_the_mean_half_up():
    film = Film(1, 1, samples=2, pattern="jittered")
    film.add(np.full((1, 1, 3), 0, np.uint8))
    film.add(np.full((1, 1, 3), 255, np.uint8))
    assert film.resolve().tolist() == [[[128, 128, 128]]]            # 127.5 → 128


def _edge_scene() -> tuple[Scene, View]:
    """A white square whose right edge x = -1.2 cuts pixel column 0 (x from -2 to -1) of a
    1-unit-per-pixel, 4 x 4 parallel view: that column is 80 % covered, its centre inside."""
    from core.scene.model import Mesh
    square = Mesh(positions=[(-5, -5, 0), (-1.2, -5, 0), (-1.2, 5, 0), (-5, 5, 0)],
                  triangles=[(0, 1, 2), (0, 2, 3)],
                  material=Material(ka=1.0, kd=0.0, ks=0.0, od=(1.0, 1.0, 1.0)))
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-2, 2, -2, 2),
                prp=(0, 0, 10), front=1, back=-1)
    return Scene(name="edge", meshes=[square], views=[view], ambient=(1, 1, 1),
                 lights=[], shading="flat", projection="parallel"), view


# Regular 4 x 4: the sample columns at x = -1.875, -1.625, -1.375 are inside, -1.125 is not:
# exactly 12 of 16. Jittered 8 x 8: one sample per stratum, within a column of strata of 0.8.
@pytest.mark.parametrize("samples, pattern, expected, tolerance", [
    (16, "regular", 0.75, 0.5 / 255), (64, "jittered", 0.8, 1 / 8 + 0.5 / 255)])
def test_supersampling_averages_an_edge_to_its_covered_fraction(samples, pattern, expected,
                                                                 tolerance):
    scene, view = _edge_scene()
    settings = RenderSettings(projection="parallel", shading="flat", size=(4, 4),
                              samples=samples, sample_pattern=pattern, seed=3)
    frame = render(scene, view, settings)
    column = frame.color[:, 0, 0].astype(float) / 255
    assert np.allclose(column, expected, atol=tolerance), column
    assert (frame.color[:, 1:] == 0).all()


def test_primary_rays_of_the_worked_example_by_hand():
    # Pixel (0, 0) of a 18 x 18 framebuffer over the window -1..17 is centred on (u, v) =
    # (-0.5, 16.5) of the view plane z = 54; the eye is the PRP, (8, 6, 84) in world.
    origins, directions, inside = primary_rays(WORKED, "perspective", 18, 18)
    assert inside.all() and np.allclose(origins, (8.0, 6.0, 84.0))
    to_plane = np.array([-0.5, 16.5, 54.0]) - (8.0, 6.0, 84.0)
    assert np.allclose(directions[0], to_plane / np.linalg.norm(to_plane), atol=1e-15)
    # Parallel: origins on the view plane, all along the DOP (CW - PRP = (0, 2, -30)).
    origins, directions, _ = primary_rays(WORKED, "parallel", 18, 18, offsets=[(0.25, 0.75)])
    assert np.allclose(origins[0], (-0.75, 16.25, 54.0))
    dop = np.array([0.0, 2.0, -30.0])
    assert np.allclose(directions, dop / np.linalg.norm(dop))


def test_the_ray_caster_is_a_renderer_like_the_z_buffer():
    sphere = Sphere((0.0, 0.0, 0.0), 1.0, Material(od=(0.9, 0.3, 0.2)))
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1.5, 1.5, -1.5, 1.5),
                prp=(0, 0, 6), front=2, back=-2)
    scene = Scene(name="ball", meshes=[], views=[view], primitives=[sphere],
                  lights=[Light(position=(3.0, 4.0, 5.0))])
    frame = render(scene, view, RenderSettings(size=(40, 30), renderer="raycast", samples=4))
    exact = render_reference([sphere], scene, view, "perspective", (40, 30), samples=2)
    assert np.array_equal(frame.color, np.floor(exact.rgb * 255 + 0.5).astype(np.uint8))
    assert frame.stats["renderer"] == "raycast" and "exact ray casting" in frame.stats["computed"]
    empty = render(load_scene(SCENES_DIR / "cube.toml"), view, RenderSettings(renderer="raycast"))
    assert "no analytic primitives" in empty.message


def test_renderers_are_found_by_name_and_can_be_added():
    calls = []

    def stripes(scene, view, settings, frame, context, timer):
        calls.append(settings.pixel_offset)
        frame.color[:] = 0
        frame.color[:, ::2] = 255

    register_renderer("stripes", stripes)
    try:
        scene = load_scene(SCENES_DIR / "cube.toml")
        frame = render(scene, scene.views[0], RenderSettings(size=(4, 2), renderer="stripes",
                                                              samples=4, sample_pattern="jittered"))
        assert len(calls) == 4 and all(0 <= x < 1 and 0 <= y < 1 for x, y in calls)
        assert frame.color[:, 0].min() == 255 and frame.color[:, 1].max() == 0
    finally:
        from core.renderers import unregister_renderer
        unregister_renderer("stripes")
    assert "stripes" not in renderer_names()
    assert get_renderer("zbuffer").name == "zbuffer"


def test_the_z_buffer_frame_keeps_its_depth():
    scene, view = _edge_scene()
    frame = render(scene, view, RenderSettings(projection="parallel", shading="flat", size=(4, 4)))
    # The square lies in the view plane z = 0, halfway between F = 1 and B = -1: N_par puts it
    # at canonical depth -F / (F - B) = -0.5 (larger is nearer; -inf where nothing was drawn).
    assert np.allclose(frame.depth[:, 0], -0.5) and np.isneginf(frame.depth[:, 1:]).all()


def test_what_a_renderer_leaves_out_by_design_is_said():
    """A local renderer takes no light from an area emitter, and radiosity uses a material's
    colour, not its texture: each frame says so in ``stats["not drawn"]`` (render prints it),
    and a scene with neither says nothing."""
    from core import RenderSettings, render
    from core.scene.formats import load_scene
    from core.paths import SCENES_DIR

    def notes(name, renderer, **extra):
        scene = load_scene(SCENES_DIR / name)
        settings = RenderSettings.for_scene(scene, renderer=renderer, size=(24, 24), **extra)
        return render(scene, scene.views[0], settings).stats["not drawn"]

    assert any("emitter" in n for n in notes("cornell_box.toml", "zbuffer"))
    assert any("texture maps (floor)" in n for n in notes(
        "texture_floor.toml", "radiosity", max_elements=64, hemicube_resolution=16))
    assert notes("torus.toml", "zbuffer") == []
    # depth shading (the terrain's height colours): the tracers light it instead, and say so
    depth = "depth shading (the height colour map)"
    assert any(n.startswith(depth) for n in notes("terrain.toml", "raytrace"))
    assert not any(n.startswith(depth) for n in notes("terrain.toml", "zbuffer"))


def test_mirrors_and_glass_that_a_local_renderer_draws_opaque_are_said():
    """Whitted's mirror and glass spheres: the z-buffer and the painters draw them with their
    local colour only, and say so; asked for transparency, only the reflection is missing;
    the ray tracer draws both and says nothing of them."""
    from core import RenderSettings, render
    from core.scene.formats import load_scene
    from core.paths import SCENES_DIR
    scene = load_scene(SCENES_DIR / "whitted.toml")

    def notes(renderer, **extra):
        settings = RenderSettings.for_scene(scene, renderer=renderer, size=(24, 18), **extra)
        return render(scene, scene.views[0], settings).stats["not drawn"]

    for renderer in ("zbuffer", "bsp", "depth-sort"):
        said = notes(renderer, transparency="off")
        assert "the reflection in the mirror (mirror sphere): only raytrace, pathtrace and " \
               "twopass follow reflected rays" in said, renderer
        assert any(n.startswith("the transparency of glass sphere (k_t > 0): drawn opaque")
                   for n in said), renderer
        shown = notes(renderer, transparency="interpolated")
        assert not any("transparency" in n for n in shown) and any("mirror" in n for n in shown)
    assert not any("mirror" in n or "transparency" in n for n in notes("raytrace"))


def test_the_ray_caster_says_which_meshes_it_leaves_out():
    """Whitted's scene through the exact ray caster: the spheres are drawn, the checkered
    floor (a plane, a mesh to the caster) is said once, though it is two meshes."""
    from core import RenderSettings, render
    from core.scene.formats import load_scene
    from core.paths import SCENES_DIR
    scene = load_scene(SCENES_DIR / "whitted.toml")
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, renderer="raycast", size=(40, 30)))
    said = frame.stats["not drawn"]
    assert said.count("floor: the ray caster draws only the analytic spheres and tori") == 1
    assert not any("sphere: the ray caster" in n for n in said)
    assert (frame.color != frame.color[0, 0]).any(axis=2).sum() > 100     # the spheres


def test_the_path_tracer_says_it_takes_no_point_light_through_glass():
    """refraction.toml: the pool floor is lit by one point light through the water (k_t 0.9).
    The ray tracer's transmitted shadow rays light it; the path tracer's shadow rays stop at
    the water, so the floor under it is near black, and its frame says why."""
    from core import RenderSettings, render
    from core.scene.formats import load_scene
    from core.paths import SCENES_DIR
    scene = load_scene(SCENES_DIR / "refraction.toml")

    def frame(renderer):
        settings = RenderSettings.for_scene(scene, renderer=renderer, size=(48, 36), samples=4)
        return render(scene, scene.views[0], settings)
    traced, path = frame("raytrace"), frame("pathtrace")
    note = ("the scene's point and directional light through water (k_t > 0): pathtrace finds "
            "none through it (a caustic of a point light); an emitter's light is traced through")
    assert note in path.stats["not drawn"]
    assert not any("through water" in n for n in traced.stats["not drawn"])
    under = (slice(24, 36), slice(0, 48))              # the bottom third: floor under water
    assert traced.color[under].mean() > 40 > path.color[under].mean()

