"""What a newcomer meets first outside the window: the names of the files the viewer writes,
the exit status of an invalid view, the scenes made for the ray tracer, and scenes framed
whole."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest

from app.naming import SAFE_NAME, frame_name, picture_name, slug, unused
from tests.conftest import ROOT

SCENES = ROOT / "scenes"


def _app(*args, cwd=ROOT, env=None):
    return subprocess.run([sys.executable, "-m", "app", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300,
                          env={**os.environ, "PYTHONPATH": str(ROOT), **(env or {})})


# -- one naming rule ----------------------------------------------------------------------------

@pytest.mark.parametrize("name, expected", [
    ("Whitted: glass and mirror spheres", "whitted-glass-and-mirror-spheres"),
    ("FvDFH house", "fvdfh-house"),
    ("few_triangles", "few-triangles"),
    ("Refraction: a rod in water, seen from far above the pool", "refraction-a-rod-in-water-seen"),
    ("Café «über» / C:\\temp?*", "cafe-uber-c-temp"),
    ("", "scene"),
    ("::: ", "scene"),
    ("a" * 40, "a" * 32),
])
def test_a_scene_name_becomes_safe_words_cut_between_words(name, expected):
    assert slug(name) == expected
    assert len(slug(name)) <= 32


def test_every_kind_of_output_name_follows_one_rule(tmp_path):
    names = [picture_name("Whitted: glass and mirror spheres", 1, "perspective", "phong",
                          "raytrace"),
             picture_name("FvDFH house", 19, "parallel", "wireframe", "zbuffer"),
             frame_name(42)]
    assert names == ["whitted-glass-and-mirror-spheres-view01-perspective-phong-raytrace.png",
                     "fvdfh-house-view19-parallel-wireframe-zbuffer.png", "frame_00042.png"]
    assert all(SAFE_NAME.match(n) for n in names)
    first = tmp_path / names[0]
    first.write_bytes(b"")
    assert unused(first).name == names[0].replace(".png", "-2.png")
    assert SAFE_NAME.match(unused(first).name)


def test_make_run_without_a_display_writes_safe_names(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(PYTHONPATH=str(ROOT), FVD_OUT=str(tmp_path / "out"))
    done = subprocess.run([sys.executable, "-m", "app", "view", str(SCENES / "cube.toml")],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == [f"cube-view{k:02d}-perspective-flat-zbuffer.png" for k in (1, 2, 3)]


def test_render_without_out_names_its_file_by_the_rule(tmp_path):
    done = _app("render", str(SCENES / "torus.toml"), "--shading", "gouraud", "--size", "40x30",
                cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    written = [p.name for p in tmp_path.iterdir()]
    assert written == ["torus-view01-perspective-gouraud-zbuffer.png"]
    assert f"wrote {written[0]} (40x30" in done.stdout


def test_animate_frames_follow_the_rule(tmp_path):
    """The frames folder names each frame by the one rule (app.naming.frame_name)."""
    from app.naming import SAFE_NAME, frame_name
    from app.commands.movie_files import write_frame
    write_frame(tmp_path, 42, b"a frame")
    assert [p.name for p in tmp_path.iterdir()] == [frame_name(42)] == ["frame_00042.png"]
    assert SAFE_NAME.match(frame_name(42))


# -- one exit status for a view that cannot be drawn -------------------------------------------

VIEWS = """0 0 54
0 0 1
0 1 0
-1 17 -1 17
8 6 30
1 -35

0 0 0
0 0 0
0 1 0
-1 1 -1 1
0 0 5
1 -1

0 0 54
0 0 1
0 1 0
-1 17 -1 17
8 6 30
40 -35
"""


@pytest.mark.parametrize("view, why", [(2, "VPN is zero"), (3, "front plane")])
@pytest.mark.parametrize("command", ["render", "matrices"])
def test_a_view_that_cannot_be_drawn_exits_2(tmp_path, view, why, command):
    # view 2 is invalid in the file; view 3 only in perspective (F is behind the eye)
    path = tmp_path / "three.views"
    path.write_text(VIEWS)
    extra = ["--out", str(tmp_path / "x.png")] if command == "render" else []
    done = _app(command, str(path), "--view", str(view), "--projection", "perspective", *extra)
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert why in done.stderr and "Traceback" not in done.stderr
    if view == 3:                                   # drawable in the other projection
        other = _app(command, str(path), "--view", "3", "--projection", "parallel", *extra)
        assert other.returncode == 0, other.stderr


def test_the_help_states_the_exit_rule_once_and_as_it_is():
    text = _app("render", "--help").stdout
    flat = re.sub(r"\s+", " ", text)
    assert flat.count("exits with status 2") == 1 and "exits 1" not in flat
    assert "invalid in the file or in this projection" in flat


# -- scenes made for the ray tracer, and framed whole ------------------------------------------

@pytest.mark.parametrize("name", ["whitted.toml", "house_mirror.toml", "refraction.toml",
                                  "glass_bunny.toml"])
def test_a_scene_made_for_the_ray_tracer_says_so_in_its_file(name):
    text = (SCENES / name).read_text()
    assert re.search(r'^renderer = "raytrace"', text, re.M), name


def test_whitted_opens_in_the_ray_tracer():
    from app.session.state import ViewerState
    from core.scene.formats import load_scene
    assert load_scene(SCENES / "whitted.toml").renderer == "raytrace"
    assert ViewerState.open(SCENES / "whitted.toml", size=(40, 30)).renderer_name == "raytrace"


@pytest.mark.parametrize("name", ["texture_sphere_torus.toml", "texture_env_normal.toml"])
def test_textured_scenes_show_their_objects_whole(name):
    """No object reaches the picture's border: every border pixel is the background."""
    from core import render
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    scene = load_scene(SCENES / name)
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, size=(120, 120)))
    background = np.round(np.asarray(scene.background) * 255).astype(np.uint8)
    image = frame.color
    border = np.concatenate([image[0], image[-1], image[:, 0], image[:, -1]])
    assert np.all(np.abs(border.astype(int) - background).max(axis=1) <= 1), name
    # and the objects fill the picture sensibly: between a quarter and two thirds of it
    covered = np.any(np.abs(image.astype(int) - background) > 1, axis=2).mean()
    assert 0.15 < covered < 0.67, covered
