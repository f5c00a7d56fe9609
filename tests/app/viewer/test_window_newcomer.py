"""The window's rough edges a newcomer met, each in the real window under Xvfb: a failed
File > Open says its own message once and Esc dismisses it (the viewer keeps running); a
window narrower than the panel shows no ghost of the old frame; a movie that does not loop
ends on its last frame ("frame N of N"); screenshots are named by the one rule.

The helpers (Xvfb, the app with its log, xdotool, screenshots) are test_window.py's.
"""

from __future__ import annotations

import re
import subprocess
import time

import numpy as np
import pytest

from test_window import ROOT
from test_window_systems import AppOn, display  # noqa: F401  (the fixture)

from app.naming import SAFE_NAME


def _field_of_open_path(picture: np.ndarray, width: int) -> tuple[int, int]:
    """The File > Open scene > Path field, left of its blue Open button: the submenu opens
    over the picture, its right edge at the panel (``width``), the field first in it. Found
    from the screen, so that a change of font or layout moves it harmlessly."""
    r, g, b = (picture[..., k].astype(int) for k in range(3))
    columns = np.arange(picture.shape[1])[None, :]
    blue = (b - r > 30) & (b > 60) & (columns >= width - 45) & (columns < width - 3)
    rows = np.flatnonzero(blue[20:].sum(axis=1) > 20) + 20          # below the menu bar
    assert rows.size, "no Open button on the screen"
    band = rows[rows < rows[0] + 30]
    y = int(band.mean())
    return int(np.flatnonzero(blue[y])[0]) - 60, y


def _open_path(app, tmp_path, path: str, name: str, width: int) -> None:
    """File > Open scene > Path: type ``path`` and press Enter, as a user does."""
    app.click(width + 20, 8)                        # File
    time.sleep(0.6)
    app.xdotool("mousemove", "--window", app.window, str(width + 40), "30")   # Open scene
    time.sleep(0.8)
    from test_window import grab
    x, y = _field_of_open_path(grab(app, tmp_path / f"{name}.png"), width)
    app.click(x, y)
    time.sleep(0.4)
    _hold(app, "ctrl+a")                            # the last path typed: replace it
    app.xdotool("type", "--window", app.window, "--delay", "20", path)
    time.sleep(0.3)
    _hold(app, "Return")


def _hold(app, keys: str) -> None:
    """Press ``keys`` for a few frames, as a hand does (Dear ImGui's input queue would also
    see a press and a release between two frames, but a hand holds a key for a while)."""
    app.xdotool("keydown", "--window", app.window, keys)
    time.sleep(0.25)
    app.xdotool("keyup", "--window", app.window, keys)


@pytest.mark.xvfb
@pytest.mark.slow
def test_a_failed_open_says_its_message_once_and_esc_dismisses_it(display, tmp_path):  # noqa: F811
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "house.toml"), "--size", "300x400")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        time.sleep(0.5)
        mark = len(app.log())
        _open_path(app, tmp_path, "nowhere-one.toml", "menu1", 300)
        app.wait_for(r"menu File > Open path -> could not open nowhere-one\.toml", timeout=20,
                     after=mark)
        time.sleep(0.8)
        mark = len(app.log())
        _open_path(app, tmp_path, "nowhere-two.toml", "menu2", 300)
        app.wait_for(r"menu File > Open path -> could not open nowhere-two\.toml", timeout=20,
                     after=mark)
        time.sleep(0.8)
        # the menu has closed itself; Esc now dismisses the message and does not quit
        mark = len(app.log())
        app.key("Escape")
        app.wait_for(r"key Esc -> (dismiss the message|close the open menu)", timeout=10,
                     after=mark)
        if "close the open menu" in app.log()[mark:]:          # a menu was still open: again
            time.sleep(0.5)
            app.key("Escape")
            app.wait_for(r"key Esc -> dismiss the message", timeout=10, after=mark)
        time.sleep(0.8)
        assert app.process.poll() is None, "Esc on an error message must not quit"
        assert "-> quit" not in app.log()[mark:]
        from test_window import grab
        grab(app, tmp_path / "dismissed.png")
        # with nothing left to dismiss, Esc quits (on the key press: xdotool's release may
        # find the window gone, so its status is not asserted)
        subprocess.run(["xdotool", "key", "--window", app.window, "Escape"], env=app.env,
                       capture_output=True, timeout=10)
        assert app.process.wait(timeout=20) == 0
        err = app.process.stderr.read().decode(errors="replace").splitlines()
        said = [line for line in err if line.startswith("could not open")]   # not the log's
        assert [line.split(":")[0] for line in said] == ["could not open nowhere-one.toml",
                                                         "could not open nowhere-two.toml"], err
    finally:
        app.stop()


