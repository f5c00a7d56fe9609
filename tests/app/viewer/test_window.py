"""The viewer: its state without a window, and the real window under Xvfb driven by xdotool.

ViewerState is checked directly (views wrap, a frame is rendered only when the picture
changed, a minimised 0 x 0 framebuffer renders nothing, a scene that fails to open leaves the
user's scene and settings alone). The window test starts ``python -m app`` on a virtual X
display, clicks and types like a user, and reads the app's log (``$FVD_LOG``) and screenshots:
a click on the picture advances the view, a click on the menu bar does not, ``o`` switches to
parallel, and what is on screen is the CPU frame.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tools import need_module, need_programs, unavailable

from core.settings import RenderSettings
from app.session.state import ViewerState
from core.scene.generators import house
from core.paths import SCENES_DIR
from core.scene.model import Scene
from core.camera.view import View
from core.scene.formats.viewfile import read_view_entries

from tests.conftest import ROOT


def house_scene() -> Scene:
    """The default scene's content, built without the scene-file reader."""
    order = read_view_entries((SCENES_DIR / "house.views").read_text(), "house.views")
    return Scene(name="house", meshes=[house()], views=[v for v in order if isinstance(v, View)],
                 view_messages=[v for v in order if not isinstance(v, View)], view_order=order,
                 shading="wireframe", projection="perspective")


class CountingRenderer:
    """core.render.render, counting its calls."""

    def __init__(self):
        from core.render import render
        self.render = render
        self.calls = []

    def __call__(self, scene, view, settings, context=None):
        self.calls.append((scene.views.index(view), settings.projection, settings.shading,
                           settings.size))
        return self.render(scene, view, settings, context)


@pytest.fixture
def state():
    return ViewerState(scene=house_scene(), scene_source="house", size=(200, 150),
                       renderer=CountingRenderer())


# -- ViewerState, no window ---------------------------------------------------------------

def test_views_wrap_both_ways(state):
    # house.views: 20 views, 6 invalid (14-18 and 20); the window steps over those and
    # numbers the others by their place in the file
    n = state.views.count
    assert n == 14 and state.views.label == "view 1 of 20 (6 invalid)"
    state.views.prev_view()
    assert state.view_index == n - 1 and state.views.label == "view 19 of 20 (6 invalid)"
    state.views.prev_view()
    assert state.views.label == "view 13 of 20 (6 invalid)"
    state.views.next_view()
    state.views.next_view()
    assert state.view_index == 0
    for _ in range(n):
        state.views.next_view()
    assert state.view_index == 0


def test_frames_are_rendered_only_when_the_picture_changes(state):
    calls = state.renderer.calls
    assert state.frames.update() and len(calls) == 1
    assert state.frame.color.shape == (150, 200, 3)
    assert not state.frames.update() and len(calls) == 1          # nothing changed
    state.choices.set_projection("perspective")                     # already perspective
    state.choices.set_shading("wireframe")                          # already wireframe
    assert not state.frames.update() and len(calls) == 1
    state.choices.set_projection("parallel")
    assert state.frames.update() and calls[-1] == (0, "parallel", "wireframe", (200, 150))
    state.views.next_view()
    assert state.frames.update() and calls[-1] == (1, "parallel", "wireframe", (200, 150))
    state.choices.set_shading("flat")                               # the house has no triangles:
    assert state.frames.update() and calls[-1][2] == "flat"        # still a frame, of its edges


def test_bad_settings_are_refused(state):
    with pytest.raises(ValueError, match="perspective, parallel"):
        state.choices.set_projection("orthographic")
    with pytest.raises(ValueError, match="wireframe"):
        state.choices.set_shading("toon")
    assert state.projection == "perspective" and state.shading == "wireframe"


def test_minimised_window_renders_nothing_and_resize_renders_at_new_size(state):
    calls = state.renderer.calls
    state.frames.update()
    first = state.frame
    state.resize(0, 0)
    assert not state.renderable
    state.views.next_view()
    assert not state.frames.update() and len(calls) == 1 and state.frame is first
    state.resize(333, 217)
    assert state.frames.update() and state.frame.color.shape == (217, 333, 3)
    assert calls[-1] == (1, "perspective", "wireframe", (333, 217))
    state.resize(0, 217)                                    # one side zero is still nothing
    assert not state.frames.update()


def test_restoring_a_minimised_window_reuses_its_frame(state):
    calls = state.renderer.calls
    state.frames.update()
    width, height = state.size
    state.resize(0, 0)
    state.resize(width, height)                  # back to the frame's size: nothing changed
    assert not state.frames.update() and len(calls) == 1


