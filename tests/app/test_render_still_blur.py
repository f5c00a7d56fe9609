"""``render --time T --motion-blur N``: one motion-blurred still, the accumulation buffer's
box filter over the shutter (held to the mean of the sharp frames at the sample times); a
scene that does not move blurs to its sharp frame, byte for byte; and a scene of a volume
alone renders."""

from __future__ import annotations

import numpy as np
from PIL import Image

from app.cli import main

WHEEL = "scenes/fast_wheel.toml"
SIZE = "96x96"


def picture(tmp_path, name, *args) -> np.ndarray:
    out = tmp_path / f"{name}.png"
    assert main(["render", *args, "--size", SIZE, "--out", str(out)]) == 0
    return np.asarray(Image.open(out)).astype(np.int64)


def test_a_blurred_still_is_the_mean_of_the_sharp_frames_over_the_shutter(tmp_path):
    """8 samples over the default shutter [-1/4, 1/4] of a frame at 30 fps: the sharp frames
    at t + (-0.25 + (i + 0.5) / 16) / 30, i = 0 .. 7, averaged. Each sharp PNG is rounded
    once, the blur's mean once: they agree within one level."""
    t = 0.1
    blurred = picture(tmp_path, "blurred", WHEEL, "--time", str(t), "--motion-blur", "8")
    sharp = picture(tmp_path, "sharp", WHEEL, "--time", str(t), "--motion-blur", "1")
    assert np.abs(blurred - sharp).max() > 60               # the spokes smear
    times = [t + (-0.25 + (i + 0.5) / 16) / 30 for i in range(8)]
    frames = [picture(tmp_path, f"at{i}", WHEEL, "--time", repr(s), "--motion-blur", "1")
              for i, s in enumerate(times)]
    assert np.abs(np.mean(frames, axis=0) - blurred).max() <= 1.0


STILL = """
name = "still"
size = [64, 64]
[[geometry]]
generator = "torus"
name = "ring"
material = { od = [0.8, 0.4, 0.2] }
[animation]
duration = 2
[[key]]
time = 0
object.ring = { translate = [0, 0, 0] }
[[key]]
time = 2
object.ring = { translate = [0, 0, 0] }
"""


def test_a_scene_that_does_not_move_blurs_to_its_sharp_frame(tmp_path):
    scene = tmp_path / "still.toml"
    scene.write_text(STILL)
    blurred = picture(tmp_path, "blurred", str(scene), "--time", "0.7", "--motion-blur", "16")
    sharp = picture(tmp_path, "sharp", str(scene), "--time", "0.7")
    assert np.array_equal(blurred, sharp) and len(np.unique(sharp)) > 10


def test_blur_options_without_what_they_need_are_one_line(tmp_path, capsys):
    out = str(tmp_path / "x.png")
    assert main(["render", WHEEL, "--motion-blur", "4", "--out", out]) == 2
    assert main(["render", WHEEL, "--time", "0", "--shutter", "0", "0.5", "--out", out]) == 2
    assert main(["render", WHEEL, "--time", "0", "--motion-blur", "0", "--out", out]) == 2
    said = capsys.readouterr().err.strip().splitlines()
    assert said == [
        "error: --motion-blur blurs an animated scene's frame at a moment: give --time SECONDS too",
        "error: --shutter is the motion blur's: give --motion-blur SAMPLES too",
        "error: motion blur takes 1 to 1024 samples, not 0"]
    assert not (tmp_path / "x.png").exists()


def test_a_volume_alone_renders(tmp_path):
    picture_ = picture(tmp_path, "volume", "scenes/volume_alone.toml", "--view", "2")
    background = np.array([0.05, 0.05, 0.08]) * 255
    lit = np.abs(picture_[..., :3] - background).max(axis=2) > 20
    assert 0.1 < lit.mean() < 0.8            # the head, framed with a margin of background
    assert not lit[0].any() and not lit[-1].any() and not lit[:, 0].any() and not lit[:, -1].any()
