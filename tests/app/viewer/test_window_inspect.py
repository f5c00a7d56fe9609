"""The window's inspector tools under Xvfb: inspect mode and a click show the
pixel's record (the CLI's ``inspect`` of the same pixel), buffer views cycle in place of the
picture, and the comparison with OpenGL shows its heat map."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np
import pytest

from tools import need_programs

from tests.app.viewer.test_window import ROOT, App, grab, start_xvfb

SIZE = (240, 200)


class SceneApp(App):
    """``python -m app SCENE --size WxH`` on an X display."""

    def __init__(self, display, workdir, *args):
        self.display, self.workdir = display, workdir
        self.log_path = workdir / "fvd.log"
        self.env = {**os.environ, "DISPLAY": display, "FVD_LOG": str(self.log_path),
                    "PYTHONPATH": str(ROOT)}
        self.env.pop("WAYLAND_DISPLAY", None)
        self.process = subprocess.Popen([sys.executable, "-m", "app", *args], cwd=ROOT,
                                        env=self.env, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        self.window = None


def _cli_record(x, y) -> dict:
    done = subprocess.run([sys.executable, "-m", "app", "inspect", "scenes/cube.toml",
                           "--shading", "phong", "--size", f"{SIZE[0]}x{SIZE[1]}",
                           "--pixel", f"{x},{y}", "--json"], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.xvfb
@pytest.mark.slow
def test_inspect_mode_buffer_views_and_opengl_compare_under_xvfb(tmp_path):
    need_programs("Xvfb", "xdotool", "import", install="apt-get install xvfb xdotool imagemagick")
    xvfb, display = start_xvfb()
    app = SceneApp(display, tmp_path, "scenes/cube.toml", "--size", f"{SIZE[0]}x{SIZE[1]}")
    try:
        app.wait_for(r"first frame shown", timeout=90)
        app.find_window()
        mark = len(app.log())
        app.key("3")                                          # Phong
        app.wait_for(r"frame \d+: .*shading=phong", timeout=30, after=mark)
        time.sleep(0.3)
        picture = grab(app, tmp_path / "picture.png", f"{SIZE[0]}x{SIZE[1]}+0+0")

        # Inspect mode: a click shows the record and does not change the view.
        mark = len(app.log())
        app.key("i")
        app.wait_for(r"key i -> inspect mode on", timeout=10, after=mark)
        x, y = 120, 100
        app.click(x, y)
        app.wait_for(rf"inspect pixel \({x}, {y}\)", timeout=60, after=mark)
        line = app.wait_for(r"inspect record: (.*)$", timeout=10, after=mark)[1]
        shown = json.loads(line)
        assert shown == _cli_record(x, y)                      # the CLI's record, exactly
        assert shown["layer"] == "triangle"
        assert shown["color"] == picture[y, x].tolist()        # the pixel on screen
        assert "view 2" not in app.log()[mark:]                # the click did not step
        time.sleep(0.5)
        whole = grab(app, tmp_path / "panel.png")
        panel = whole[:, SIZE[0]:]
        assert len(np.unique(panel.reshape(-1, 3), axis=0)) > 5

        # Buffer views cycle in place of the picture, then back to the picture.
        seen = []
        for _ in range(7):
            mark = len(app.log())
            app.key("v")
            seen.append(app.wait_for(r"key v -> buffer view: ([\w-]+)", timeout=60,
                                     after=mark)[1])
            if seen[-1] == "picture":
                break
        assert seen[:4] == ["depth", "normal", "triangle", "barycentrics"], seen
        assert seen[-1] == "picture", seen

        mark = len(app.log())
        app.key("v")                                          # depth, on screen
        app.wait_for(r"key v -> buffer view: depth", timeout=60, after=mark)
        time.sleep(0.5)
        depth = grab(app, tmp_path / "depth.png", f"{SIZE[0]}x{SIZE[1]}+0+0")
        assert not np.array_equal(depth, picture)
        grey = depth[(depth != 0).any(axis=2)]
        assert len(grey) and (grey[:, 0] == grey[:, 1]).all() and (grey[:, 1] == grey[:, 2]).all()

        # Compare with OpenGL: the heat map replaces the picture; h flips back.
        mark = len(app.log())
        app.key("h")
        verdict = app.wait_for(r"key h -> compare with OpenGL: (.*)$", timeout=60, after=mark)[1]
        assert "within 1/255" in verdict
        time.sleep(0.5)
        heat = grab(app, tmp_path / "heat.png", f"{SIZE[0]}x{SIZE[1]}+0+0")
        assert not np.array_equal(heat, depth) and not np.array_equal(heat, picture)
        mark = len(app.log())
        app.key("h")
        app.wait_for(r"key h -> showing the picture", timeout=10, after=mark)
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)


def test_the_tools_follow_the_frame_without_a_window():
    """InspectorTools on a ViewerState: a click's record is the CLI's; a buffer view follows
    a new frame, and falls back to the picture when the new frame has no such buffer."""
    from app.viewer.inspector_tools import PICTURE, InspectorTools
    from app.session.state import ViewerState
    from core.paths import SCENES_DIR

    state = ViewerState.open(SCENES_DIR / "cube.toml", size=SIZE)
    state.choices.set_shading("phong")
    state.frames.update()
    tools = InspectorTools(state)
    tools.toggle_inspect("test")
    tools.inspect(120, 100, "test")
    tools.settle()                                  # drawn off the UI thread
    assert tools.record["color"] == state.frame.color[100, 120].tolist()
    assert tools.lines[0].startswith("pixel (120, 100)  zbuffer  colour")
    tools.next_buffer("test")
    tools.settle()
    assert tools.buffer == "depth" and tools.overlay.shape == (SIZE[1], SIZE[0], 4)
    assert tools.picture(state.frame) is tools.overlay
    state.choices.set_shading("wireframe")                  # no triangles filled: no depth buffer
    state.frames.update()
    tools.frame_changed(state.frame, state.frame_seconds)
    tools.settle()
    assert tools.buffer == PICTURE and tools.picture(state.frame) is state.frame.rgbx
    assert list(tools.frame_ms) == [pytest.approx(state.frame_seconds * 1e3)]


def test_another_scene_clears_the_last_ones_record_comparison_and_buffer_view():
    from app.viewer.inspector_tools import PICTURE, InspectorTools
    from app.session.state import ViewerState
    from core.paths import SCENES_DIR
    state = ViewerState.open(SCENES_DIR / "cube.toml", size=SIZE)
    state.choices.set_shading("phong")
    state.frames.update()
    tools = InspectorTools(state)
    tools.inspect(120, 100, "test")
    tools.settle()
    tools.choose_buffer("depth", "test")
    tools.settle()
    assert tools.lines and tools.buffer == "depth"
    tools.choose_buffer("normal", "test")          # still drawing when the scene changes
    assert state.open_scene(SCENES_DIR / "sphere.toml")
    tools.scene_changed()
    tools.settle()
    assert tools.lines == [] and tools.record is None and tools.buffer == PICTURE
    assert tools.overlay is None and tools.verdict == "" and not tools.frame_ms
