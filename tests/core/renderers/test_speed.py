"""The speed work changes no picture: deferred lighting computes the numbers the
eager path computes, the z-buffer's spans never leave a stale pixel, the background memset is
the colour asked for; and the bench's two new rows draw the same scene."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tools import llvmpipe_context

from core import RenderContext, RenderSettings, View, render
from core.camera.film import fill_bytes
from core.scene.generators import sphere_torus


@pytest.fixture(scope="module")
def scene():
    return sphere_torus(triangles=4000)


def _cutting_view(scene) -> View:
    """The first view with its front plane moved into the torus, so triangles get clipped."""
    return dataclasses.replace(scene.views[0], front=0.3)


@pytest.mark.parametrize("shading", ["flat", "gouraud"])
def test_deferred_lighting_gives_the_eager_image_bit_for_bit(scene, shading, monkeypatch):
    from core.shading import shade
    view = _cutting_view(scene)
    settings = RenderSettings.for_scene(scene, shading=shading, size=(160, 120))
    monkeypatch.setattr(shade, "LIGHT_ALL_BELOW", 0)      # defer even for this small scene
    monkeypatch.setattr(shade, "LAZY_ITEMS_PER_PIXEL", 0.0)
    lazy = render(scene, view, settings, context=RenderContext())
    eager_prepare = shade.prepare

    def eager(*args, **kwargs):
        kwargs["lazy"] = False
        return eager_prepare(*args, **kwargs)

    monkeypatch.setattr(shade, "prepare", eager)
    eager_frame = render(scene, view, settings, context=RenderContext())
    assert np.array_equal(lazy.color, eager_frame.color)


@pytest.mark.parametrize("triangles, size, lazy", [(4000, (64, 48), False),
                                                   (20_000, (64, 48), True),
                                                   (20_000, (320, 240), False)])
def test_small_scenes_light_every_front_face_at_once(triangles, size, lazy, monkeypatch):
    """Below shade.LIGHT_ALL_BELOW triangles the z-buffer lights in the vertex step (the
    pass that finds the visible faces would cost more); above it, it defers, unless the
    items lit (here the vertices, about half the triangles) are at most a fifth of the
    picture's pixels (20,000 triangles: 10,401 vertices against 614 and 15,360)."""
    from core.shading import shade
    asked = []
    prepare = shade.prepare

    def spy(*args, **kwargs):
        asked.append(kwargs["lazy"])
        return prepare(*args, **kwargs)

    monkeypatch.setattr(shade, "prepare", spy)
    small = sphere_torus(triangles=triangles)
    render(small, small.views[0], RenderSettings.for_scene(small, shading="gouraud",
                                                           size=size),
           context=RenderContext())
    assert asked == [lazy]


def test_the_cutting_view_really_clips(scene):
    frame = render(scene, _cutting_view(scene),
                   RenderSettings.for_scene(scene, shading="gouraud", size=(160, 120)),
                   context=RenderContext())
    # clipped triangles are fanned into new ones: more rasterized than kept after culling
    kept = frame.stats["triangles in"] - frame.stats.get("culled", 0)
    assert frame.stats["triangles rasterized"] != kept


def test_spans_leave_no_stale_pixel_from_a_larger_frame(scene):
    """A big picture, then a small one, in one context: the same as the small one alone."""
    settings = RenderSettings.for_scene(scene, shading="gouraud", size=(200, 200))
    near = dataclasses.replace(scene.views[0], window=(-1.2, 1.2, -1.2, 1.2))
    far = dataclasses.replace(scene.views[0], window=(-9.0, 9.0, -9.0, 9.0))
    shared = RenderContext()
    render(scene, near, settings, context=shared)
    after = render(scene, far, settings, context=shared)
    depth_after = after.depth.copy()
    alone = render(scene, far, settings, context=RenderContext())
    assert np.array_equal(after.color, alone.color)
    assert np.array_equal(depth_after, alone.depth)
    assert np.isneginf(alone.depth).mean() > 0.8          # the far picture is mostly empty


def test_the_scanline_rasterizer_then_the_edge_one_share_a_buffer(scene):
    settings = RenderSettings.for_scene(scene, shading="gouraud", size=(120, 120))
    shared = RenderContext()
    big = dataclasses.replace(scene.views[0], window=(-1.2, 1.2, -1.2, 1.2))
    render(scene, big, dataclasses.replace(settings, rasterizer="scanline"), context=shared)
    small = dataclasses.replace(scene.views[0], window=(-9.0, 9.0, -9.0, 9.0))
    after = render(scene, small, settings, context=shared)
    alone = render(scene, small, settings, context=RenderContext())
    assert np.array_equal(after.color, alone.color)


def test_fill_bytes_fills_a_frame_view_and_a_plain_image():
    rgbx = np.zeros((3, 5, 4), np.uint8)
    fill_bytes(rgbx[:, :, :3], [10, 20, 30])
    assert np.all(rgbx[:, :, :3] == [10, 20, 30])
    plain = np.zeros((2, 3, 3), np.uint8)
    fill_bytes(plain, [1, 2, 3])
    assert np.all(plain == [1, 2, 3])
    strided = np.zeros((4, 6, 3), np.uint8)[::2, ::2]
    fill_bytes(strided, [7, 8, 9])
    assert np.all(strided == [7, 8, 9])


def test_the_floor_draws_the_pixels_we_draw(scene):
    from app.bench.floor import Floor
    floor = Floor(scene, (200, 200))
    words = floor.frame(scene.views[0])
    ours = render(scene, scene.views[0],
                  RenderSettings.for_scene(scene, shading="gouraud", size=(200, 200)),
                  context=RenderContext())
    background = int(floor.background)
    covered_floor = words != background
    covered_ours = np.isfinite(ours.depth)
    assert (covered_floor != covered_ours).mean() < 0.01


def test_the_lean_gl_row_draws_the_pixels_we_draw(scene):
    from app.oracles.lean_gl import LeanGL
    gl = LeanGL((200, 200), ctx=llvmpipe_context())      # only the context may be missing
    try:
        gl.load(scene)
        gl.draw(scene.views[0], "perspective", "gouraud")
        image = gl.read()
    finally:
        gl.release()
    ours = render(scene, scene.views[0],
                  RenderSettings.for_scene(scene, shading="gouraud", size=(200, 200)),
                  context=RenderContext())
    from core.camera.film import to_rgb8
    background = to_rgb8(scene.background)
    covered_gl = np.any(image != background, axis=2)
    covered_ours = np.isfinite(ours.depth)
    assert (covered_gl != covered_ours).mean() < 0.01
