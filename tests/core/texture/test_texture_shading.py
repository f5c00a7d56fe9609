"""The textured shader in the renderer: colour maps, bump and normal maps, environment maps,
bad texture files."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from core import render
from core.scene.formats import load_scene
from core.settings import RenderSettings
from core.texture import Texture
from core.texture.surface import bumped_normal, environment, mapped_normal

SPHERE = """
name = "t"
shading = "phong"
ambient = [0.2, 0.2, 0.2]
[[geometry]]
generator = "uv_sphere"
params = {{ radius = 1.0, segments = 48, rings = 24 }}
material = {{ ka = 0.3, kd = 0.6, ks = 0.4, n = 20, od = [0.8, 0.3, 0.2] {extra} }}
[[view]]
vrp = [0, 0, 0]
vpn = [0.2, 0.3, 1]
vup = [0, 1, 0]
window = [-1.2, 1.2, -1.2, 1.2]
prp = [0, 0, 5]
front = 1.5
back = -1.5
[[light]]
position = [3, 4, 5]
"""


def _scene(tmp_path, extra="", name="s.toml"):
    path = tmp_path / name
    path.write_text(SPHERE.format(extra=extra))
    return load_scene(path)


def _draw(scene, **settings):
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, size=(160, 160), **settings))
    assert frame.message is None
    return frame.color.astype(int)


def test_constant_texture_is_the_material_colour(tmp_path):
    """A texture of one colour c (sRGB) gives the picture of the material with O_d = c."""
    plain = _draw(_scene(tmp_path))
    textured = _draw(_scene(tmp_path, ', texture = { procedural = "checker", a = [0.8, 0.3, 0.2],'
                                      ' b = [0.8, 0.3, 0.2] }', "t.toml"))
    assert np.abs(plain - textured).max() <= 1


@pytest.mark.parametrize("filter_name", ["nearest", "bilinear", "trilinear", "anisotropic"])
def test_every_filter_draws(tmp_path, filter_name):
    scene = _scene(tmp_path, ', texture = { procedural = "checker", scale = 8 }')
    image = _draw(scene, texture_filter=filter_name)
    plain = _draw(_scene(tmp_path, "", "p.toml"))
    covered = (plain != plain[0, 0]).any(axis=2)
    values = image[covered].mean(axis=1)
    assert values.std() > 20            # the checker shows


def test_bad_texture_file_draws_untextured_with_a_message(tmp_path):
    (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"\x00" * 20)
    scene = _scene(tmp_path, ', texture = "broken.png", bump = "nowhere.png"')
    assert scene.view_messages == []                 # a texture is not a view: no view is invalid
    messages = " ".join(scene.messages)
    assert "broken.png" in messages and "geometry[1].material.texture" in messages
    assert "nowhere.png" in messages and "geometry[1].material.bump" in messages
    assert np.abs(_draw(scene) - _draw(_scene(tmp_path, "", "p.toml"))).max() <= 1


def test_no_bump_setting_ignores_height_maps(tmp_path):
    bumped = _scene(tmp_path, ', bump = { procedural = "perlin_height", scale = 4 }, '
                              'bump_scale = 0.05')
    plain = _draw(_scene(tmp_path, "", "p.toml"))
    assert np.abs(_draw(bumped, bump=False) - plain).max() <= 1
    assert np.abs(_draw(bumped) - plain).max() > 20


def test_unknown_texture_key_and_procedural_are_errors(tmp_path):
    from core.scene.formats import ReaderError
    with pytest.raises(ReaderError, match="material.texture.procedural"):
        _scene(tmp_path, ', texture = { procedural = "marble" }')
    with pytest.raises(ReaderError, match="unknown key 'colour'"):
        _scene(tmp_path, ', texture = { procedural = "checker", colour = 1 }')


def _ramp(direction):
    """A height map rising linearly along u (direction 0) or v (1), 64 x 64, clamped."""
    t = (np.arange(64) + 0.5) / 64
    h = np.broadcast_to(t[None, :] if direction == 0 else t[:, None], (64, 64))
    tex = Texture.from_array(np.array(h), wrap="clamp")
    texels, levels = tex.packed()
    return texels, levels, np.array([[0, len(levels), tex.wrap_code]], np.int64)


@pytest.mark.parametrize("direction", [0, 1])
def test_blinn_bump_on_a_ramp_is_the_displaced_surface_normal(direction):
    """Plane P(u, v) = (L u, L v, 0), height F = s u: the surface z = s x / L has the normal
    (−s/L, 0, 1) (and likewise along v)."""
    L, s = 2.0, 0.3
    texels, levels, textures = _ramp(direction)
    n = bumped_normal(0.0, 0.0, 1.0, L, 0.0, 0.0, 0.0, L, 0.0, texels, levels, textures, 0, s,
                      1, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0)
    expected = np.array([-s / L, 0.0, 1.0]) if direction == 0 else np.array([0.0, -s / L, 1.0])
    np.testing.assert_allclose(n, expected / np.linalg.norm(expected), atol=1e-6)


def test_flat_normal_map_keeps_the_normal_and_tilts_in_the_tangent_frame():
    flat = Texture.from_array(np.tile([0.5, 0.5, 1.0], (4, 4, 1)))
    texels, levels = flat.packed()
    table = np.array([[0, len(levels), 0]], np.int64)
    n = np.array([0.0, 0.6, 0.8])
    got = mapped_normal(*n, 1.0, 0.0, 0.0, 0.0, -0.8, 0.6, texels, levels, table, 0, 1,
                        0.5, 0.5, 0, 0, 0, 0)
    np.testing.assert_allclose(got, n, atol=1e-6)
    # rgb = (1, 0.5, 0.5): n_ts = (1, 0, 0), all along the tangent T = P_u
    tilted = Texture.from_array(np.tile([1.0, 0.5, 0.5], (4, 4, 1)))
    texels, levels = tilted.packed()
    got = mapped_normal(*n, 1.0, 0.0, 0.0, 0.0, -0.8, 0.6, texels, levels, table, 0, 1,
                        0.5, 0.5, 0, 0, 0, 0)
    np.testing.assert_allclose(got, [1.0, 0.0, 0.0], atol=1e-6)


def test_environment_lookup_directions():
    """Equirectangular: −z is the middle (u = ½, v = ½), +y the top row, +x at u = ¾."""
    h, w = 64, 128
    v, u = np.meshgrid((np.arange(h) + 0.5) / h, (np.arange(w) + 0.5) / w, indexing="ij")
    tex = Texture.from_array(np.stack([u, v, np.zeros_like(u)], axis=-1), wrap="clamp")
    texels, levels = tex.packed()
    table = np.array([[0, len(levels), tex.wrap_code]], np.int64)
    for direction, (eu, ev) in {(0, 0, -1): (0.5, 0.5), (0, 1, 0): (None, 1.0),
                                (1, 0, 0): (0.75, 0.5), (-1, 0, 0): (0.25, 0.5)}.items():
        r, g, _ = environment(texels, levels, table, 0, *map(float, direction))
        if eu is not None:
            assert r == pytest.approx(eu, abs=1 / w)
        assert g == pytest.approx(ev, abs=1 / h)


def test_textures_on_generators_and_scenes_render():
    for name in ("texture_floor", "texture_sphere_torus", "texture_bump_sphere",
                 "texture_env_normal"):
        scene = load_scene(f"scenes/{name}.toml")
        assert not scene.view_messages
        image = _draw(scene)
        assert image.std() > 10, name


def test_tangent_frame_of_a_plane_and_a_sphere():
    from core.scene.generators import plane, uv_sphere
    from core.texture.material import tangent_frames
    m = plane(size=4.0, subdivisions=3)
    frames = tangent_frames(m.positions, m.triangles, m.uv)
    np.testing.assert_allclose(frames[:, :3], np.tile([4.0, 0, 0], (len(frames), 1)), atol=1e-12)
    np.testing.assert_allclose(frames[:, 3:], np.tile([0, 0, -4.0], (len(frames), 1)), atol=1e-12)
    s = uv_sphere(radius=1.0, segments=64, rings=32)
    frames = tangent_frames(s.positions, s.triangles, s.uv)
    # away from the poles, dP/du and dP/dv are perpendicular to the radius (the normal)
    ring = np.abs(s.positions[:, 1]) < 0.7
    for part in (frames[ring, :3], frames[ring, 3:]):
        cos = np.abs(np.sum(part * s.positions[ring], axis=1)) / np.linalg.norm(part, axis=1)
        assert cos.max() < 0.05


@pytest.mark.parametrize("shading", ["flat", "gouraud"])
def test_flat_and_gouraud_draw_textured_materials_with_their_colour(tmp_path, shading):
    textured = _scene(tmp_path, ', texture = { procedural = "checker", scale = 8 }')
    plain = _scene(tmp_path, "", "p.toml")
    assert np.abs(_draw(textured, shading=shading) - _draw(plain, shading=shading)).max() == 0
    from core.plan import plan
    stage = [s for s in plan(textured, "perspective", shading) if s.name == "texture lookups"][0]
    assert not stage.runs and "per-pixel" in stage.reason


def test_viewer_texture_filter_reaches_the_settings():
    from app.session.state import ViewerState
    state = ViewerState.open("scenes/texture_floor.toml", size=(40, 40))
    assert state.choices.settings().texture_filter == "trilinear"
    state.choices.set_texture_filter("anisotropic")
    assert state.choices.settings().texture_filter == "anisotropic" and state.dirty
    with pytest.raises(ValueError):
        state.choices.set_texture_filter("cubic")


def test_obj_vt_is_textured(tmp_path):
    """An OBJ quad with ``vt``: the checker shows; without ``vt`` the plan says so."""
    quad = ("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    (tmp_path / "quad.obj").write_text(quad)
    (tmp_path / "bare.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n")
    scene_text = SPHERE.replace('generator = "uv_sphere"', 'file = "{mesh}"').replace(
        "params = {{ radius = 1.0, segments = 48, rings = 24 }}\n", "")
    for mesh in ("quad.obj", "bare.obj"):
        (tmp_path / f"{mesh}.toml").write_text(scene_text.format(
            mesh=mesh, extra=', texture = { procedural = "checker", scale = 4 }'))
    scene = load_scene(tmp_path / "quad.obj.toml")
    assert scene.meshes[0].uv is not None
    image = _draw(scene)
    covered = (image != image[0, 0]).any(axis=2)
    assert image[covered].mean(axis=1).std() > 20
    from core.plan import plan
    bare = load_scene(tmp_path / "bare.obj.toml")
    stage = [s for s in plan(bare, "perspective", "phong") if s.name == "texture lookups"][0]
    assert "has no (u, v)" in stage.reason
    flat = _draw(bare)
    assert flat[(flat != flat[0, 0]).any(axis=2)].mean(axis=1).std() < 20
