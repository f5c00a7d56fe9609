"""The real window under Xvfb: an animated scene played, paused and stepped with the keys, and
the switch to the ray tracer (the picture changes, the app keeps running).

The helpers (Xvfb, the app with its log, xdotool, screenshots) are test_window.py's.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time

import numpy as np
import pytest

from tools import need_programs
from test_window import ROOT, XVFB_TOOLS, App, grab, start_xvfb


class AppOn(App):
    """``python -m app view ARGS…`` on the display (App opens the default scene)."""

    def __init__(self, display, workdir, *args):
        import os
        self.display, self.workdir, self.window = display, workdir, None
        self.log_path = workdir / "fvd.log"
        self.env = {**os.environ, "DISPLAY": display, "FVD_LOG": str(self.log_path),
                    "PYTHONPATH": str(ROOT)}
        self.env.pop("WAYLAND_DISPLAY", None)
        self.process = subprocess.Popen([sys.executable, "-m", "app", "view", *args],
                                        cwd=workdir, env=self.env, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _needs_tools():
    need_programs(*XVFB_TOOLS, "import", install="apt-get install xvfb xdotool imagemagick")


@pytest.fixture
def display():
    _needs_tools()
    xvfb, name = start_xvfb()
    yield name
    xvfb.kill()
    xvfb.wait(timeout=10)


@pytest.mark.xvfb
@pytest.mark.slow
def test_animated_scene_plays_pauses_and_steps(display, tmp_path):
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "fountain.toml"), "--size", "200x200")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        first = app.wait_for(r"frame \d+: the keyed view .* t=0\.000", timeout=30)
        mark = len(app.log())
        app.key("space")
        app.wait_for(r"key Space -> play at t=0\.000", timeout=10, after=mark)
        # playing: frames at later moments follow on their own
        app.wait_for(r"frame \d+: .* t=0*[1-9]\d*\.\d+|frame \d+: .* t=0\.(?!000)\d+",
                     timeout=60, after=mark)
        time.sleep(1.0)
        mark = len(app.log())
        app.key("space")
        moment = app.wait_for(r"key Space -> pause at t=(\d+\.\d+)", timeout=10, after=mark)[1]
        paused = float(moment)
        assert paused > 0.0
        # the paused moment is drawn, and no frame of a later moment follows it
        app.wait_for(rf"frame \d+: .* t={re.escape(moment)} ", timeout=60, after=mark)
        time.sleep(1.0)
        after = [float(t) for t in re.findall(r"frame \d+: .* t=(\d+\.\d+)", app.log()[mark:])]
        assert all(t <= paused + 1e-3 for t in after), after
        mark = len(app.log())
        app.key("period")
        step = app.wait_for(r"key \. -> next frame: t = \d+\.\d+ s of 6\.00 s, frame (\d+) of 180",
                            timeout=10, after=mark)
        # one frame on from the paused moment (frame k + 1 of the file is at k / 30 s): at
        # most one frame ahead, give or take the log's rounding of the moment to 1 ms (0.015
        # of a frame; paused on frame k, "1.833" for 55 / 30 s, the step is 1.01 ahead)
        ahead = int(step[1]) - 1 - paused * 30
        assert -0.015 < ahead <= 1.015, ahead
        stepped = (int(step[1]) - 1) / 30
        app.wait_for(rf"frame \d+: .* t={stepped:.3f} ", timeout=30, after=mark)
        # paused, a left click on the picture still advances the view (keyed camera -> view 1)
        mark = len(app.log())
        app.click(100, 100)
        app.wait_for(r"left click at \(100, 100\) -> next the keyed view .* -> view 1 of 2",
                     timeout=10, after=mark)
        app.wait_for(r"frame \d+: view 1 of 2 .* t=", timeout=30, after=mark)
        assert app.process.poll() is None
        picture = grab(app, tmp_path / "fountain.png", "200x200+0+0")
        assert len(np.unique(picture.reshape(-1, 3), axis=0)) > 10
        assert first is not None
    finally:
        app.stop()


@pytest.mark.xvfb
@pytest.mark.slow
def test_switch_to_ray_traced_changes_the_picture(display, tmp_path):
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "whitted.toml"), "--size", "160x120",
                "--renderer", "zbuffer")          # the file asks for the ray tracer
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        app.wait_for(r"frame \d+: .* renderer=zbuffer", timeout=30)
        time.sleep(0.5)
        zbuffer = grab(app, tmp_path / "zbuffer.png", "160x120+0+0")
        mark = len(app.log())
        app.key("r")
        app.wait_for(r"key r -> renderer raytrace", timeout=10, after=mark)
        app.wait_for(r"partial frame: .*\(coarse \(1 ray per \d+ x \d+ pixels\)\)", timeout=120,
                     after=mark)
        app.wait_for(r"frame \d+: .* renderer=raytrace", timeout=180, after=mark)
        time.sleep(0.5)
        traced = grab(app, tmp_path / "traced.png", "160x120+0+0")
        whole = grab(app, tmp_path / "window.png")
        assert app.process.poll() is None, "the app keeps running"
        changed = np.any(zbuffer != traced, axis=2).mean()
        assert changed > 0.05, f"only {changed:.1%} of the picture changed"
        # what is on screen is the ray tracer's frame, pixel for pixel
        rendered = tmp_path / "render.png"
        done = subprocess.run([sys.executable, "-m", "app", "render", "scenes/whitted.toml",
                               "--size", "160x120", "--renderer", "raytrace", "--out",
                               str(rendered)], cwd=ROOT, capture_output=True, text=True,
                              timeout=300)
        assert done.returncode == 0, done.stderr
        from PIL import Image
        assert np.array_equal(traced, np.asarray(Image.open(rendered).convert("RGB")))
        assert whole.shape[1] > 160
    finally:
        app.stop()


@pytest.mark.xvfb
@pytest.mark.slow
def test_bump_demo_clicks_as_j3dpanel(display, tmp_path):
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "bump_demo.toml"), "--size", "120x120")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        time.sleep(0.3)
        rings = grab(app, tmp_path / "map0.png", "120x120+0+0")
        mark = len(app.log())
        app.click(60, 60, button=3)             # any button but the left: the next map
        app.wait_for(r"right click at \(60, 60\) -> the bump demo: Bump: B\(x,y\) = sin\(x\) "
                     r"\+ cos\(y\)", timeout=10, after=mark)
        app.wait_for(r"frame 2: ", timeout=30, after=mark)
        mark = len(app.log())
        app.click(60, 60)                        # left: bump / Phong
        app.wait_for(r"left click at \(60, 60\) -> the bump demo: Phong", timeout=10, after=mark)
        app.wait_for(r"frame 3: ", timeout=30, after=mark)
        time.sleep(0.3)
        phong = grab(app, tmp_path / "phong.png", "120x120+0+0")
        assert "pop-up menu" not in app.log()    # the demo's right button is not the pop-up
        assert app.process.poll() is None
        # the Phong mode is smooth: far fewer distinct blues than the rings
        assert len(np.unique(phong.reshape(-1, 3), axis=0)) < len(
            np.unique(rings.reshape(-1, 3), axis=0))
    finally:
        app.stop()
