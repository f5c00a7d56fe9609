"""Update dynamics keyed (the notes of 11 April: "changes in shape, color, transparency,
size"; the lighting among the environmental changes): a material's k_t and a light's
intensity as channels beside O_d, the transform's scale and the light's position."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from app.cli import main
from core.animation.keys import animation_of
from core.scene.formats import ReaderError, read_scene_file

SCENE = "scenes/update_dynamics.toml"


def test_keyed_transparency_size_and_intensity_are_the_straight_lines_between_the_keys():
    anim = animation_of(read_scene_file(open(SCENE).read(), SCENE))
    names = [m.name for m in anim.scene.meshes]
    at = anim.scene_at(1.0)                                # a quarter of the way
    assert at.meshes[names.index("pane")].material.kt == pytest.approx(0.2, abs=1e-15)
    assert at.lights[0].intensity == pytest.approx((0.9, 0.7875, 0.775), abs=1e-15)
    assert at.lights[1].intensity == (0.25, 0.25, 0.3)     # not keyed: as in the file
    ring0 = anim.scene.meshes[names.index("ring")].positions
    ring1 = at.meshes[names.index("ring")].positions
    assert np.allclose(ring1, 1.15 * ring0, atol=1e-12)   # scale 1 + 0.25 (1.6 - 1)
    assert at.meshes[names.index("ring")].material.kt == 0.0


PANE = """
shading = "flat"
transparency = "interpolated"
background = [0, 0, 0]
size = [48, 48]
[[geometry]]
generator = "cube"
name = "box"
transform = { translate = [0, 0, -1] }
material = { od = [0.9, 0.3, 0.2] }
@PANE@
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-1.5, 1.5, -1.5, 1.5]
prp = [0, 0, 6]
front = 2
back = -3
[[light]]
position = [2, 3, 5]
intensity = @INTENSITY@
@ANIMATION@
"""
PANE_GEOMETRY = """[[geometry]]
generator = "plane"
name = "pane"
params = { size = 4 }
transform = { rotate = [90, 0, 0], translate = [0, 0, 1] }
material = { od = [0.3, 0.6, 0.9], kt = KT }"""
KEYS = """[animation]
duration = 2
interpolation = "linear"
[[key]]
time = 0
material.pane = { kt = 0.0 }
light.1 = { intensity = [1, 1, 1] }
[[key]]
time = 2
material.pane = { kt = 1.0 }
light.1 = { intensity = [0.2, 0.4, 0.6] }"""


def render(tmp_path, name, text, *args) -> np.ndarray:
    scene, out = tmp_path / f"{name}.toml", tmp_path / f"{name}.png"
    scene.write_text(text)
    assert main(["render", str(scene), "--out", str(out), *args]) == 0
    return np.asarray(Image.open(out))[..., :3].astype(np.int64)


def scene_text(pane: str, intensity: str, animation: str) -> str:
    return (PANE.replace("@PANE@", pane).replace("@INTENSITY@", intensity)
            .replace("@ANIMATION@", animation))


def still(kt, intensity, pane=True):
    return scene_text(PANE_GEOMETRY.replace("KT", repr(kt)) if pane else "", intensity, "")


def test_a_keyed_frame_is_the_still_scene_with_those_values(tmp_path):
    """At t = 0.6 (linear): k_t = 0.3, I_p = (1 - 0.3 * 0.8, 1 - 0.3 * 0.6, 1 - 0.3 * 0.4).
    The keyed frame equals, byte for byte, the still scene written with those numbers; and
    the pane's pixels are the notes' interpolated transparency of the two stills without
    keys, I = (1 - k_t) I_pane + k_t I_behind (each rounded once: within a level)."""
    keyed = render(tmp_path, "keyed", scene_text(PANE_GEOMETRY.replace("KT", "0.0"),
                                                 "[1, 1, 1]", KEYS),
                   "--time", "0.6")
    lit = "[0.76, 0.82, 0.88]"
    assert np.array_equal(keyed, render(tmp_path, "still", still(0.3, lit)))
    opaque = render(tmp_path, "opaque", still(0.0, lit))
    behind = render(tmp_path, "behind", still(0.0, lit, pane=False))
    assert np.abs(keyed - (0.7 * opaque + 0.3 * behind)).max() <= 1.0
    assert np.abs(keyed - opaque).max() > 20                    # and it is not the opaque pane


@pytest.mark.parametrize("key,message", [
    ("material.pane = { kt = 1.5 }", "key[1].material.pane.kt: 1.5 is out of range [0, 1]"),
    ("material.pane = { kt = nan }", "key[1].material.pane.kt: expected a finite number, got nan"),
    ("light.1 = { intensity = [1, -1, 1] }", "key[1].light.1.intensity[2]: -1 is out of range"),
    ("light.1 = { colour = [1, 1, 1] }", "key[1].light.1.colour: unknown key 'colour' (allowed: position, intensity)"),
])
def test_bad_keys_are_one_line(key, message):
    text = still(0.0, "[1, 1, 1]") + f"\n[animation]\nduration = 1\n[[key]]\ntime = 0\n{key}\n"
    with pytest.raises(ReaderError) as error:
        read_scene_file(text, "scene.toml")
    assert message in str(error.value) and "\n" not in str(error.value)
