"""Depth cueing (FvDFH 16.1.3): I' = s_o I + (1 - s_o) I_dc, checked against hand values at
three depths on the z-buffer, the painters, the ray tracer and wireframe, in both projections."""

from __future__ import annotations

import numpy as np
import pytest

from core.camera.view import View
from core.context import RenderContext
from core.render import render
from core.scene.formats import ReaderError, read_scene_file
from core.scene.model import Light, Material, Mesh, Scene
from core.settings import RenderSettings
from core.effects.depth_cue import DepthCue, scale_factor

# Three squares facing the viewer at view depths -2, -5, -8 (along the VPN from the VRP), lit
# by ambient light only (k_a = 1, I_a = 1: I = O_d = 0.8 exactly, on every renderer). The cue
# planes at 0 and -10 with s = 1 and 0 give s_o = 0.8, 0.5, 0.2.
DEPTHS = (-2.0, -5.0, -8.0)
CENTRES_X = (-3.0, 0.0, 3.0)
I_DC = (0.2, 0.4, 0.6)
# hand values: 255 (s_o 0.8 + (1 - s_o) I_dc), rounded half up
EXPECTED = {
    -2.0: (round(255 * (0.8 * 0.8 + 0.2 * 0.2)), round(255 * (0.64 + 0.2 * 0.4)),
           round(255 * (0.64 + 0.2 * 0.6))),          # 0.68, 0.72, 0.76 -> 173, 184, 194
    -5.0: (round(255 * 0.5), round(255 * 0.6), round(255 * 0.7)),    # 0.5, 0.6, 0.7
    -8.0: (round(255 * 0.32), round(255 * 0.48), round(255 * 0.64)),  # 0.2*0.8 + 0.8*I_dc
}


def _squares(shading="flat") -> Scene:
    meshes = []
    for x, z in zip(CENTRES_X, DEPTHS):
        p = np.array([[x - 1, -1, z], [x + 1, -1, z], [x + 1, 1, z], [x - 1, 1, z]])
        meshes.append(Mesh(positions=p, triangles=[[0, 1, 2], [0, 2, 3]], edges=np.zeros((0, 2)),
                           material=Material(ka=1.0, kd=0.0, ks=0.0, od=(0.8, 0.8, 0.8))))
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-6, 6, -6, 6),
                prp=(0, 0, 20), front=1.0, back=-15.0)
    return Scene(name="squares", meshes=meshes, views=[view], ambient=(1.0, 1.0, 1.0),
                 lights=[Light(position=(0, 0, 50), intensity=(0.0, 0.0, 0.0))],
                 background=(0.0, 0.0, 0.0), line_color=(0.8, 0.8, 0.8), shading=shading,
                 depth_cue=DepthCue(front=0.0, back=-10.0, s_front=1.0, s_back=0.0, color=I_DC))


def test_scale_factor_by_hand():
    assert np.allclose(scale_factor([-2.0, -5.0, -8.0], 0.0, -10.0, 1.0, 0.0), [0.8, 0.5, 0.2])
    # clamped to s_f in front of the front plane and s_b behind the back one
    assert np.allclose(scale_factor([3.0, -12.0], 0.0, -10.0, 0.9, 0.1), [0.9, 0.1])


def _centre_pixel(x_world, z, projection, size=500):
    """The pixel where the square's centre (x_world, 0, z) lands."""
    scale = size / 12.0
    if projection == "perspective":
        x_world = x_world * 20.0 / (20.0 - z)      # onto the view plane from PRP (0, 0, 20)
    return int((x_world + 6.0) * scale), size // 2


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("renderer", ["zbuffer", "raytrace", "bsp", "depth-sort"])
def test_surfaces_cued_at_three_depths(renderer, projection):
    scene = _squares()
    settings = RenderSettings.for_scene(scene, renderer=renderer, projection=projection)
    assert settings.depth_cue                   # on: the scene has the table
    frame = render(scene, scene.views[0], settings, RenderContext())
    assert frame.message is None
    for x, z in zip(CENTRES_X, DEPTHS):
        col, row = _centre_pixel(x, z, projection)
        got = frame.color[row - 3:row + 4, col - 3:col + 4].reshape(-1, 3)
        assert (np.abs(got.astype(int) - EXPECTED[z]) <= 1).all(), (z, got[0], EXPECTED[z])
    off = render(scene, scene.views[0], settings.replace(depth_cue=False), RenderContext())
    col, row = _centre_pixel(0.0, -5.0, projection)
    assert tuple(off.color[row, col]) == (204, 204, 204)        # 0.8 uncued


