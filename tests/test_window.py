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
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from core.settings import RenderSettings
from app.viewer.state import ViewerState
from core.scene.generators import house
from core.paths import SCENES_DIR
from core.scene.model import Scene
from core.scene.formats.viewfile import read_views

ROOT = Path(__file__).resolve().parent.parent


def house_scene() -> Scene:
    """The default scene's content, built without the scene-file reader."""
    views, messages = read_views((SCENES_DIR / "house.views").read_text(), "house.views")
    return Scene(name="house", meshes=[house()], views=views, view_messages=messages,
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
    n = state.view_count
    assert n >= 5 and state.view_label == f"view 1 of {n}"
    state.prev_view()
    assert state.view_index == n - 1 and state.view_label == f"view {n} of {n}"
    state.next_view()
    assert state.view_index == 0
    for _ in range(n):
        state.next_view()
    assert state.view_index == 0


def test_frames_are_rendered_only_when_the_picture_changes(state):
    calls = state.renderer.calls
    assert state.update() and len(calls) == 1
    assert state.frame.color.shape == (150, 200, 3)
    assert not state.update() and len(calls) == 1          # nothing changed
    state.set_projection("perspective")                     # already perspective
    state.set_shading("wireframe")                          # already wireframe
    assert not state.update() and len(calls) == 1
    state.set_projection("parallel")
    assert state.update() and calls[-1] == (0, "parallel", "wireframe", (200, 150))
    state.next_view()
    assert state.update() and calls[-1] == (1, "parallel", "wireframe", (200, 150))
    state.set_shading("flat")                               # the house has no triangles:
    assert state.update() and calls[-1][2] == "flat"        # still a frame, of its edges


def test_bad_settings_are_refused(state):
    with pytest.raises(ValueError, match="perspective, parallel"):
        state.set_projection("orthographic")
    with pytest.raises(ValueError, match="wireframe"):
        state.set_shading("toon")
    assert state.projection == "perspective" and state.shading == "wireframe"


def test_minimised_window_renders_nothing_and_resize_renders_at_new_size(state):
    calls = state.renderer.calls
    state.update()
    first = state.frame
    state.resize(0, 0)
    assert not state.renderable
    state.next_view()
    assert not state.update() and len(calls) == 1 and state.frame is first
    state.resize(333, 217)
    assert state.update() and state.frame.color.shape == (217, 333, 3)
    assert calls[-1] == (1, "perspective", "wireframe", (333, 217))
    state.resize(0, 217)                                    # one side zero is still nothing
    assert not state.update()


def test_restoring_a_minimised_window_reuses_its_frame(state):
    calls = state.renderer.calls
    state.update()
    width, height = state.size
    state.resize(0, 0)
    state.resize(width, height)                  # back to the frame's size: nothing changed
    assert not state.update() and len(calls) == 1


def test_standard_input_cannot_be_opened_from_the_window(state):
    before = state.scene
    assert not state.open_scene("-")
    assert state.scene is before
    assert "standard input" in state.open_messages[-1]


def test_a_failing_render_keeps_the_last_frame_and_says_why(state):
    state.update()
    good = state.frame
    real = state.renderer

    def broken(scene, view, settings, context=None):
        if settings.shading == "phong":
            raise ZeroDivisionError("a stage fell over")
        return real(scene, view, settings, context)

    state.renderer = broken
    state.set_shading("phong")
    assert not state.update() and state.frame is good and not state.dirty
    assert state.messages[-1] == ("could not render view 1 (perspective, phong): "
                                  "ZeroDivisionError: a stage fell over")
    state.set_shading("wireframe")                          # the user carries on
    assert state.update() and state.frame is not good and state.render_error is None
    assert not any("could not render" in m for m in state.messages)


def test_messages_show_invalid_views_and_the_frame_message(state):
    scene = state.scene
    assert scene.view_messages, "house.views has invalid views that must give messages"
    assert state.messages == [f"invalid view: {m}" for m in scene.view_messages]
    # A view that is valid for one projection only: its frame says why it is blank.
    from core.camera.view import problems
    index = next((i for i, v in enumerate(scene.views)
                  if bool(problems(v, "perspective")) != bool(problems(v, "parallel"))), None)
    assert index is not None, "house.views has a view valid for one projection only"
    state.set_view(index)
    blank = []
    for projection in ("perspective", "parallel"):
        state.set_projection(projection)
        state.update()
        if state.frame.message:
            assert state.messages[-1] == state.frame.message
            assert "invalid" in state.frame.message
            blank.append(projection)
    assert blank == ["perspective"]            # F behind the eye: only perspective refuses it


def test_compile_notice_only_when_numba_compiles(capsys):
    from app.viewer import state as state_module

    state_module._compiling.clear()
    state_module.compile_notice()                 # slow, but loading cached kernels: silent
    assert capsys.readouterr().err == ""
    state_module._compiling.set()
    state_module.compile_notice()
    assert capsys.readouterr().err == "compiling the rasterizer (first start only)…\n"
    state_module._compiling.clear()


def test_gui_text_keeps_to_the_fonts_characters():
    pytest.importorskip("glfw")
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
    state.next_view()
    state.next_view()
    state.set_projection("parallel")
    state.update()
    scene, frame, renders = state.scene, state.frame, len(state.renderer.calls)
    for path in bad_scene_files(tmp_path):
        assert state.open_scene(str(path)) is False
        assert state.scene is scene and state.frame is frame
        assert (state.view_index, state.projection, state.shading) == (2, "parallel", "wireframe")
        assert not state.dirty and not state.update() and len(state.renderer.calls) == renders
        assert state.messages[-1].startswith(f"could not open {path}")
    assert len(state.open_messages) == 3
    # A good scene then opens, at its first view with its own settings, and clears the errors.
    assert state.open_scene(str(SCENES_DIR / "house.views"))
    assert state.view_index == 0 and state.open_messages == [] and state.dirty
    assert state.update()


# -- the real window under Xvfb ----------------------------------------------------------

XVFB_TOOLS = ("Xvfb", "xdotool")


def start_xvfb():
    """A virtual X display on a free number; returns (process, ':N')."""
    read_fd, write_fd = os.pipe()
    xvfb = subprocess.Popen(["Xvfb", "-displayfd", str(write_fd), "-screen", "0", "640x560x24",
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
        pytest.skip("Xvfb did not start")
    return xvfb, f":{number.decode().strip()}"


class App:
    """``python -m app`` on an X display, with its log file and the xdotool calls we need."""

    def __init__(self, display: str, workdir: Path):
        self.display, self.workdir = display, workdir
        self.log_path = workdir / "fvd.log"
        self.env = {**os.environ, "DISPLAY": display, "FVD_LOG": str(self.log_path),
                    "PYTHONPATH": str(ROOT)}
        self.env.pop("WAYLAND_DISPLAY", None)
        self.process = subprocess.Popen([sys.executable, "-m", "app"], cwd=workdir, env=self.env,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
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
                         r"size=(\d+)x(\d+)")
    return [dict(n=int(m[1]), view=int(m[2]), of=int(m[3]), projection=m[4], shading=m[5],
                 size=(int(m[6]), int(m[7]))) for m in pattern.finditer(log)]


def test_no_display_renders_every_view_to_png(state, tmp_path, capsys):
    from PIL import Image

    from app.viewer.launch import render_all_views
    from core.render import render

    out = tmp_path / "views"
    assert render_all_views(state, out, "DISPLAY and WAYLAND_DISPLAY are not set") == 0
    captured = capsys.readouterr()
    n = state.view_count
    assert (f"no display found (DISPLAY and WAYLAND_DISPLAY are not set): rendering the {n} "
            f"views to PNG in {out}") in captured.err
    files = sorted(out.glob("*.png"))
    assert [f.name for f in files] == [f"house-view{k:02d}-perspective-wireframe.png"
                                       for k in range(1, n + 1)]
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
@pytest.mark.slow
def test_window_click_menu_and_keys_under_xvfb(tmp_path):
    missing = [tool for tool in XVFB_TOOLS if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"{' and '.join(missing)} not installed (apt-get install xvfb xdotool)")
    from PIL import Image

    xvfb, display = start_xvfb()
    app = App(display, tmp_path)
    try:
        # The first frame: numba's cache may be cold on a fresh checkout, so allow for JIT.
        app.wait_for(r"first frame shown", timeout=90)
        app.find_window()
        first = frames(app.log())[-1]
        assert (first["view"], first["size"]) == (1, (500, 500))
        n = first["of"]

        # A left click on the picture advances the view.
        mark = len(app.log())
        app.click(250, 250)
        app.wait_for(r"frame \d+: view 2 of", timeout=10, after=mark)

        # A click on the menu bar (its empty middle) is ImGui's: the view stays.
        mark = len(app.log())
        app.click(250, 6)
        app.wait_for(r"left click at \(250, 6\) -> taken by the menu/GUI", timeout=10, after=mark)

        # 'o' (parallel) or 'p' (perspective) switches at once; that frame is still view 2, so
        # the menu click above (handled before it, in order) did not advance the view.
        key, other = (("o", "parallel") if first["projection"] == "perspective"
                      else ("p", "perspective"))
        mark = len(app.log())
        app.key(key)
        app.wait_for(rf"projection={other}", timeout=10, after=mark)
        last = frames(app.log())[-1]
        assert (last["view"], last["of"], last["projection"]) == (2, n, other)
        assert all(f["view"] in (1, 2) for f in frames(app.log()))

        # 's' saves the CPU frame; the screen shows exactly that frame where no panel covers it.
        mark = len(app.log())
        app.key("s")
        saved = Path(app.wait_for(r"screenshot saved to (.+\.png)$", timeout=10, after=mark)[1])
        cpu = np.asarray(Image.open(saved).convert("RGB"))
        assert cpu.shape == (500, 500, 3)
        assert len(np.unique(cpu.reshape(-1, 3), axis=0)) >= 2, "the saved frame is blank"
        grab = tmp_path / "screen.png"
        if shutil.which("import"):
            subprocess.run(["import", "-window", app.window, str(grab)], env=app.env,
                           check=True, timeout=10)
        else:
            subprocess.run(["xwd", "-id", app.window, "-out", str(grab) + ".xwd"], env=app.env,
                           check=True, timeout=10)
            grab = grab.with_suffix(".png.xwd")
        screen = np.asarray(Image.open(grab).convert("RGB"))
        assert screen.shape == (500, 500, 3)
        middle = (slice(150, 350), slice(100, 400))      # below the panels, above the messages
        assert len(np.unique(cpu[middle].reshape(-1, 3), axis=0)) >= 2, "nothing to compare"
        assert np.array_equal(screen[middle], cpu[middle])
        assert len(np.unique(screen.reshape(-1, 3), axis=0)) > 10  # picture and GUI text

        # Keys: '3' is Phong, the right arrow the next view; each re-renders at once.
        mark = len(app.log())
        app.key("3")
        app.wait_for(r"shading=phong", timeout=20, after=mark)
        app.key("Right")
        app.wait_for(rf"frame \d+: view 3 of .*projection={other} shading=phong", timeout=10,
                     after=mark)

        # Resizing re-renders at the new framebuffer size (odd sizes too).
        mark = len(app.log())
        app.xdotool("windowsize", app.window, "333", "217")
        app.wait_for(r"frame \d+: view 3 of .* size=333x217", timeout=10, after=mark)

        # q quits cleanly (on the key press: xdotool's release may find the window gone).
        subprocess.run(["xdotool", "key", "--window", app.window, "q"], env=app.env,
                       capture_output=True, timeout=10)
        assert app.process.wait(timeout=10) == 0
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)
