"""A scene's ``rotate_axis`` and ``shear`` against matrices written out by hand, and its colour
models against Python's ``colorsys`` (an independent implementation)."""

from __future__ import annotations

import colorsys
import math

import numpy as np
import pytest

from core.scene.colours import hls_to_rgb, hsv_to_rgb, to_rgb
from core.scene.formats import ReaderError
from core.scene.formats.scenefile import read_scene_file
from core.transforms import rotate_axis, rotate_z, shear


def _cube(transform: str = "", material: str = "", extra: str = ""):
    text = (extra + '[[geometry]]\ngenerator = "cube"\n'
            + (f"transform = {transform}\n" if transform else "")
            + (f"material = {material}\n" if material else ""))
    return read_scene_file(text, "t.toml")


def test_rotation_about_an_axis_against_hand_matrices():
    # about z by 90 degrees: R_z(90)
    np.testing.assert_allclose(rotate_axis((0, 0, 2), math.pi / 2), rotate_z(math.pi / 2),
                               atol=1e-15)
    # about (1, 1, 1) by 120 degrees: x -> y -> z -> x, the permutation matrix
    turn = np.array([[0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 1]], dtype=float)
    np.testing.assert_allclose(rotate_axis((1, 1, 1), 2 * math.pi / 3), turn, atol=1e-15)
    # about the vertical line through (1, 0, 0) by 180 degrees: (x, y, z) -> (2 - x, y, -z)
    half = np.array([[-1, 0, 0, 2], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, 1]], dtype=float)
    np.testing.assert_allclose(rotate_axis((0, 1, 0), math.pi, (1, 0, 0)), half, atol=1e-15)


def test_shear_against_hand_matrices():
    expected = np.array([[1, 0, 2, 0], [0, 1, 3, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=float)
    np.testing.assert_array_equal(shear(xy=(2, 3)), expected)        # FvDFH's SH_xy(2, 3)
    np.testing.assert_array_equal(shear(yz=(0.5, 0)) @ np.array([4, 1, 1, 1.0]),
                                  [4, 3, 1, 1])                         # y += 0.5 x


def test_scene_transform_keys_move_the_vertices_as_the_matrices_do():
    plain = _cube().meshes[0].positions
    turned = _cube('{ rotate_axis = { axis = [1, 1, 1], angle = 120 } }').meshes[0].positions
    np.testing.assert_allclose(turned, plain[:, [2, 0, 1]], atol=1e-12)
    sheared = _cube('{ shear = { xy = [0.5, 0] }, translate = [1, 0, 0] }').meshes[0].positions
    np.testing.assert_allclose(sheared[:, 0], plain[:, 0] + 0.5 * plain[:, 2] + 1.0, atol=1e-15)
    np.testing.assert_allclose(sheared[:, 1:], plain[:, 1:], atol=1e-15)


@pytest.mark.parametrize("transform, message", [
    ('{ rotate_axis = { axis = [0, 0, 0], angle = 30 } }',
     r"rotate_axis\.axis: the axis is zero: no direction to rotate about"),
    ('{ rotate_axis = { angle = 30 } }', r"rotate_axis: needs 'axis'"),
    ('{ shear = { xx = [1, 2] } }', r"shear\.xx: unknown key 'xx' \(allowed: xy, xz, yz\)"),
])
def test_bad_transforms_get_one_message(transform, message):
    with pytest.raises(ReaderError, match=message):
        _cube(transform)


def test_colour_models_against_colorsys():
    rng = np.random.default_rng(5)
    for h, a, b in rng.uniform(0, 1, (2000, 3)):
        np.testing.assert_allclose(hsv_to_rgb(360 * h, a, b), colorsys.hsv_to_rgb(h, a, b),
                                   atol=1e-12)
        np.testing.assert_allclose(hls_to_rgb(360 * h, a, b), colorsys.hls_to_rgb(h, a, b),
                                   atol=1e-12)
    assert to_rgb("cmy", (0.25, 1, 0)) == (0.75, 0.0, 1.0)
    assert to_rgb("hsv", (120, 1, 1)) == (0.0, 1.0, 0.0)       # pure green


def test_scene_files_take_hsv_and_refuse_what_is_out_of_range():
    scene = _cube(material="{ od = { hsv = [240, 1, 0.5] }, os = { hls = [0, 1, 0] } }",
                  extra='background = { cmy = [1, 1, 0] }\n')
    assert scene.meshes[0].material.od == pytest.approx(colorsys.hsv_to_rgb(2 / 3, 1, 0.5))
    assert scene.meshes[0].material.os == (1.0, 1.0, 1.0)
    assert tuple(scene.background) == (0.0, 0.0, 1.0)
    with pytest.raises(ReaderError, match=r"od\.hsv: the hue must be from 0 to 360 degrees, "
                                          r"not 400\.0"):
        _cube(material="{ od = { hsv = [400, 1, 1] } }")
    with pytest.raises(ReaderError, match=r"od\.hsv: the value must be from 0 to 1, not 2\.0"):
        _cube(material="{ od = { hsv = [40, 1, 2] } }")
    with pytest.raises(ReaderError, match=r"od: a colour is \[r, g, b\] or one of"):
        _cube(material="{ od = { hsb = [40, 1, 1] } }")
