"""A small scene's picture is scaled up for the window (its aspect kept) so that the panel
beside it fits; a size given on the command line is kept as it is."""

from __future__ import annotations

from app.viewer.launch import MIN_PICTURE_HEIGHT, enlarged


def test_small_scenes_are_scaled_up_to_the_least_height_keeping_their_aspect():
    assert MIN_PICTURE_HEIGHT == 480
    assert enlarged((320, 240)) == (640, 480)          # robot_arm.toml
    assert enlarged((596, 256)) == (1118, 480)         # volume_mip.toml: 596 x 480 / 256
    assert enlarged((500, 500)) == (500, 500)
    assert enlarged((64, 480)) == (64, 480)
    assert enlarged((1, 1)) == (480, 480)