def test_standard_input_cannot_be_opened_from_the_window(state):
    before = state.scene
    assert not state.open_scene("-")
    assert state.scene is before
    assert "standard input" in state.open_messages[-1]


def test_a_failing_render_keeps_the_last_frame_and_says_why(state):
    state.frames.update()
    good = state.frame
    real = state.renderer

    def broken(scene, view, settings, context=None):
        if settings.shading == "phong":
            raise ZeroDivisionError("a stage fell over")
        return real(scene, view, settings, context)

    state.renderer = broken
    state.choices.set_shading("phong")
    assert not state.frames.update() and state.frame is good and not state.dirty
    assert state.messages.all[-1] == ("could not render view 1 of 20 (6 invalid) "
                                      "(perspective, phong): ZeroDivisionError: a stage fell over")
    state.choices.set_shading("wireframe")                          # the user carries on
    assert state.frames.update() and state.frame is not good and state.render_error is None
    assert not any("could not render" in m for m in state.messages.all)


def test_messages_show_invalid_views_and_the_frame_message(state):
    scene = state.scene
    assert scene.view_messages, "house.views has invalid views that must give messages"
    assert state.messages.all == [f"invalid view: {m}" for m in scene.view_messages]
    # A view that is valid for one projection only: its frame says why it is blank.
    from core.camera.view import problems
    index = next((i for i, v in enumerate(scene.views)
                  if bool(problems(v, "perspective")) != bool(problems(v, "parallel"))), None)
    assert index is not None, "house.views has a view valid for one projection only"
    state.views.set_view(index)
    blank = []
    for projection in ("perspective", "parallel"):
        state.choices.set_projection(projection)
        state.frames.update()
        if state.frame.message:
            assert state.messages.all[-1] == state.frame.message
            assert "invalid" in state.frame.message
            blank.append(projection)
    assert blank == ["perspective"]            # F behind the eye: only perspective refuses it


def test_compile_notice_only_when_numba_compiles(capsys):
    from app.session import frames as state_module

    state_module._compiling.clear()
    state_module.compile_notice()                 # slow, but loading cached kernels: silent
    assert capsys.readouterr().err == ""
    state_module._compiling.set()
    state_module.compile_notice()
    assert "compiling the kernels" in capsys.readouterr().err
    state_module._compiling.clear()


def test_gui_text_keeps_to_the_fonts_characters():
    need_module("glfw", "the window needs glfw")
    from app.viewer.window import displayable, shipped_scenes

    assert displayable("Cohen–Sutherland — “clip” … 1/W ≤ 0 · ok") == \
        'Cohen-Sutherland - "clip" ... 1/W ? 0 . ok'
    names = [p.name for p in shipped_scenes()]
    assert "house.views" in names and not any(n.endswith((".py", ".md")) for n in names)


def bad_scene_files(tmp_path) -> list[Path]:
    junk = tmp_path / "junk.tri"
    junk.write_bytes(b"\x00\xff not a tri file \x00" * 10)
    huge = tmp_path / "huge.tri"
    huge.write_text("0 0 10\n-1 1 0\n0.01 0 0\n0 -0.01 0\n1000000000000\n0 0 0 1 0 0 0 1 0\n")
    return [junk, huge, tmp_path / "does-not-exist.toml"]


def test_a_scene_that_fails_to_open_keeps_the_users_work(state, tmp_path):
    state.views.next_view()
    state.views.next_view()
    state.choices.set_projection("parallel")
    state.frames.update()
    scene, frame, renders = state.scene, state.frame, len(state.renderer.calls)
    for path in bad_scene_files(tmp_path):
        assert state.open_scene(str(path)) is False
        assert state.scene is scene and state.frame is frame
        assert (state.view_index, state.projection, state.shading) == (2, "parallel", "wireframe")
        assert not state.dirty and not state.frames.update()
        assert len(state.renderer.calls) == renders
        assert state.messages.all[-1].startswith(f"could not open {path}")
    assert len(state.open_messages) == 3
    # A good scene then opens, at its first view with its own settings, and clears the errors.
    assert state.open_scene(str(SCENES_DIR / "house.views"))
    assert state.view_index == 0 and state.open_messages == [] and state.dirty
    assert state.frames.update()


# -- the real window under Xvfb ----------------------------------------------------------

XVFB_TOOLS = ("Xvfb", "xdotool")


