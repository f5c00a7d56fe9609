"""A storm of input on the real window under Xvfb: a drag with a shading key pressed eight
times a second and the window resized in the middle of it.

Every picture swapped onto the screen says which request it answers ("on screen: request N",
app/viewer/loop.py): the numbers never go down (no older camera or shading after a newer one
is ever shown), every key is acted on, the last picture shows the last shading asked for, and
the window keeps running. How fast each is answered is measured by ``python -m app bench
--window`` (the keys' row), not asserted here.
"""

from __future__ import annotations

import re
import time

import pytest

from tests.app.viewer.test_window import XVFB_TOOLS, start_xvfb
from tests.app.viewer.test_window_systems import AppOn
from tests.conftest import ROOT
from tools import need_programs

KEYS = ["1", "2", "3"] * 6              # flat, Gouraud, Phong: 18 presses at 8 a second


@pytest.mark.xvfb
@pytest.mark.slow
def test_a_drag_with_shading_keys_and_a_resize_never_shows_an_older_picture(tmp_path):
    need_programs(*XVFB_TOOLS, install="apt-get install xvfb xdotool")
    xvfb, display = start_xvfb()
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "torus.toml"), "--size", "400x400")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        time.sleep(0.3)
        mark = len(app.log())
        app.xdotool("mousemove", "--window", app.window, "150", "200")
        time.sleep(0.15)
        app.xdotool("mousedown", "1")
        for i, key in enumerate(KEYS):
            app.xdotool("mousemove", "--window", app.window, str(150 + 6 * i), "200")
            app.key(key)
            if i == len(KEYS) // 2:             # resized in the middle of the drag
                app.xdotool("windowsize", app.window, "900", "460")
            time.sleep(1 / 8)
        app.xdotool("mouseup", "1")
        app.wait_for(r"frame \d+: .*phong", timeout=30, after=mark)
        time.sleep(1.5)                         # the last pictures land

        log = app.log()[mark:]
        requests = [int(n) for n in re.findall(r"on screen: request (\d+),", log)]
        assert len(requests) >= 5, log[-3000:]
        assert requests == sorted(requests), requests
        acted = re.findall(r"action: key ([123]) -> shading", log)
        assert acted == KEYS, log[-3000:]
        assert len(set(re.findall(r"size=(\d+x\d+)", log))) == 2     # drawn at the new size
        last_frame = re.findall(r"frame \d+: .*", log)[-1]
        assert "phong" in last_frame, last_frame
        assert app.process.poll() is None
        assert "Traceback" not in app.log()
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)