@pytest.mark.xvfb
@pytest.mark.slow
def test_a_window_narrower_than_the_panel_shows_no_ghost_of_the_old_frame(display, tmp_path):  # noqa: F811
    from app.viewer.window import PANEL_WIDTH
    from test_window import grab

    # a bright background, so that an old frame behind the panel would show through it
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "whitted.toml"), "--size", "200x700",
                "--renderer", "zbuffer")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        app.wait_for(r"frame \d+: .* renderer=zbuffer", timeout=60)
        time.sleep(0.5)
        mark = len(app.log())
        app.xdotool("windowsize", app.window, str(PANEL_WIDTH - 60), "740")
        app.wait_for(r"picture hidden: the panel takes the whole window", timeout=10, after=mark)
        time.sleep(1.0)
        narrow = grab(app, tmp_path / "narrow.png")
        assert narrow.shape[:2] == (740, PANEL_WIDTH - 60)
        # the panel's left margin below its last widget (no text there): the rows where the
        # old 700-pixel frame was are the panel's plain colour, like the rows below them,
        # where there never was a frame (a frame behind the panel shows through its alpha)
        margin = narrow[:735, 2:5].reshape(735, -1)    # not the panel's 1-pixel border
        plain = margin[730]
        below = np.flatnonzero(np.any(margin != plain, axis=1))
        last_widget = below.max() if below.size else 0
        # the panel's widgets end near row 470 (its font and the whitted scene's notes), so
        # rows from there to 700 are where an old frame would show
        assert last_widget < 600, (f"not the panel's plain colour down to row {last_widget}: "
                                   "a frame shows through")
        assert np.all(margin[last_widget + 1:] == plain)
        assert app.process.poll() is None
        # widened again, the picture comes back at the size the panel leaves
        mark = len(app.log())
        app.xdotool("windowsize", app.window, str(PANEL_WIDTH + 120), "740")
        app.wait_for(r"frame \d+: .* size=120x740", timeout=60, after=mark)
    finally:
        app.stop()


MOVIE = """
name = "A short movie"
shading = "flat"
[animation]
duration = 0.5
fps = 10
loop = false
[[geometry]]
generator = "cube"
name = "box"
[[key]]
time = 0.0
object.box = { rotate = [0, 0, 0] }
[[key]]
time = 0.5
object.box = { rotate = [0, 90, 0] }
"""


@pytest.mark.xvfb
@pytest.mark.slow
def test_a_movie_that_does_not_loop_ends_on_its_last_frame(display, tmp_path):  # noqa: F811
    scene = tmp_path / "movie.toml"
    scene.write_text(MOVIE)
    app = AppOn(display, tmp_path, str(scene), "--size", "120x120")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        time.sleep(0.5)
        mark = len(app.log())
        app.key("space")
        app.wait_for(r"key Space -> play", timeout=10, after=mark)
        # played to its end: the last frame is drawn (at 0.4 s: frame 5 of 5, at k / fps)
        app.wait_for(r"frame \d+: .* t=0\.400 ", timeout=120, after=mark)
        time.sleep(0.5)
        for _ in range(3):                        # and one step past it, three times
            app.key("period")
            time.sleep(0.3)
        steps = re.findall(r"next frame: (.*)", app.log()[mark:])
        assert steps, app.log()[mark:]
        assert all(re.search(r"frame 5 of 5", s) for s in steps), steps
        assert not re.search(r"frame [6-9] of 5", app.log())
        assert app.process.poll() is None
    finally:
        app.stop()


@pytest.mark.xvfb
@pytest.mark.slow
def test_screenshots_follow_the_naming_rule_and_name_the_renderer(display, tmp_path):  # noqa: F811
    app = AppOn(display, tmp_path, str(ROOT / "scenes" / "whitted.toml"), "--size", "80x60",
                "--renderer", "zbuffer")
    try:
        app.wait_for(r"first frame shown", timeout=120)
        app.find_window()
        app.wait_for(r"frame \d+: .* renderer=zbuffer", timeout=60)
        mark = len(app.log())
        app.key("s")
        first = app.wait_for(r"screenshot saved to (.+\.png)$", timeout=10, after=mark)[1]
        mark = len(app.log())
        app.key("r")
        app.wait_for(r"frame \d+: .* renderer=raytrace", timeout=180, after=mark)
        app.key("s")
        second = app.wait_for(r"screenshot saved to (.+\.png)$", timeout=10, after=mark)[1]
        names = [first.rsplit("/", 1)[1], second.rsplit("/", 1)[1]]
        assert names == ["whitted-glass-and-mirror-spheres-view01-perspective-phong-zbuffer.png",
                         "whitted-glass-and-mirror-spheres-view01-perspective-phong-raytrace.png"]
        assert all(SAFE_NAME.match(n) for n in names)
    finally:
        app.stop()
