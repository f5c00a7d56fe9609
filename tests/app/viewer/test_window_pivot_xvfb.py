"""The pivot under the cursor, the turntable and the headlight in the real window under Xvfb.

A 1 x 1 square on the floor (y = 0) seen from straight above, its plane the view plane: the
eye at (0, 2, 0), u = +x, v = -z, the window +-1 over 400 x 400 pixels. Pixel (c, r) then
shows the floor point (-1 + (c + 1/2) / 200, 0, -(1 - (r + 1/2) / 200)). The scene's one light
grazes the floor (N . L = 0) and there is no ambient light, so the square is black until the
headlight, at the eye straight above its centre, lights it white (flat: N . L = 1).
"""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

from tools import need_programs
from tests.app.viewer.test_window import XVFB_TOOLS, grab, start_xvfb
from tests.app.viewer.test_window_hands import drag
from tests.app.viewer.test_window_systems import AppOn

SCENE = """
name = "Floor"
shading = "flat"
ambient = [0, 0, 0]
background = [0, 0, 0.5]

[[geometry]]
generator = "plane"
params = { size = 1.0 }
material = { ka = 0.0, kd = 1.0, ks = 0.0, od = [1, 1, 1] }

[[view]]
name = "from above"
vrp = [0, 0, 0]
vpn = [0, 1, 0]
vup = [0, 0, -1]
window = [-1, 1, -1, 1]
prp = [0, 0, 2]
front = 1
back = -1

[[light]]
direction = [1, 0, 0]
"""


def _numbers(text: str) -> np.ndarray:
    return np.array([float(c) for c in text.split(",")])


@pytest.mark.xvfb
@pytest.mark.slow
def test_a_drag_turns_about_the_point_under_the_press_and_the_headlight_follows(tmp_path):
    need_programs(*XVFB_TOOLS, "import", install="apt-get install xvfb xdotool imagemagick")
    scene = tmp_path / "floor.toml"
    scene.write_text(SCENE)
    xvfb, display = start_xvfb()
    app = AppOn(display, tmp_path, str(scene), "--size", "400x400")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        time.sleep(0.4)
        dark = grab(app, tmp_path / "dark.png", "400x400+0+0")
        assert (dark[200, 200] == 0).all()              # the grazing light: black

        mark = len(app.log())
        app.key("l")
        app.wait_for(r"key l -> headlight True", timeout=10, after=mark)
        app.wait_for(r"frame \d+: view", timeout=30, after=mark)
        time.sleep(0.4)
        lit = grab(app, tmp_path / "lit.png", "400x400+0+0")
        assert (lit[200, 200] == 255).all() and (lit[20, 20] == dark[20, 20]).all()

        # A press on the square at (150, 250): the floor point (-0.2475, 0, 0.2525)
        mark = len(app.log())
        drag(app, [(150, 250), (170, 250), (200, 250), (250, 250)])
        line = app.wait_for(r"drag arcball orbit about the point under the cursor \(([^)]*)\)",
                            timeout=10, after=mark)
        assert np.allclose(_numbers(line[1]), (-0.2475, 0.0, 0.2525), atol=1e-4)
        # the picture that answers the drag says how long after the input it reached the
        # screen (app.viewer.latency): more than nothing, less than the test's own wait
        shown = app.wait_for(r"on screen: request \d+, the window's own ([\d.]+) ms "
                             r"\(CPU [\d.]+ ms, swap [\d.]+ ms\), (\d+) ms after the input",
                             timeout=30, after=mark)
        assert 0.0 < float(shown[1]) and 0 < int(shown[2]) < 30_000

        # A press on the background: the scene's centre, the origin
        app.key("Return")
        mark = len(app.log())
        drag(app, [(20, 20), (40, 20), (60, 20), (80, 20)])
        line = app.wait_for(r"drag arcball orbit about the scene's centre \(([^)]*)\)",
                            timeout=10, after=mark)
        assert np.allclose(_numbers(line[1]), 0.0, atol=1e-12)

        # The turntable: 100 px right over a 400 px picture turns the scene by pi/4 about the
        # up axis (VUP, -z): VPN (0, 1, 0) turned by -pi/4 about -z is (-1, 1, 0) / sqrt 2
        app.key("Return")
        mark = len(app.log())
        app.key("y")
        app.wait_for(r"key y -> rotation turntable", timeout=10, after=mark)
        drag(app, [(200, 200), (220, 200), (260, 200), (300, 200)])
        line = app.wait_for(r"drag turntable orbit about .* VPN \(([^)]*)\) VUP \(([^)]*)\)",
                            timeout=10, after=mark)
        assert np.allclose(_numbers(line[1]), (-0.5 ** 0.5, 0.5 ** 0.5, 0.0), atol=1e-12)
        assert np.allclose(_numbers(line[2]), (0.0, 0.0, -1.0), atol=0)
        # the headlight came along: the eye now looks at 45 degrees, flat N . L = cos 45
        app.wait_for(r"frame \d+: view .*camera=moved", timeout=30, after=mark)
        time.sleep(0.6)
        turned = grab(app, tmp_path / "turned.png", "400x400+0+0")
        assert abs(int(turned[200, 200, 0]) - 255 * 0.5 ** 0.5) <= 1
        assert not re.search(r"Traceback", app.log())
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)
