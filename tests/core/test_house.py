"""The wireframe house: golden images of every view, invalid views, the plan, and the CLI."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from core.settings import RenderSettings
from core.scene.generators import house
from core.paths import ROOT, SCENES_DIR
from core.plan import plan
from core.render import render
from core.scene.model import Scene
from core.scene.formats.viewfile import read_views

VIEWS_TEXT = (SCENES_DIR / "house.views").read_text()


def house_scene() -> Scene:
    views, messages = read_views(VIEWS_TEXT, "house.views")
    return Scene("house", [house()], views, messages, shading="wireframe")


def test_house_geometry():
    mesh = house()
    assert mesh.positions.shape == (10, 3) and mesh.edges.shape == (15, 2)
    assert sorted(set(mesh.positions[:, 2])) == [30.0, 54.0]


@pytest.mark.parametrize("projection", ["perspective", "parallel"])
@pytest.mark.parametrize("k", range(13))
def test_golden_house_views(golden, k, projection):
    scene = house_scene()
    frame = render(scene, scene.views[k],
                   RenderSettings.for_scene(scene, projection=projection, shading="wireframe", size=(500, 500)))
    if frame.message:                     # view 19 of the file (F behind the eye) is not here
        pytest.fail(frame.message)
    golden(f"house_v{k + 1:02d}_{projection}", frame.color)


def test_golden_house_file_view_19_in_parallel(golden):
    """The file's view 19 (F = 40 lies behind the eye at PRP_n = 30) is refused in perspective
    and drawn in parallel projection, where the eye is at infinity: its picture is held too."""
    scene = house_scene()
    view = scene.views[13]
    assert "view 19" in view.label
    frame = render(scene, view, RenderSettings.for_scene(scene, projection="parallel",
                                                         shading="wireframe", size=(500, 500)))
    assert frame.message is None
    golden("house_file_view19_parallel", frame.color)


def test_front_view_edges_land_where_hand_math_puts_them():
    # Notes' example view (F=1, B=-23), perspective: the front wall lies in the view plane, so
    # its corners map straight through the window (-1..17) onto 500 px: x = (u+1)/18*500.
    frame = render(house_scene(), house_scene().views[2],
                   RenderSettings(projection="perspective", shading="wireframe", size=(500, 500)))
    lit = frame.color[:, :, 0] > 0
    for u, v in [(0, 0), (16, 0), (16, 10), (8, 16), (0, 10)]:
        col = int((u + 1) / 18 * 500)
        row = 499 - int((v + 1) / 18 * 500)
        assert lit[row - 1:row + 2, col - 1:col + 2].any(), (u, v)


def test_empty_picture_when_house_is_behind_the_eye():
    frame = render(house_scene(), house_scene().views[11],
                   RenderSettings(projection="perspective", shading="wireframe", size=(200, 200)))
    assert frame.message is None and not frame.color.any()


def test_invalid_views_in_the_file_give_messages_and_the_others_render():
    scene = house_scene()
    assert len(scene.view_messages) == 6 and len(scene.views) == 14
    lit = [render(scene, scene.views[k],
                  RenderSettings.for_scene(scene, projection="parallel", shading="wireframe", size=(100, 100))).color.any() for k in range(14)]
    assert sum(lit) >= 12


def test_view_invalid_for_perspective_only():
    scene = house_scene()
    k = 13                                      # the file's view 19: F = 40 > PRP_n = 30
    assert "view 19" in scene.views[k].label
    bad = render(scene, scene.views[k],
                 RenderSettings.for_scene(scene, projection="perspective", shading="wireframe", size=(100, 100)))
    assert "not in front of the eye" in bad.message and not bad.color.any()
    good = render(scene, scene.views[k],
                  RenderSettings.for_scene(scene, projection="parallel", shading="wireframe", size=(100, 100)))
    assert good.message is None and good.color.any()


def test_zero_sized_framebuffer_is_a_message_not_a_crash():
    frame = render(house_scene(), house_scene().views[0],
                   RenderSettings(projection="perspective", shading="wireframe", size=(0, 0)))
    assert frame.color.shape == (0, 0, 3) and "0 x 0" in frame.message


def test_wireframe_plan_has_no_depth_buffer():
    scene = house_scene()
    stages = {s.name: s for s in plan(scene, "perspective", "wireframe")}
    assert not stages["depth buffer"].runs and not stages["z-buffer scan conversion"].runs
    assert stages["clip lines"].runs and stages["scan-convert lines"].runs
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, projection="perspective", shading="wireframe", size=(50, 50)))
    assert frame.stats["allocated"] == ["color"]


def _app(*args, stdin=None):
    return subprocess.run([sys.executable, "-m", "app", *args], cwd=ROOT, input=stdin,
                          capture_output=True, text=True, timeout=120)


def test_matrices_command_reproduces_the_worked_example():
    worked = "0 0 54\n0 0 1\n0 1 0\n-1 17 -1 17\n8 6 30\n10 -50\n"
    result = _app("matrices", "-", "--projection", "perspective", stdin=worked)
    assert result.returncode == 0, result.stderr
    m = json.loads(result.stdout)
    assert m["T_vrp"][2][3] == -54 and m["R"] == np.eye(4).tolist()
    assert m["T_prp"] == [[1, 0, 0, -8], [0, 1, 0, -6], [0, 0, 1, -30], [0, 0, 0, 1]]
    assert m["SH_par"][1][2] == pytest.approx(1 / 15, abs=1e-15)
    assert np.array_equal(np.array(m["S_per"]), np.diag([1 / 24, 1 / 24, 1 / 80, 1]))
    assert m["z_min"] == -0.25
    for key in ("N_per", "M_vv3dv"):
        assert np.array(m[key]).shape == (4, 4)
    parallel = json.loads(_app("matrices", "-", "--projection", "parallel", stdin=worked).stdout)
    assert set(parallel) >= {"T_vrp", "R", "SH_par", "T_par", "S_par", "N_par", "M_vv3dv"}
    assert np.array(parallel["S_par"]).diagonal().tolist() == [2 / 18, 2 / 18, 1 / 60, 1]


def test_render_command_reads_views_from_stdin(tmp_path):
    text = VIEWS_TEXT
    out = tmp_path / "v2.png"
    result = _app("render", "-", "--view", "2", "--projection", "parallel", "--size", "333x217",
                  "--out", str(out), stdin=text)
    assert result.returncode == 0, result.stderr
    assert "view 14 (line 111): VPN is zero" in result.stderr
    from PIL import Image
    image = np.asarray(Image.open(out))
    assert image.shape == (217, 333, 3) and image.any()


def test_render_command_rejects_bad_view_number(tmp_path):
    result = _app("render", "-", "--view", "99", "--out", str(tmp_path / "x.png"), stdin=VIEWS_TEXT)
    assert result.returncode == 2 and "the file has 20 views (1 to 20)" in result.stderr
