"""Transparency in the z-buffer family (FvDFH 16.5.1): a k_t = 0.5 pane over a square gives
the interpolated formula's value, the ray tracer agrees under the stated correspondence, and
screen-door's 4 x 4 tile means equal the interpolated value."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.view import View
from core.context import RenderContext
from core.raytrace.optics import AIR
from core.render import render
from core.scene.model import Light, Material, Mesh, Scene
from core.settings import RenderSettings

# Under I_a = 0.2 and a directional light of intensity 1 along +z, a square facing +z with
# k_a = k_d = 0.5 (k_s = 0) has I = (0.5 * 0.2 + 0.5 * 1) O_d = 0.6 O_d.
BEHIND_OD, PANE_OD, KT = (0.2, 0.6, 1.0), (1.0, 0.5, 0.0), 0.5
I2 = tuple(0.6 * c for c in BEHIND_OD)            # (0.12, 0.36, 0.60)
I1 = tuple(0.6 * c for c in PANE_OD)              # (0.60, 0.30, 0.00)
BLEND = tuple((1 - KT) * a + KT * b for a, b in zip(I1, I2))     # (0.36, 0.33, 0.30)
HAND = tuple(int(255 * c + 0.5) for c in BLEND)   # (92, 84, 77)


def _square(z, half, material):
    p = np.array([[-half, -half, z], [half, -half, z], [half, half, z], [-half, half, z]])
    return Mesh(positions=p, triangles=[[0, 1, 2], [0, 2, 3]], material=material)


def _scene(pane: Material) -> Scene:
    behind = _square(-2.0, 2.0, Material(ka=0.5, kd=0.5, ks=0.0, od=BEHIND_OD))
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-3, 3, -3, 3),
                prp=(0, 0, 10), front=2.0, back=-5.0)
    return Scene(name="pane", meshes=[behind, _square(1.0, 1.0, pane)], views=[view],
                 ambient=(0.2, 0.2, 0.2), lights=[Light(direction=(0, 0, 1))],
                 background=(0, 0, 0), transparency="interpolated")


PANE = Material(ka=0.5, kd=0.5, ks=0.0, od=PANE_OD, kt=KT, ior=AIR)
CENTRE = (slice(240, 260), slice(240, 260))       # behind the pane
OUTSIDE = (slice(245, 255), slice(140, 150))      # only the square behind


@pytest.mark.parametrize("renderer", ["zbuffer", "bsp", "depth-sort"])
@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_interpolated_pane_by_hand(renderer, projection):
    scene = _scene(PANE)
    settings = RenderSettings.for_scene(scene, renderer=renderer, projection=projection)
    assert settings.transparency == "interpolated"
    frame = render(scene, scene.views[0], settings, RenderContext())
    pane = frame.color[CENTRE].reshape(-1, 3).astype(int)
    # within one level: I_1 and I_2 are bytes before they are blended
    assert (np.abs(pane - HAND) <= 1).all(), (pane[0], HAND)
    assert (frame.color[OUTSIDE].reshape(-1, 3) == [31, 92, 153]).all()     # I_2 alone
    off = render(scene, scene.views[0], settings.replace(transparency="off"), RenderContext())
    assert (off.color[CENTRE].reshape(-1, 3) == [153, 77, 0]).all()         # drawn opaque


def test_ray_tracer_agrees_under_the_correspondence():
    """Whitted: I = I_local + k_t I_t. With the pane's ior equal to the medium's (no bending),
    no mirror term, shadows off (the z-buffer casts none) and its local terms scaled by
    (1 - k_t) (k_a, k_d halved: I_local = (1 - k_t) I_1), this is (1 - k_t) I_1 + k_t I_2."""
    scaled = Material(ka=0.5 * (1 - KT), kd=0.5 * (1 - KT), ks=0.0, od=PANE_OD, kt=KT, ior=AIR)
    traced_scene = _scene(scaled)
    settings = RenderSettings.for_scene(traced_scene, renderer="raytrace", shadows="off")
    traced = render(traced_scene, traced_scene.views[0], settings, RenderContext())
    assert traced.message is None
    scene = _scene(PANE)
    zbuffer = render(scene, scene.views[0], RenderSettings.for_scene(scene), RenderContext())
    for region in (CENTRE, OUTSIDE):
        error = np.abs(traced.color[region].astype(int) - zbuffer.color[region])
        assert error.max() <= 2, error.max()
    assert (np.abs(traced.color[CENTRE].reshape(-1, 3).astype(int) - HAND) <= 2).all()


@pytest.mark.parametrize("renderer", ["zbuffer", "depth-sort"])
def test_screen_door_tile_means(renderer):
    scene = _scene(PANE)
    settings = RenderSettings.for_scene(scene, renderer=renderer)
    interpolated = render(scene, scene.views[0], settings, RenderContext()).color
    door = render(scene, scene.views[0], settings.replace(transparency="screen-door"),
                  RenderContext()).color
    tiles = door[240:256, 240:256].reshape(4, 4, 4, 4, 3).mean(axis=(1, 3))   # 4 x 4 tiles
    assert np.abs(tiles - interpolated[240:256, 240:256].reshape(4, 4, 4, 4, 3).mean(
        axis=(1, 3))).max() <= 1.0
    # half the pixels of every tile show the pane, half the square behind
    shown = (door[240:256, 240:256] == [153, 77, 0]).all(axis=2)
    assert shown.reshape(4, 4, 4, 4).sum(axis=(1, 3)).tolist() == [[8] * 4] * 4


@pytest.mark.parametrize("renderer", ["zbuffer", "depth-sort"])
def test_the_notes_second_recipe_adds_the_near_ones_specular_by_hand(renderer):
    # FvDFH 16.5.1 / the notes (L2104): ambient + diffuse of the near surface interpolated with
    # the far colour, then its specular added. Parallel along -z, the light along +z: R = V,
    # so (R . V)^n = 1 and the pane's specular is k_s O_s = 0.3 in every channel.
    shiny = Material(ka=0.5, kd=0.5, ks=0.3, n=10, od=PANE_OD, kt=KT, ior=AIR)
    scene = _scene(shiny)
    settings = RenderSettings.for_scene(scene, renderer=renderer, projection="parallel",
                                        shading="phong")
    ad = I1                                                   # (0.60, 0.30, 0.00)
    added = tuple((1 - KT) * a + KT * b + 0.3 for a, b in zip(ad, I2))      # (0.66, 0.63, 0.60)
    dimmed = tuple((1 - KT) * (a + 0.3) + KT * b for a, b in zip(ad, I2))   # (0.51, 0.48, 0.45)
    for mode, value in (("interpolated-specular", added), ("interpolated", dimmed)):
        frame = render(scene, scene.views[0], settings.replace(transparency=mode),
                       RenderContext())
        pane = frame.color[CENTRE].reshape(-1, 3).astype(int)
        hand = np.array([int(255 * c + 0.5) for c in value])
        assert (np.abs(pane - hand) <= 1).all(), (mode, pane[0], hand)


def _random_triangles(rng, count, width, height):
    """``count`` triangles of random size over a ``width`` x ``height`` picture, some off it."""
    centres = rng.uniform(-5, [width + 5, height + 5], (count, 2))
    corners = centres[:, None, :] + rng.normal(0, rng.uniform(0.5, 12, (count, 1, 1)),
                                                (count, 3, 2))
    xy_z = np.column_stack([corners.reshape(-1, 2), np.zeros(3 * count)])
    return xy_z, np.ones(3 * count), np.arange(3 * count).reshape(-1, 3)


def test_layers_share_no_pixel_and_each_pixel_meets_its_triangles_in_rising_layers():
    """The layers come from the rasterizer's own coverage (count_fragments, each triangle
    alone, is the oracle): a layer's triangles never cover one pixel twice; a pixel's
    triangles, in painting order, sit in strictly rising layers; each triangle sits just
    above the highest layer it covers (so there are as few layers as the depth allows)."""
    from core.effects.transparency import coverage_layers
    from core.pipeline.raster import count_fragments
    rng = np.random.default_rng(7)
    width, height = 40, 30
    xy_z, inv_w, triangles = _random_triangles(rng, 150, width, height)
    layers = coverage_layers(xy_z, inv_w, triangles, width, height)
    covers = [count_fragments(xy_z, inv_w, triangles[t:t + 1], width, height, parallel=False) > 0
              for t in range(len(triangles))]
    top = np.zeros((height, width), np.int64)
    for t, covered in enumerate(covers):
        expected = top[covered].max() if covered.any() else 0
        if covered.any():
            assert layers[t] == expected, t
        top[covered] = layers[t] + 1
    for layer in range(layers.max() + 1):
        chosen = triangles[layers == layer]
        together = count_fragments(xy_z, inv_w, chosen, width, height, parallel=False)
        assert together.max() <= 1, layer
    assert 2 < layers.max() + 1 < 40        # overlaps, but far fewer layers than triangles


def test_a_closed_glass_sphere_is_two_layers():
    """The sphere's back faces cover each pixel once and its front faces once: two layers,
    however many triangles (by pixel box it was nearly one layer a triangle)."""
    from core.scene.generators import uv_sphere
    glass = Material(ka=0.1, kd=0.2, ks=0.5, od=(0.8, 0.9, 1.0), kt=0.6, ior=AIR)
    ball = uv_sphere(radius=1.0)
    sphere = Mesh(positions=ball.positions + [0.0, 0.0, -1.0], triangles=ball.triangles,
                  material=glass)
    scene = _scene(PANE)
    scene = Scene(name="glass", meshes=[scene.meshes[0], sphere], views=scene.views,
                  ambient=scene.ambient, lights=scene.lights, background=(0, 0, 0),
                  transparency="interpolated")
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, size=(80, 80)))
    assert frame.stats["transparent triangles"] > 500
    assert frame.stats["transparency layers"] == 2