def start_xvfb():
    """A virtual X display on a free number; returns (process, ':N')."""
    read_fd, write_fd = os.pipe()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "1024x768x24",
                             "-nolisten", "tcp"], pass_fds=(write_fd,),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_fd)
    number = b""
    deadline = time.monotonic() + 10
    with os.fdopen(read_fd, "rb") as pipe:
        while not number.endswith(b"\n") and time.monotonic() < deadline:
            chunk = pipe.read(1)
            if not chunk:
                break
            number += chunk
    if not number.strip():
        xvfb.kill()
        unavailable("Xvfb did not start")
    return xvfb, f":{number.decode().strip()}"


class App:
    """``python -m app`` on an X display, with its log file and the xdotool calls we need."""

    def __init__(self, display: str, workdir: Path, env: dict | None = None):
        self.display, self.workdir = display, workdir
        self.log_path = workdir / "fvd.log"
        self.env = {**os.environ, "DISPLAY": display, "FVD_LOG": str(self.log_path),
                    "PYTHONPATH": str(ROOT), **(env or {})}
        self.env.pop("WAYLAND_DISPLAY", None)
        # stdin /dev/null: a terminal's stand-in (a file or pipe there would be read as views)
        self.process = subprocess.Popen([sys.executable, "-m", "app"], cwd=workdir, env=self.env,
                                        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                        stderr=subprocess.PIPE)
        self.window = None

    def log(self) -> str:
        return self.log_path.read_text() if self.log_path.exists() else ""

    def wait_for(self, pattern: str, timeout: float, after: int = 0) -> re.Match:
        """The first match of ``pattern`` in the log past offset ``after``; fails on timeout."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            match = re.compile(pattern, re.M).search(self.log(), after)
            if match:
                return match
            if self.process.poll() is not None:
                out, err = self.process.communicate()
                pytest.fail(f"the app exited ({self.process.returncode}) before {pattern!r}:\n"
                            f"{err.decode(errors='replace')[-3000:]}")
            time.sleep(0.05)
        pytest.fail(f"no {pattern!r} in the log within {timeout} s:\n{self.log()[-3000:]}")

    def xdotool(self, *args: str) -> str:
        done = subprocess.run(["xdotool", *args], env=self.env, capture_output=True, text=True,
                              timeout=10)
        assert done.returncode == 0, f"xdotool {' '.join(args)}: {done.stderr}"
        return done.stdout.strip()

    def find_window(self) -> str:
        self.window = self.xdotool("search", "--sync", "--onlyvisible", "--name", "FvD viewer")
        self.window = self.window.split()[0]
        return self.window

    def click(self, x: int, y: int, button: int = 1) -> None:
        self.xdotool("mousemove", "--window", self.window, str(x), str(y))
        time.sleep(0.15)            # let a frame see the pointer there first, like a person
        self.xdotool("click", str(button))

    def key(self, name: str) -> None:
        self.xdotool("key", "--window", self.window, name)

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(timeout=10)


def frames(log: str) -> list[dict]:
    """Every 'frame N: view k of N ... projection=P shading=S size=WxH' line, parsed."""
    pattern = re.compile(r"frame (\d+): view (\d+) of (\d+) .*?projection=(\w+) shading=(\w+) "
                         r".*?size=(\d+)x(\d+)")
    return [dict(n=int(m[1]), view=int(m[2]), of=int(m[3]), projection=m[4], shading=m[5],
                 size=(int(m[6]), int(m[7]))) for m in pattern.finditer(log)]


def test_no_display_renders_every_view_to_png(state, tmp_path, capsys):
    from PIL import Image

    from app.viewer.launch import render_all_views
    from core.render import render

    out = tmp_path / "views"
    assert render_all_views(state, out, "DISPLAY and WAYLAND_DISPLAY are not set") == 0
    captured = capsys.readouterr()
    n = state.views.count
    assert (f"no display found (DISPLAY and WAYLAND_DISPLAY are not set): rendering the {n} "
            f"views to PNG in {out}") in captured.err
    files = sorted(out.glob("*.png"))
    # named by their place in the file: 1-13, then 19 (14-18 and 20 are invalid)
    assert [f.name for f in files] == [f"house-view{k:02d}-perspective-wireframe-zbuffer.png"
                                       for k in [*range(1, 14), 19]]
    for k, path in enumerate(files):
        assert f"wrote {path}" in captured.out
        expected = render(state.scene, state.scene.views[k],
                          RenderSettings.for_scene(state.scene, projection="perspective", shading="wireframe", size=(200, 150))).color
        assert np.array_equal(np.asarray(Image.open(path).convert("RGB")), expected)


def test_view_command_without_display_falls_back_to_png(tmp_path):
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update(PYTHONPATH=str(ROOT), FVD_OUT=str(tmp_path / "out"))
    done = subprocess.run([sys.executable, "-m", "app", "view"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    match = re.search(r"no display found \(.*\): rendering the (\d+) views to PNG in (.+?)/? "
                      r"instead", done.stderr)
    assert match and Path(match[2]) == tmp_path / "out"
    files = sorted((tmp_path / "out").glob("*.png"))
    assert len(files) == int(match[1]) > 0
    assert all(f"wrote {f}" in done.stdout for f in files)


@pytest.mark.xvfb
def test_a_display_without_opengl_3_3_falls_back_to_png_and_says_why(tmp_path):
    # Mesa told to offer OpenGL 2.1 only: glfw cannot make the 3.3 core context, and the
    # viewer says so in one line (glfw's own words, not a traceback) and writes the PNGs.
    need_programs(*XVFB_TOOLS, install="apt-get install xvfb xdotool")
    xvfb, display = start_xvfb()
    try:
        env = {**os.environ, "DISPLAY": display, "PYTHONPATH": str(ROOT),
               "FVD_OUT": str(tmp_path / "out"), "MESA_GL_VERSION_OVERRIDE": "2.1",
               "MESA_GLSL_VERSION_OVERRIDE": "120"}
        env.pop("WAYLAND_DISPLAY", None)
        done = subprocess.run([sys.executable, "-m", "app", "view"], cwd=tmp_path, env=env,
                              stdin=subprocess.DEVNULL, capture_output=True, text=True,
                              timeout=120)
    finally:
        xvfb.kill()
        xvfb.wait(timeout=10)
    assert done.returncode == 0, done.stderr
    match = re.search(r"no window could be opened on this display \((.+)\): rendering the "
                      r"(\d+) views to PNG in", done.stderr)
    assert match, done.stderr
    assert "Traceback" not in done.stderr and "(65543)" not in match[1]
    assert len(sorted((tmp_path / "out").glob("*.png"))) == int(match[2]) > 0


def grab(app, path: Path, crop: str | None = None) -> np.ndarray:
    """The window as the X server shows it (``crop``: ImageMagick's WxH+X+Y)."""
    from PIL import Image
    args = ["import", "-window", app.window] + (["-crop", crop, "+repage"] if crop else [])
    subprocess.run([*args, str(path)], env=app.env, check=True, timeout=10)
    return np.asarray(Image.open(path).convert("RGB"))


@pytest.mark.xvfb
@pytest.mark.slow
def _processes_with(variable: str, value: str) -> list[int]:
    """The pids whose environment has ``variable=value`` (Linux's /proc)."""
    wanted, found = f"{variable}={value}".encode(), []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if wanted in (entry / "environ").read_bytes().split(b"\0"):
                    found.append(int(entry.name))
            except OSError:
                pass
    return found


def test_a_cold_kernel_cache_opens_the_window_at_once(tmp_path):
    """A fresh clone's first start: no kernel is cached, yet the window and the house (which
    needs none) are on screen at once while worker processes compile; a window killed then
    leaves no warm-up compiling on."""
    need_programs(*XVFB_TOOLS, install="apt-get install xvfb xdotool")
    if not Path("/proc/self/environ").exists():
        unavailable("no /proc to find the warm-up's processes by")
    cache = tmp_path / "cold-cache"
    xvfb, display = start_xvfb()
    app = App(display, tmp_path, env={"NUMBA_CACHE_DIR": str(cache)})
    try:
        app.wait_for(r"kernel cache cold: compiling the kernels in worker processes", 60)
        app.wait_for(r"first frame shown", timeout=60)
        assert frames(app.log())[0]["shading"] == "wireframe"
        others = set(_processes_with("NUMBA_CACHE_DIR", str(cache))) - {app.process.pid}
        assert others, "no warm-up process beside the window"
    finally:
        app.process.kill()                # no clean-up of its own: the warm-up sees it gone
        app.process.wait(timeout=10)
        xvfb.kill()
    deadline = time.monotonic() + 90
    while _processes_with("NUMBA_CACHE_DIR", str(cache)) and time.monotonic() < deadline:
        time.sleep(0.2)
    left = _processes_with("NUMBA_CACHE_DIR", str(cache))
    assert left == [], f"the warm-up outlived the window: pids {left}"
    assert not (cache / "fvd-warm.json").exists()     # stopped half-way: not marked warm


def test_window_click_menu_and_keys_under_xvfb(tmp_path):
    need_programs(*XVFB_TOOLS, "import", install="apt-get install xvfb xdotool imagemagick")
    from PIL import Image

    from app.viewer.window import PANEL_WIDTH

    xvfb, display = start_xvfb()
    app = App(display, tmp_path)
    try:
        # The first frame: numba's cache may be cold on a fresh checkout, so allow for JIT.
        app.wait_for(r"first frame shown", timeout=90)
        app.find_window()
        first = frames(app.log())[-1]
        assert (first["view"], first["of"], first["size"]) == (1, 20, (500, 500))
        # the picture is 500 x 500 at the top-left, the panel beside it: nothing on the picture
        assert "Geometry: %dx500" % (500 + PANEL_WIDTH) in app.xdotool("getwindowgeometry",
                                                                         app.window)

        # A left click on the picture advances the view.
        mark = len(app.log())
        app.click(250, 250)
        app.wait_for(r"frame \d+: view 2 of 20", timeout=10, after=mark)

        # A click on the panel's menu bar (its empty right end) is ImGui's: the view stays.
        mark = len(app.log())
        app.click(500 + PANEL_WIDTH - 12, 8)
        app.wait_for(r"left click at \(\d+, 8\) -> taken by the menu/panel", timeout=10,
                     after=mark)

        # Right click: the pop-up; Esc closes it and the app keeps running.
        mark = len(app.log())
        app.click(250, 250, button=3)
        app.wait_for(r"right click at \(250, 250\) -> pop-up menu", timeout=10, after=mark)
        time.sleep(0.5)
        app.key("Escape")
        app.wait_for(r"key Esc -> close the open menu", timeout=10, after=mark)
        time.sleep(0.5)
        assert app.process.poll() is None, "Esc with the pop-up open must not quit"
        assert "-> quit" not in app.log()[mark:]

        # 'o' (parallel) or 'p' (perspective) switches at once; that frame is still view 2.
        key, other = (("o", "parallel") if first["projection"] == "perspective"
                      else ("p", "perspective"))
        mark = len(app.log())
        app.key(key)
        app.wait_for(rf"projection={other}", timeout=10, after=mark)
        last = frames(app.log())[-1]
        assert (last["view"], last["of"], last["projection"]) == (2, 20, other)
        assert all(f["view"] in (1, 2) for f in frames(app.log()))

        # The picture area on screen is `python -m app render` of the same view, pixel for
        # pixel; 's' saves the same frame into screenshots/.
        time.sleep(0.5)
        screen = grab(app, tmp_path / "picture.png", "500x500+0+0")
        rendered = tmp_path / "render.png"
        done = subprocess.run([sys.executable, "-m", "app", "render", "scenes/house.toml",
                               "--view", "2", "--projection", other, "--out", str(rendered)],
                              cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        cli = np.asarray(Image.open(rendered).convert("RGB"))
        assert len(np.unique(cli.reshape(-1, 3), axis=0)) >= 2, "the rendered frame is blank"
        assert np.array_equal(screen, cli)
        mark = len(app.log())
        app.key("s")
        saved = Path(app.wait_for(r"screenshot saved to (.+\.png)$", timeout=10, after=mark)[1])
        assert saved.parent == tmp_path / "screenshots"
        assert np.array_equal(np.asarray(Image.open(saved).convert("RGB")), cli)
        whole = grab(app, tmp_path / "window.png")
        assert whole.shape == (500, 500 + PANEL_WIDTH, 3)
        assert len(np.unique(whole[:, 500:].reshape(-1, 3), axis=0)) > 5   # the panel's text

        # Keys: '3' is Phong, the right arrow the next view; each re-renders at once.
        mark = len(app.log())
        app.key("3")
        app.wait_for(r"shading=phong", timeout=20, after=mark)
        app.key("Right")
        app.wait_for(rf"frame \d+: view 3 of 20 .*projection={other} shading=phong", timeout=10,
                     after=mark)

        # Resizing: the picture takes what the panel leaves (odd sizes too).
        mark = len(app.log())
        app.xdotool("windowsize", app.window, str(333 + PANEL_WIDTH), "217")
        app.wait_for(r"frame \d+: view 3 of .* size=333x217", timeout=10, after=mark)

        # Esc with nothing open quits cleanly (on the key press: xdotool's release may find
        # the window gone).
        subprocess.run(["xdotool", "key", "--window", app.window, "Escape"], env=app.env,
                       capture_output=True, timeout=10)
        assert app.process.wait(timeout=10) == 0
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)