def test_a_ray_tracer_under_a_new_name_is_cued_by_its_rays():
    """The ray tracer's function under a new name with its capabilities (``ray_depth``,
    ``blur_per_ray``): depth cueing casts its primary rays for the depths, as for the ray
    tracer (its frame has no depth buffer), and motion blur may time its rays."""
    from types import SimpleNamespace

    from core.animation import ray_blur
    from core.renderers import register_renderer, unregister_renderer
    register_renderer("whitted-again", "core.renderers.raytrace.draw:draw", samples_itself=True,
                      options="core.renderers.raytrace.options:RaytraceOptions", recursive=True,
                      ray_depth=True, blur_per_ray=True)
    try:
        scene = _squares()
        settings = RenderSettings.for_scene(scene, renderer="whitted-again",
                                            projection="parallel")
        frame = render(scene, scene.views[0], settings, RenderContext())
        assert frame.message is None and frame.depth is None
        for x, z in zip(CENTRES_X, DEPTHS):
            col, row = _centre_pixel(x, z, "parallel")
            assert (np.abs(frame.color[row, col].astype(int) - EXPECTED[z]) <= 1).all()
        traced = render(scene, scene.views[0], settings.replace(renderer="raytrace"),
                        RenderContext())
        assert np.array_equal(frame.color, traced.color)
        still = SimpleNamespace(sprites_at=lambda t: None)       # no particles
        assert ray_blur.usable(still, 0.0, settings.replace(depth_cue=False)) is None
        assert ray_blur.usable(still, 0.0, settings.replace(depth_cue=False,
                                                            renderer="zbuffer")) is not None
    finally:
        unregister_renderer("whitted-again")


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
def test_wireframe_cued_at_three_depths(projection):
    scene = _squares("wireframe")
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, projection=projection),
                   RenderContext())
    for x, z in zip(CENTRES_X, DEPTHS):
        col, row = _centre_pixel(x, z, projection)
        # the square's edges: every lit pixel within its box
        half = int((col - _centre_pixel(x - 1.0, z, projection)[0]) + 2)
        box = frame.color[row - half:row + half + 1, col - half:col + half + 1].reshape(-1, 3)
        lit = box[box.any(axis=1)]
        assert len(lit) > 100
        assert (np.abs(lit.astype(int) - EXPECTED[z]) <= 1).all(), (z, np.unique(lit, axis=0))


def test_scene_table_defaults_and_errors():
    base = """
[[geometry]]
generator = "cube"
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 8]
front = 2
back = -2
"""
    scene = read_scene_file(base + "[depth_cue]\n", "cue.toml")
    assert scene.depth_cue == DepthCue()
    z_f, z_b, s_f, s_b, color = scene.depth_cue.resolved(scene.views[0], scene.background)
    assert (z_f, z_b, s_f, s_b, tuple(color)) == (2.0, -2.0, 1.0, 0.0, scene.background)
    assert RenderSettings.for_scene(scene).depth_cue
    assert not RenderSettings.for_scene(read_scene_file(base, "plain.toml")).depth_cue
    with pytest.raises(ReaderError, match=r"depth_cue.*back.*behind the front one"):
        read_scene_file(base + "[depth_cue]\nfront = -1\nback = 0\n", "bad.toml")
    with pytest.raises(ReaderError, match=r"depth_cue.*unknown key 'near'"):
        read_scene_file(base + "[depth_cue]\nnear = 1\n", "bad.toml")
    with pytest.raises(ReaderError, match=r"s_back"):
        read_scene_file(base + "[depth_cue]\ns_back = 2\n", "bad.toml")
