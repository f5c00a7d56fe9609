"""A scene of a [[volume]] alone (no [[geometry]], view or light), as a CT scan arrives: framed
and lit from the volume's sample grid."""

from __future__ import annotations

import math

import pytest

import core.systems  # noqa: F401  (the systems' scene keys: [[volume]])
from core.scene.formats import ReaderError, read_scene_file


def test_the_auto_views_frame_the_volumes_grid():
    """The phantom's 80 samples a side span [-1, 1]^3: the bounding sphere of the grid's
    corners has centre 0 and radius sqrt(3), so VRP = 0, the window is +-1.15 sqrt(3), the
    eye 3 sqrt(3) away and F, B = +-1.05 sqrt(3) (the framing of any mesh file)."""
    scene = read_scene_file(open("scenes/volume_alone.toml").read(), "scenes/volume_alone.toml")
    assert scene.meshes == [] and len(scene.views) == 3 and len(scene.lights) == 2
    r = math.sqrt(3)
    for view in scene.views:
        assert view.vrp == pytest.approx((0, 0, 0), abs=1e-12)
        assert view.window == pytest.approx((-1.15 * r, 1.15 * r, -1.15 * r, 1.15 * r), rel=1e-12)
        assert view.prp == pytest.approx((0, 0, 3 * r), rel=1e-12)
        assert (view.front, view.back) == pytest.approx((1.05 * r, -1.05 * r), rel=1e-12)
    assert scene.lights[0].position == pytest.approx((2 * r, 3 * r, 4 * r), rel=1e-12)


def test_a_volume_moved_by_its_transform_is_framed_where_it_is():
    text = """
[[volume]]
generator = "sphere"
params = { size = 33 }
spacing = [0.25, 0.25, 0.25]
transform = { translate = [10, 0, 0] }
mode = "mip"
"""
    scene = read_scene_file(text, "v.toml")
    # 33 samples 0.25 apart: 8 units a side, centred on its translate
    assert scene.views[0].vrp == pytest.approx((10, 0, 0), abs=1e-12)
    assert scene.views[0].window[1] == pytest.approx(1.15 * 4 * math.sqrt(3), rel=1e-12)


def test_a_scene_of_nothing_says_what_it_needs():
    with pytest.raises(ReaderError) as error:
        read_scene_file('name = "x"\n', "x.toml")
    assert str(error.value) == "x.toml: a scene needs at least one [[geometry]] or [[volume]] table"
