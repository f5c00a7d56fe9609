"""Motion blur (core.animation.frames.Shutter): a square moving at constant speed along a
pixel row against the exact box-filtered coverage; a still scene blurred is the sharp frame."""

from __future__ import annotations

import numpy as np
import pytest

from app.cli import main
from core.animation.frames import Shutter, render_at
from core.animation.keys import animation_of
from core.scene.formats import read_scene_file
from core.settings import RenderSettings

SQUARE = """
name = "moving square"
shading = "flat"
projection = "parallel"
ambient = [1, 1, 1]
background = [0, 0, 0]
size = [64, 8]
[[geometry]]
generator = "plane"
params = { size = 8 }
name = "square"
transform = { rotate = [90, 0, 0] }
material = { ka = 1, kd = 0, ks = 0, od = [1, 1, 1] }
[[light]]
position = [0, 0, 50]
intensity = [0, 0, 0]
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [0, 64, -4, 4]
prp = [32, 0, 10]
front = 5
back = -5
[animation]
duration = 1
fps = 1
interpolation = "linear"
[[key]]
time = 0
object.square = { translate = [X0, 0, 0] }
[[key]]
time = 1
object.square = { translate = [X1, 0, 0] }
"""


def frame(text, t, shutter=None):
    scene = read_scene_file(text, "square.toml")
    anim = animation_of(scene)
    settings = RenderSettings.for_scene(scene, size=(64, 8), shading="flat",
                                        projection="parallel")
    return render_at(anim, t, settings, shutter=shutter).color[..., 0].astype(float) / 255


def coverage(left0: float) -> np.ndarray:
    """The exact box filter over the shutter of a pixel centre's coverage: the square's left
    edge sweeps [left0 + 16, left0 + 48] (64 px/s over the shutter's 0.5 s), so the centre c
    is inside for the part of the sweep in [c − 8, c]."""
    c = np.arange(64) + 0.5
    low, high = left0 + 16.0, left0 + 48.0
    return np.clip(np.minimum(c, high) - np.maximum(c - 8, low), 0, None) / 32.0


def moving(left0: float) -> str:
    return SQUARE.replace("X0", str(4 + left0)).replace("X1", str(4 + left0 + 64))


def test_the_sharp_square_covers_its_eight_pixels():
    row = frame(moving(0.0), 0.5)[4]
    assert np.array_equal(row, (np.abs(np.arange(64) + 0.5 - 36) < 4).astype(float))


def test_64_samples_give_the_exact_box_filtered_coverage_within_1_over_255():
    """The sample times are the midpoints of 64 equal parts of the shutter: the left edge
    at 16.25, 16.75, ... — never on a pixel centre, and every [c − 8, c] holds as many
    samples as its length's share. Samples at the parts' starts, or any other offset,
    would miss by up to 1/64 here."""
    got = frame(moving(0.0), 0.5, Shutter(64))
    assert np.all(got == got[4])                                  # the row, every row
    error = np.abs(got[4] - coverage(0.0))
    assert error.max() <= 1 / 255, error.max()
    assert coverage(0.0).max() == 0.25 and (coverage(0.0) > 0).sum() == 40


def test_any_offset_stays_within_the_midpoint_rules_bound():
    """Off the pixel grid, the 64 samples count each end of a sweep to within one sample:
    |error| <= 1/64 (+ the byte's rounding), and every pixel the square passes is blurred."""
    got = frame(moving(0.3), 0.5, Shutter(64))[4]
    error = np.abs(got - coverage(0.3))
    assert error.max() <= 1 / 64 + 0.5 / 255
    assert error.mean() < 1 / 255


def test_a_still_scene_blurred_is_the_sharp_frame():
    still = SQUARE.split("[animation]")[0] + "[animation]\nduration = 1\nfps = 1\n"
    sharp = frame(still, 0.5)
    assert np.array_equal(frame(still, 0.5, Shutter(16)), sharp)
    assert np.array_equal(frame(still, 0.5, Shutter(7, 0.0, 1.0)), sharp)


def test_bad_shutters_are_refused_with_a_message(tmp_path, capsys):
    with pytest.raises(ValueError, match="the shutter opens and closes within a frame"):
        Shutter(4, 0.5, 0.2)
    path = tmp_path / "square.toml"
    path.write_text(moving(0.0))
    assert main(["animate", str(path), "--out", str(tmp_path / "f"), "--shutter", "0", "1"]) == 2
    assert "--shutter is the motion blur's: give --motion-blur SAMPLES too" in capsys.readouterr().err
    assert main(["animate", str(path), "--out", str(tmp_path / "f"), "--motion-blur", "4",
                 "--shutter", "0.6", "0.1"]) == 2
    assert "--shutter: the shutter opens and closes within a frame" in capsys.readouterr().err
