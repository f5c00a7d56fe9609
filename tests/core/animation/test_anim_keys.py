"""Scene-file keys: [animation] and [[key]] read into tracks; scene_at / view_at."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from core.animation.keys import animation_of
from core.camera.view import View, n_per_factors
from core.scene.formats import ReaderError, read_scene_file
from core.transforms import rotate_y

SCENE = """
name = "keyed"
shading = "flat"
[[geometry]]
generator = "cube"
name = "box"
[[light]]
position = [3, 4, 6]
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 8]
front = 3
back = -3
[animation]
fps = 10
interpolation = "linear"
orientation = "slerp"
[[key]]
time = 0
view = { vrp = [0, 0, 0], vpn = [0, 0, 1], vup = [0, 1, 0] }
object.box = { rotate = [0, 0, 0], translate = [0, 0, 0] }
light.1 = { position = [3, 4, 6] }
material.box = { od = [1, 0, 0] }
[[key]]
time = 2
view = { vrp = [2, 0, 0], vpn = [1, 0, 0], vup = [0, 1, 0] }
object.box = { rotate = [0, 90, 0], translate = [0, 2, 0] }
light.1 = { position = [-3, 4, 6] }
material.box = { od = [0, 0, 1] }
"""


def load(text=SCENE):
    scene = read_scene_file(text, "keyed.toml")
    return scene, animation_of(scene)


def test_the_file_gives_duration_fps_and_frames():
    scene, anim = load()
    assert anim.duration == 2.0 and anim.fps == 10.0 and anim.frame_count == 20
    assert animation_of(read_scene_file(SCENE.split("[animation]")[0], "still.toml")) is None


def test_halfway_view_is_the_hand_computed_middle_view():
    """VPN from +z to +x by slerp: halfway it is (1, 0, 1)/sqrt 2, VUP stays +y; VRP lerps."""
    scene, anim = load()
    mid = anim.view_at(1.0)
    r = np.sqrt(0.5)
    hand = View(vrp=(1.0, 0.0, 0.0), vpn=(r, 0.0, r), vup=(0.0, 1.0, 0.0),
                window=(-2.0, 2.0, -2.0, 2.0), prp=(0.0, 0.0, 8.0), front=3.0, back=-3.0)
    ours, theirs = n_per_factors(mid), n_per_factors(hand)
    for name in ("R", "T_vrp", "N_per"):
        assert np.allclose(ours[name], theirs[name], rtol=0, atol=1e-12), name


def test_halfway_frame_renders_as_the_still_middle_view():
    from core import render
    from core.settings import RenderSettings
    import dataclasses
    scene, anim = load()
    mid_scene = anim.scene_at(1.0)
    settings = RenderSettings.for_scene(scene, size=(96, 96))
    r = np.sqrt(0.5)
    hand = View(vrp=(1.0, 0.0, 0.0), vpn=(r, 0.0, r), vup=(0.0, 1.0, 0.0),
                window=(-2.0, 2.0, -2.0, 2.0), prp=(0.0, 0.0, 8.0), front=3.0, back=-3.0)
    keyed = render(mid_scene, mid_scene.views[0], settings).color.copy()
    still = render(dataclasses.replace(mid_scene, views=[hand]), hand, settings).color
    assert np.array_equal(keyed, still)
    assert len(np.unique(keyed.reshape(-1, 3), axis=0)) >= 2          # something was drawn
    # (the box face in view is one flat polygon now: one colour besides the background)


def test_object_light_and_colour_tracks():
    scene, anim = load()
    mid = anim.scene_at(1.0)
    box, moved = scene.meshes[0], mid.meshes[0]
    expected = box.positions @ rotate_y(np.radians(45))[:3, :3].T + [0, 1, 0]
    assert np.allclose(moved.positions, expected, atol=1e-12)
    assert np.allclose(mid.lights[0].position, (0, 4, 6))
    assert np.allclose(mid.meshes[0].material.od, (0.5, 0, 0.5))
    assert scene.meshes[0].positions is box.positions          # the still scene is untouched
    assert mid.views[1] == scene.views[0]                       # the still views follow


def test_loop_wraps_time():
    scene, anim = load(SCENE.replace('fps = 10', 'fps = 10\nloop = true'))
    assert np.allclose(anim.view_at(2.5).vrp, anim.view_at(0.5).vrp)
    scene, anim = load()
    assert np.allclose(anim.view_at(2.5).vrp, anim.view_at(2.0).vrp)      # held at the end


@pytest.mark.parametrize("change,message", [
    (("view = { vrp = [2, 0, 0], vpn = [1, 0, 0], vup = [0, 1, 0] }",
      "view = { vrp = [2, 0, 0], vpn = [1, 0, 0] }"), "keyed.toml:29: key[2].view: vpn and vup are keyed together"),
    (("object.box = { rotate = [0, 90, 0]", "object.bax = { rotate = [0, 90, 0]"),
     "keyed.toml:30: key[2].object.bax: unknown key 'bax' (allowed: box)"),
    (("time = 2", "time = 0"), "a second key for"),
    (("time = 2", "tim = 2"), "keyed.toml:28: key[2].tim: unknown key 'tim'"),
    (('interpolation = "linear"', 'interpolation = "cubic"'), "animation.interpolation: 'cubic' is not one of"),
    (("fps = 10", "fps = 0"), "animation.fps: must be greater than 0"),
    (("light.1 = { position = [-3, 4, 6] }", "light.2 = { position = [-3, 4, 6] }"),
     "key[2].light.2: unknown key '2'"),
])
def test_bad_keys_name_the_key_and_line(change, message):
    with pytest.raises(ReaderError) as error:
        load(SCENE.replace(*change))
    assert message in str(error.value)


def test_level_keeps_the_horizon_level_where_slerp_alone_rolls():
    """Two level frames (VUP +y) that differ in pitch and yaw: the great arc between them
    rolls the camera (u leaves the horizontal plane); with level the u axis stays horizontal
    and VPN is still the slerped one."""
    from core.camera.view import vrc_basis
    text = SCENE.replace("vpn = [1, 0, 0], vup = [0, 1, 0] }", "vpn = [1, 0.8, 0], vup = [0, 1, 0] }")
    rolled = max(abs(vrc_basis(load(text)[1].view_at(t))[0][1]) for t in np.linspace(0, 2, 21))
    assert rolled > 0.05
    scene, anim = load(text.replace('orientation = "slerp"', 'orientation = "slerp"\nlevel = [0, 1, 0]'))
    plain = load(text)[1]
    for t in np.linspace(0, 2, 21):
        u = vrc_basis(anim.view_at(t))[0]
        assert abs(u[1]) < 1e-12
        n, n_plain = (np.array(v.vpn) / np.linalg.norm(v.vpn) for v in (anim.view_at(t), plain.view_at(t)))
        assert np.allclose(n, n_plain, atol=1e-12)


def test_the_eye_path_passes_through_the_keyed_eyes_and_is_drawn():
    from core import RenderSettings
    from core.animation.frames import render_at
    from core.animation.paths import eye_of, paths_of
    scene, anim = load()
    path = paths_of(anim, samples_per_second=10)["view.eye"]          # t = 0, 0.1, … 2
    # key 1: VRP 0, VPN +z, PRP (0, 0, 8) → eye (0, 0, 8); key 2: VRP (2, 0, 0), VPN +x → (10, 0, 0)
    assert np.allclose(path[0], [0, 0, 8]) and np.allclose(path[-1], [10, 0, 0])
    assert np.allclose(path[10], eye_of(anim.view_at(1.0)))
    assert np.allclose(np.linalg.norm(path - [1, 0, 0] * np.linspace(0, 2, 21)[:, None], axis=1), 8)
    settings = RenderSettings.for_scene(scene, size=(64, 64), projection="parallel")
    top = dataclasses.replace(scene.views[0], vrp=(5.0, 0.0, 4.0), vpn=(0.0, 1.0, 0.0),
                              vup=(0.0, 0.0, -1.0), window=(-8.0, 8.0, -8.0, 8.0), prp=(0.0, 0.0, 20.0),
                              front=10.0, back=-10.0)
    scene.views.append(top)                                      # a still view from above
    plain = render_at(anim, 1.0, settings, view_index=2).color.copy()
    drawn = render_at(anim, 1.0, settings, view_index=2, paths=True).color
    changed = np.any(drawn != plain, axis=2)
    assert changed.sum() > 20 and np.all(drawn[changed] == [255, 217, 51])
