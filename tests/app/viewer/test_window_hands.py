"""The camera's hands in the real window under Xvfb, driven by xdotool (app.viewer.hands).

One session of the default scene (the house, 500 x 500, perspective wireframe): a drag
changes the picture and the panel's VPN and does not step the view; Ctrl+S appends the view to
saved.views in the user's state folder (``$XDG_STATE_HOME/fvd-viewer``) and ``python -m app
render`` of that file draws the screen's picture with 0 pixels different; Enter gives back
the file's view with 0 pixels different from the first picture; the wheel then grows the picture monotonically; a click without a drag advances exactly one view;
the loupe at 8x shows each frame pixel as an 8 x 8 block of its colour; F1 shows the keys
in the panel and leaves the picture alone.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time

import numpy as np
import pytest

from tools import need_programs

from core.paths import SCENES_DIR as ROOT_SCENES
from tests.app.viewer.test_window import App, frames, grab, start_xvfb


def drag(app, path, button: int = 1) -> None:
    """Press at the first point, move through the others, release at the last."""
    app.xdotool("mousemove", "--window", app.window, *map(str, path[0]))
    time.sleep(0.15)
    app.xdotool("mousedown", str(button))
    for x, y in path[1:]:
        time.sleep(0.05)
        app.xdotool("mousemove", "--window", app.window, str(x), str(y))
    time.sleep(0.1)
    app.xdotool("mouseup", str(button))


def settled(app, tmp_path, name: str, mark: int) -> np.ndarray:
    """The picture once a frame newer than ``mark`` is logged and the screen has stopped
    changing (two grabs apart with no frame logged between them: a drag's last frames may
    still be arriving)."""
    app.wait_for(r"^.*frame \d+: view", timeout=20, after=mark)
    deadline = time.monotonic() + 20
    before = grab(app, tmp_path / f"{name}.png", "500x500+0+0")
    while time.monotonic() < deadline:
        count = len(frames(app.log()))
        time.sleep(0.25)
        now = grab(app, tmp_path / f"{name}.png", "500x500+0+0")
        if np.array_equal(now, before) and len(frames(app.log())) == count:
            return now
        before = now
    pytest.fail(f"the picture {name} did not settle")


def extent(picture: np.ndarray) -> int:
    """Width of the lines drawn (the columns with any lit pixel)."""
    columns = np.flatnonzero(picture.any(axis=(0, 2)))
    return int(columns[-1] - columns[0]) if len(columns) else 0


@pytest.mark.xvfb
@pytest.mark.slow
def test_orbit_save_wheel_reset_click_and_help_under_xvfb(tmp_path):
    need_programs("Xvfb", "xdotool", "import", install="apt-get install xvfb xdotool imagemagick")
    from PIL import Image

    xvfb, display = start_xvfb()
    app = App(display, tmp_path, env={"XDG_STATE_HOME": str(tmp_path / "state")})
    try:
        app.wait_for(r"first frame shown", timeout=90)
        app.find_window()
        time.sleep(0.4)
        first = grab(app, tmp_path / "first.png", "500x500+0+0")
        panel = grab(app, tmp_path / "panel0.png", "340x500+500+0")

        # A drag orbits: VPN leaves (0, 0, 1), the picture and the panel change, view 1 stays.
        mark = len(app.log())
        drag(app, [(250, 250), (262, 252), (280, 255), (300, 255)])
        line = app.wait_for(r"drag arcball orbit about .* from \(250, 250\) to \(300, 255\) "
                            r"-> camera .*VPN \(([^)]*)\)", timeout=10, after=mark)
        vpn = np.array([float(c) for c in line[1].split(",")])
        assert vpn[0] < -0.1 and abs(np.linalg.norm(vpn) - 1) < 1e-12
        moved = settled(app, tmp_path, "moved", mark)
        assert frames(app.log())[-1]["view"] == 1 and "camera=moved" in app.log()[mark:]
        assert not np.array_equal(moved, first)
        assert not np.array_equal(grab(app, tmp_path / "panel1.png", "340x500+500+0"), panel)

        # Ctrl+S: the view appended to saved.views in the user's state folder (not the
        # folder the program was started from); render draws the same picture exactly.
        mark = len(app.log())
        app.key("ctrl+s")
        number = int(app.wait_for(r"view saved to .*saved\.views as view (\d+)", timeout=10,
                                  after=mark)[1])
        assert number == 1 and not (tmp_path / "saved.views").exists()
        saved = tmp_path / "state" / "fvd-viewer" / "saved.views"
        out = tmp_path / "saved.png"
        done = subprocess.run([sys.executable, "-m", "app", "render", str(saved), "--view",
                               "1", "--out", str(out)], cwd=tmp_path, env=app.env,
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        rendered = np.asarray(Image.open(out).convert("RGB"))
        assert int((rendered != moved).any(axis=2).sum()) == 0

        # Enter: the file's view, bit for bit.
        mark = len(app.log())
        app.key("Return")
        app.wait_for(r"key Enter -> the file's view again", timeout=10, after=mark)
        back = settled(app, tmp_path, "back", mark)
        assert "camera=moved" not in app.log()[mark:]
        assert int((back != first).any(axis=2).sum()) == 0
        cli = tmp_path / "view1.png"                 # and `render` of the file's view 1
        done = subprocess.run([sys.executable, "-m", "app", "render", "scenes/house.toml",
                               "--view", "1", "--out", str(cli)], cwd=ROOT_SCENES.parent,
                              capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        assert int((np.asarray(Image.open(cli).convert("RGB")) != back).any(axis=2).sum()) == 0

        # The wheel dollies in: the house grows with every notch.
        widths = [extent(back)]
        for _ in range(3):
            mark = len(app.log())
            app.xdotool("mousemove", "--window", app.window, "250", "250")
            app.xdotool("click", "4")
            app.wait_for(r"wheel \+1 \(dolly\)", timeout=10, after=mark)
            widths.append(extent(settled(app, tmp_path, "wheel", mark)))
        assert all(b > a for a, b in zip(widths, widths[1:])), widths

        mark = len(app.log())
        app.key("Return")
        assert int((settled(app, tmp_path, "back2", mark) != first).any(axis=2).sum()) == 0

        # A click without a drag still advances exactly one view.
        mark = len(app.log())
        app.click(250, 250)
        app.wait_for(r"frame \d+: view 2 of 20", timeout=10, after=mark)
        time.sleep(0.5)
        assert [f["view"] for f in frames(app.log()[mark:])] == [2]

        # The loupe: Alt+wheel three notches at a lit pixel (cx, cy) is 8x round it: screen
        # pixel q shows frame pixel c + floor((q - c) / 8), an 8 x 8 block each.
        picture = grab(app, tmp_path / "before-loupe.png", "500x500+0+0")
        lit = np.argwhere(picture.any(axis=2))
        cy, cx = lit[np.abs(lit - 250).sum(axis=1).argmin()]
        app.xdotool("mousemove", "--window", app.window, str(cx), str(cy))
        for k in (2, 4, 8):
            mark = len(app.log())
            app.xdotool("keydown", "--window", app.window, "alt")
            app.xdotool("click", "4")
            app.xdotool("keyup", "--window", app.window, "alt")
            app.wait_for(rf"Alt\+wheel \+1 at \({cx}, {cy}\) -> loupe {k}x", timeout=10, after=mark)
        time.sleep(0.5)
        loupe = grab(app, tmp_path / "loupe.png", "500x500+0+0")
        q = np.arange(500)
        rows, cols = cy + (q - cy) // 8, cx + (q - cx) // 8
        inside = lambda i: (i >= 0) & (i < 500)
        expected = np.zeros_like(picture)
        expected[np.ix_(inside(rows), inside(cols))] = picture[np.ix_(rows[inside(rows)],
                                                                     cols[inside(cols)])]
        assert np.array_equal(loupe, expected)
        assert (loupe[cy:cy + 8, cx:cx + 8] == picture[cy, cx]).all()
        assert len(np.unique(loupe.reshape(-1, 3), axis=0)) >= 2      # lines, not all black
        for _ in range(3):
            app.xdotool("keydown", "--window", app.window, "alt")
            app.xdotool("click", "5")
            app.xdotool("keyup", "--window", app.window, "alt")
        app.wait_for(r"-> loupe 1x", timeout=10)
        time.sleep(0.5)
        assert np.array_equal(grab(app, tmp_path / "unloupe.png", "500x500+0+0"), picture)

        # F1: the keys in the panel, the picture untouched.
        mark = len(app.log())
        app.key("F1")
        app.wait_for(r"key F1 -> keys help shown", timeout=10, after=mark)
        time.sleep(0.4)
        whole = grab(app, tmp_path / "help.png")
        assert np.array_equal(whole[:, :500], picture)
        assert not np.array_equal(whole[:, 500:], panel)
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)


# -- files: dropped, recent (the handlers called directly) --------------------------------

def hostile_drops(tmp_path):
    """(what glfw would hand the callback, the words its one message must have)."""
    import os
    folder = tmp_path / "a folder"
    folder.mkdir()
    empty = tmp_path / "empty.tri"
    empty.write_bytes(b"")
    fifo = tmp_path / "pipe.tri"
    os.mkfifo(fifo)
    huge = tmp_path / "huge.ply"
    with open(huge, "wb") as out:
        out.truncate(2 << 30)                           # 2 GiB, sparse
    odd = os.fsencode(tmp_path) + b"/caf\xe9.tri"
    with open(odd, "wb") as out:
        out.write(b"x")
    many = [str(tmp_path / f"{k}.tri") for k in range(40)]
    return [([str(folder)], "a folder"), ([str(empty)], "empty (0 bytes)"),
            ([str(fifo)], "a FIFO"), ([str(huge)], f"{2 << 30} bytes, more than any reader"),
            ([odd], "not UTF-8"), (many, "dropped 40 files at once"),
            ([str(tmp_path / "gone.tri")], "no such file")]


def test_hostile_drops_give_one_message_each(tmp_path):
    from app.viewer.files import check_drop
    for paths, words in hostile_drops(tmp_path):
        path, why = check_drop(paths)
        assert path is None and words in why, (paths[:1], why)
        assert "\n" not in why
    good = ROOT_SCENES / "few_triangles.tri"
    assert check_drop([str(good)]) == (str(good), "")


def test_recent_files_survive_a_restart_and_a_bad_list_is_ignored(tmp_path, capsys):
    from app.viewer.files import RECENT_COUNT, RecentFiles
    listed = tmp_path / "cfg" / "recent.json"
    recent = RecentFiles(listed)
    files = []
    for k in range(RECENT_COUNT + 2):
        f = tmp_path / f"s{k}.tri"
        f.write_text("0\n")
        files.append(f)
        recent.add(str(f))
    recent.add(str(files[3]))                        # opened again: first, not twice
    again = RecentFiles(listed)                      # a restart
    assert again.paths[0] == str(files[3]) and len(again.paths) == RECENT_COUNT
    assert again.paths[1] == str(files[-1]) and str(files[0]) not in again.paths
    files[-1].unlink()                               # gone since: listed, marked
    assert again.items()[1] == (str(files[-1]), False) and again.items()[0][1]
    # corrupt: ignored with one warning, the viewer goes on with an empty list
    listed.write_text('{"recent": [1, 2')
    broken = RecentFiles(listed)
    assert broken.paths == [] and "is ignored" in broken.warning
    assert "warning: the recent-files list" in capsys.readouterr().err
    listed.write_text('{"recent": "not a list"}')
    assert RecentFiles(listed).paths == []
    # unwritable: the warning, no exception
    blocked = tmp_path / "file-not-dir"
    blocked.write_text("")
    stuck = RecentFiles(blocked / "recent.json")
    stuck.add(str(files[0]))
    assert stuck.paths == [str(files[0])] and "could not be saved" in stuck.warning


@pytest.mark.xvfb
def test_a_dropped_file_opens_in_the_window_and_enters_recent(tmp_path):
    # The window on Xvfb, its drop handler called as glfw would call it. It runs in a fresh
    # process: after the EGL contexts of other tests in this one, libglvnd's GLX refuses
    # glfw's window with an X error, and Xlib's default handler ends the whole process.
    need_programs("Xvfb", install="apt-get install xvfb")
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    xvfb, display = start_xvfb()
    try:
        with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
            pool.submit(_drop_session, tmp_path, display).result(timeout=300)
    finally:
        xvfb.kill()
        xvfb.wait(timeout=10)


def _drop_session(tmp_path, display) -> None:
    import ctypes
    import os
    os.environ.update(DISPLAY=display, FVD_CONFIG_DIR=str(tmp_path / "config"))
    os.environ.pop("WAYLAND_DISPLAY", None)
    from app.viewer.files import RecentFiles
    from app.session.state import ViewerState
    from app.viewer.window import ViewerWindow
    state = ViewerState.open(ROOT_SCENES / "house.toml", size=(160, 120))
    window = ViewerWindow(state, out_dir=tmp_path)
    try:
        window.draw_frame()
        for paths, words in hostile_drops(tmp_path):
            assert window.on_drop(paths) is False
            assert words in state.open_messages[-1]
            window.draw_frame()                      # the window goes on
        assert state.scene.name.lower().startswith("fvdfh house")
        # glfw's own call: C strings, one of them not UTF-8
        names = [os.fsencode(tmp_path) + b"/caf\xe9.tri"]
        window._drop_callback(None, 1, (ctypes.c_char_p * 1)(*names))
        assert "not UTF-8" in state.open_messages[-1]
        tri = ROOT_SCENES / "few_triangles.tri"
        window._drop_callback(None, 1, (ctypes.c_char_p * 1)(str(tri).encode()))
        assert state.scene_source == str(tri)
        window.open_scene(str(ROOT_SCENES / "house.toml"), "test")
        assert window.on_drop([str(tri)]) is True
        assert state.scene_source == str(tri) and state.open_messages == []
        window.draw_frame()
        assert RecentFiles().paths[:2] == [str(tri), str((ROOT_SCENES / "house.toml"))]
    finally:
        window.close()


# -- the hands on a ViewerState, and --reference (no window) --------------------------------

def house_state(size=(160, 120)):
    from app.session.state import ViewerState
    return ViewerState.open(ROOT_SCENES / "house.toml", size=size)


def test_a_refused_pose_keeps_the_last_good_view_and_reset_is_exact():
    from app.viewer.hands import CameraHands
    state = house_state()
    hands = CameraHands(state)
    file_view = state.views.current
    hands.press(80, 60, pan=False)
    assert not hands.move(82, 61, threshold=6)              # within the threshold: no drag
    assert hands.move(120, 60, threshold=6) and state.hand_view is not None
    assert hands.release(120, 60, threshold=6)             # it was a drag, not a click
    moved = state.views.current
    assert moved.vpn != file_view.vpn and state.view_index == 0
    # dolly in until the eye nears the VRP: refused with its reason, the last pose kept
    refused = 0
    for _ in range(400):
        before = state.views.current
        if not hands.wheel(+1):
            refused += 1
            assert state.views.current == before
            assert "refused, the last good view kept" in hands.message
    assert refused > 0
    # Enter: the file's view, the very object (every number and F, B as in the file)
    assert hands.reset() and state.views.current is file_view and state.hand_view is None
    # a click (press and release within the threshold) is not a drag
    hands.press(10, 10, pan=True)
    assert hands.release(13, 12, threshold=6) is False and state.hand_view is None


def test_the_panel_numbers_are_the_matrices_commands(tmp_path):
    import json

    from app.viewer.hands import save_view, view_lines
    state = house_state()
    view = state.views.current
    lines = view_lines(view, "perspective")
    assert lines[:2] == ["VRP 0 0 0", "VPN 0 0 1"] and "N_per =" in lines
    done = subprocess.run([sys.executable, "-m", "app", "matrices", "scenes/house.toml",
                           "--view", "1"], cwd=ROOT_SCENES.parent, capture_output=True,
                          text=True, timeout=120)
    printed = json.loads(done.stdout)
    row = lines[lines.index("N_per =") + 1].split()
    assert [float(c) for c in row] == pytest.approx(printed["N_per"][0], rel=1e-3)
    # saved and read back: the same 18 numbers, bit for bit, after an existing view
    from core.scene.formats.viewfile import read_views
    path = tmp_path / "mine.views"
    path.write_text("0 0 0 0 0 1 0 1 0 -1 1 -1 1 0 0 5 1 -1")          # no newline at the end
    odd = view.__class__(vrp=(0.1, 1 / 3, -2e-17), vpn=view.vpn, vup=view.vup,
                         window=view.window, prp=view.prp, front=view.front, back=view.back)
    assert save_view(odd, path, "test") == 2
    views, messages = read_views(path.read_text(), str(path))
    assert messages == [] and np.array_equal(views[1].numbers, odd.numbers)
    path.write_text("0 0 0 1 2 3")                                    # a truncated view
    with pytest.raises(ValueError, match="truncated"):
        save_view(odd, path, "test")


def test_the_reference_cycles_picture_reference_difference(tmp_path):
    from PIL import Image

    from app.viewer.inspector_tools import InspectorTools
    from app.viewer.reference import ReferenceView, load_reference
    from core.inspect.compare import compare
    state = house_state()
    state.frames.update()
    ours = state.frame.color
    teacher = ours.copy()
    teacher[10:20, 30:40] = (255, 0, 0)                   # 100 pixels differ
    png = tmp_path / "teacher.png"
    Image.fromarray(teacher).save(png)
    tools = InspectorTools(state)
    tools.reference = ReferenceView(load_reference(png), png.name)
    tools.frame_changed(state.frame, 0.01)
    assert tools.picture(state.frame) is state.frame.rgbx
    tools.flip("key h")
    assert tools.reference.mode == "reference"
    assert np.array_equal(tools.picture(state.frame)[..., :3], teacher)
    tools.flip("key h")
    heat = tools.picture(state.frame)[..., :3]
    assert tools.reference.mode == "difference"
    assert tools.reference.verdict == "against teacher.png: " + compare(ours, teacher).verdict()
    assert "100 of 19200 pixels beyond the tolerance" in tools.reference.verdict
    assert (heat[10:20, 30:40] != teacher[10:20, 30:40] // 4).any(axis=2).all()
    tools.flip("key h")
    assert tools.reference.mode == "picture" and tools.picture(state.frame) is state.frame.rgbx
    # bad references: one clear message each
    (tmp_path / "notes.png").write_text("not a png")
    Image.fromarray(teacher).save(tmp_path / "photo.jpg")
    for name, words in (("missing.png", "no such file"), ("notes.png", "cannot read it"),
                        ("photo.jpg", "not a PNG")):
        with pytest.raises(ValueError, match=words):
            load_reference(tmp_path / name)
    small = ReferenceView(teacher[:50, :50], "small.png")
    small.cycle(state.frame, "key h")
    assert small.mode == "picture" and "50 x 50, the picture 160 x 120" in small.verdict


def test_while_dragging_the_latest_camera_wins():
    # A slow renderer and fifty pointer moves while its frame runs: the worker renders the
    # first request and then only the newest camera, never the ones in between.
    import threading

    from app.viewer.hands import CameraHands
    from app.viewer.worker import RenderWorker
    from core.render import render
    drawn, release = [], threading.Event()

    def slow(scene, view, settings, context=None):
        drawn.append(view)
        if len(drawn) == 1:
            release.wait(10)
        return render(scene, view, settings, context)

    state = house_state()
    state.renderer = slow
    hands = CameraHands(state)
    worker = RenderWorker()
    try:
        hands.press(80, 60, pan=False)
        hands.move(100, 60, threshold=6)
        assert state.frames.request(worker)
        deadline = time.monotonic() + 10
        while not drawn and time.monotonic() < deadline:
            time.sleep(0.01)
        for k in range(50):                       # the frame is still being drawn
            hands.move(100 + k, 60 + k % 7, threshold=6)
            state.frames.request(worker)
        latest = state.views.current
        release.set()
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            result = worker.collect()
            if result is not None and state.frames.accept(result) and len(drawn) == 2:
                break
            time.sleep(0.01)
        assert len(drawn) == 2 and drawn[1] == latest
    finally:
        worker.stop()


def test_the_loupe_maps_pans_and_returns_to_one_to_one():
    from app.viewer.loupe import Loupe
    loupe = Loupe()
    assert loupe.wheel(+3, 100.4, 50.9) == 8 and loupe.texel_at(100, 50) == (100, 50)
    assert loupe.texel_at(107, 57) == (100, 50) and loupe.texel_at(108, 49) == (101, 49)
    assert loupe.wheel(+5, 0, 0) == 32                       # at most 32x
    (sx, sy), shown = loupe.screen, loupe.texel_at(*loupe.screen)
    loupe.pan_from((sx, sy), 64, -32)                        # the picture follows the pointer
    assert loupe.texel_at(sx + 64, sy - 32) == shown and loupe.texel_at(sx, sy) == (
        shown[0] - 2, shown[1] + 1)
    assert loupe.set(1, 3, 3) == 1 and loupe.texel_at(17, 5) == (17, 5)   # 1:1 is the picture


def test_view_refuses_a_reference_that_is_not_a_png(tmp_path):
    import os
    (tmp_path / "notes.png").write_text("not a png")
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([sys.executable, "-m", "app", "view", "--reference",
                           str(tmp_path / "notes.png")], cwd=ROOT_SCENES.parent, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().startswith(f"error: --reference {tmp_path / 'notes.png'}: cannot "
                                          "read it as a PNG")
    assert "Traceback" not in done.stderr


def test_without_a_dialog_program_the_windows_own_dialog_opens(monkeypatch):
    import shutil as shutil_module

    from app.viewer import files
    monkeypatch.setattr(files.sys, "platform", "linux")
    monkeypatch.setattr(shutil_module, "which", lambda name: None)
    assert "no file dialog program found (zenity, kdialog" in files.dialog_missing()
    dialog = files.FileDialog()
    assert dialog.start("save view", "Append the view", save=True) == ""
    assert dialog.open and dialog.chooser is not None and dialog.chooser.save
    assert dialog.chooser.suffixes == (".views",)
    assert dialog.start("open", "Open") == "a file dialog is already open"
    assert dialog.poll() is None
