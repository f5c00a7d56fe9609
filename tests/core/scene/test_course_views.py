"""Views numbered by their place in the file; `python -m app < grade.data`; files of only
invalid views; the scene keys and options of the course (keep_aspect, rasterizer, --course-tri).
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

from app.session.state import ViewerState
from core.paths import SCENES_DIR
from core.render import render
from core.scene import view_numbers
from core.scene.formats import load_scene
from core.settings import RenderSettings

from tests.conftest import ROOT

# Five views: valid, invalid (VUP parallel to VPN), valid, invalid (not a number), valid.
VIEW_A = "0 0 0\n0 0 1\n0 1 0\n-50 50 -50 50\n8 6 84\n60 25\n"
VIEW_B = "0 0 54\n0 0 1\n0 1 0\n-1 17 -1 17\n8 6 30\n1 -35\n"
VIEW_C = "16 0 54\n0 0 1\n0 1 0\n-20 20 -5 35\n20 25 20\n1 -35\n"
MIXED = (VIEW_A + "0 0 0\n0 0 1\n0 0 5\n-1 1 -1 1\n0 0 5\n1 -1\n" + VIEW_B
         + "0 0 0\n0 0 1\n0 1 0\n-1 1 -1 x\n0 0 5\n1 -1\n" + VIEW_C)


def _app(*args, stdin=None, env=None, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "app", *args], cwd=cwd, input=stdin,
                          capture_output=True, text=True, timeout=180, env=env)


def _png(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def test_file_positions_map_to_views_and_messages(tmp_path):
    path = tmp_path / "mixed.views"
    path.write_text(MIXED)
    scene = load_scene(path)
    assert len(scene.views) == 3 and view_numbers.total(scene) == 5
    assert [view_numbers.file_number(scene, i) for i in range(3)] == [1, 3, 5]
    assert view_numbers.index_of(scene, 3) == 1 and view_numbers.index_of(scene, 5) == 2
    with pytest.raises(view_numbers.ViewNumberError, match="view 2 .*VUP is parallel to VPN"):
        view_numbers.index_of(scene, 2)
    with pytest.raises(view_numbers.ViewNumberError, match="the file has 5 views"):
        view_numbers.index_of(scene, 6)
    assert view_numbers.label(scene, 1) == "view 3 of 5 (2 invalid)"


def test_render_view_k_is_the_kth_of_the_file_from_stdin(tmp_path):
    # --view 3 of the mixed file is VIEW_B: the same picture as VIEW_B alone
    out, alone = tmp_path / "k3.png", tmp_path / "alone.png"
    done = _app("render", "-", "--view", "3", "--out", str(out), stdin=MIXED)
    assert done.returncode == 0, done.stderr
    assert "view 3 of 5 (2 invalid)" in done.stdout
    assert _app("render", "-", "--view", "1", "--out", str(alone), stdin=VIEW_B).returncode == 0
    assert np.array_equal(_png(out), _png(alone)) and _png(out).any()
    # an invalid view: its message, and a non-zero exit; so for one past the end
    bad = _app("render", "-", "--view", "4", "--out", str(tmp_path / "x.png"), stdin=MIXED)
    assert bad.returncode != 0 and not (tmp_path / "x.png").exists()
    assert "error: --view 4 is invalid: <stdin>: view 4 (line 19): line 22: v_max: 'x' is not a number" in bad.stderr
    past = _app("render", "-", "--view", "6", "--out", str(tmp_path / "y.png"), stdin=MIXED)
    assert past.returncode != 0 and "the file has 5 views (1 to 5)" in past.stderr


def test_house_view_numbers_are_file_positions(tmp_path):
    # house.views: view 19 (F behind the eye) is valid in parallel; 14 is invalid (VPN zero)
    ok = _app("render", "scenes/house.toml", "--view", "19", "--projection", "parallel",
              "--out", str(tmp_path / "v19.png"))
    assert ok.returncode == 0, ok.stderr
    assert "view 19 of 20 (6 invalid)" in ok.stdout
    bad = _app("render", "scenes/house.toml", "--view", "14", "--out", str(tmp_path / "v14.png"))
    assert bad.returncode != 0 and "--view 14 is invalid" in bad.stderr and "VPN is zero" in bad.stderr


def test_bare_app_reads_views_from_stdin_without_a_display(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(PYTHONPATH=str(ROOT), FVD_OUT=str(tmp_path / "out"))
    with open(tmp_path / "grade.data", "w") as f:
        f.write(MIXED)
    with open(tmp_path / "grade.data") as stdin:           # `python -m app < grade.data`
        done = subprocess.run([sys.executable, "-m", "app"], cwd=tmp_path, env=env, stdin=stdin,
                              capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in (tmp_path / "out").glob("*.png"))
    assert names == [f"house-view{k:02d}-perspective-wireframe-zbuffer.png" for k in (1, 3, 5)]
    assert "<stdin>: view 2 (line 7): VUP is parallel to VPN" in done.stderr


def test_a_file_of_only_invalid_views_keeps_the_current_scene(tmp_path):
    bad = tmp_path / "bad.views"
    bad.write_text("0 0 0\n0 0 0\n0 1 0\n-1 1 -1 1\n0 0 5\n1 -1\n"
                   "0 0 0\n0 0 1\n0 0 1\n-1 1 -1 1\n0 0 5\n1 -1\n")
    state = ViewerState.open(SCENES_DIR / "house.toml", size=(120, 90))
    state.views.next_view()
    assert state.frames.update()
    scene, frame = state.scene, state.frame
    assert state.open_scene(str(bad)) is False
    assert state.scene is scene and state.frame is frame and state.view_index == 1
    assert "none of its 2 views is valid" in state.messages.notices[0]
    assert any("VPN is zero" in m for m in state.messages.notices)
    assert any("VUP is parallel to VPN" in m for m in state.messages.notices)


def test_invalid_views_are_kept_apart_from_the_other_messages():
    state = ViewerState.open(SCENES_DIR / "house.toml", size=(120, 90))
    assert len(state.messages.invalid) == 6 and state.messages.notices == []
    assert state.views.label == "view 1 of 20 (6 invalid)"


def test_scene_keys_keep_aspect_and_rasterizer(tmp_path):
    scene_file = tmp_path / "s.toml"
    scene_file.write_text('keep_aspect = true\nrasterizer = "scanline"\nshading = "gouraud"\n'
                          '[[geometry]]\ngenerator = "uv_sphere"\n')
    scene = load_scene(scene_file)
    settings = RenderSettings.for_scene(scene)
    assert settings.keep_aspect is True and settings.rasterizer == "scanline"
    state = ViewerState(scene=scene, scene_source=str(scene_file), size=(64, 48))
    assert state.keep_aspect is True and state.rasterizer == "scanline"
    scene_file.write_text('rasterizer = "raytrace"\n[[geometry]]\ngenerator = "uv_sphere"\n')
    from core.scene.formats import ReaderError
    with pytest.raises(ReaderError, match="rasterizer.*not one of edge, scanline"):
        load_scene(scene_file)


def test_stretched_render_puts_the_house_corners_at_the_hand_pixels():
    # The notes' view with a 2:1 window (-1 17 -1 8) on 500 x 500: the front wall is on the
    # view plane, so corner (u, v) lands at x = (u + 1) / 18 * 500, y = (v + 1) / 9 * 500.
    from core.camera.view import View
    scene = load_scene(SCENES_DIR / "house.toml")
    view = View(vrp=(0, 0, 54), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 17, -1, 8),
                prp=(8, 6, 30), front=1, back=-23)
    for keep, y0, sy in ((False, 0.0, 500 / 9), (True, 125.0, 250 / 9)):
        settings = RenderSettings.for_scene(scene, size=(500, 500), keep_aspect=keep)
        lit = render(scene, view, settings).color[:, :, 0] > 0
        for u, v in [(0, 0), (16, 0)]:
            x, y = (u + 1) / 18 * 500, y0 + (v + 1) * sy
            col, row = int(np.floor(x)), 499 - int(np.floor(y))
            assert lit[row, col], (keep, u, v)
        rows = np.flatnonzero(lit.any(axis=1))
        if keep:        # letterboxed: device rows 125-375 only (image rows 124-374: the roof,
            # clipped at the window's top edge y = 375, lands in the pixel containing it)
            assert rows.min() >= 124 and rows.max() <= 374
        else:                              # stretched: the roof (v = 16) is above the window
            assert rows.min() == 0


def test_course_tri_skips_what_the_startup_code_skips(tmp_path):
    # Two triangles at z = -1, seen from (0, 0, 10): one wound towards the viewpoint
    # (N = +z, viewpoint . N > 0: drawn), one away (N = -z: skipped by the startup code; our
    # own rule draws both, the mesh not being closed)
    from core.scene.course_tri import course_tri_scene, startup_code_keeps
    text = ("0 0 10\n-1 1 0\n0.004 0 0\n0 -0.004 0\n2\n"
            "-0.9 -0.9 -1 -0.1 -0.9 -1 -0.1 -0.1 -1\n"
            "0.1 -0.9 -1 0.9 -0.1 -1 0.9 -0.9 -1\n")
    path = tmp_path / "two.tri"
    path.write_text(text)
    scene = load_scene(path)
    kept = course_tri_scene(scene, scene.views[0])
    assert scene.triangle_count == 2 and kept.triangle_count == 1
    assert startup_code_keeps(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]), np.array([[0, 1, 2]]),
                              np.array([0, 0, -1.0])).tolist() == [False]
    ours, course = tmp_path / "ours.png", tmp_path / "course.png"
    assert _app("render", str(path), "--out", str(ours)).returncode == 0
    assert _app("render", str(path), "--course-tri", "--out", str(course)).returncode == 0
    a, b = _png(ours), _png(course)
    left, right = (slice(300, 450), slice(50, 200)), (slice(300, 450), slice(300, 450))
    assert np.array_equal(a[left], b[left])                 # the triangle facing the viewpoint
    assert (a[right] != a[0, 0]).any() and (b[right] == b[0, 0]).all()   # the other is gone
