"""The panel's volume section under Xvfb: the picture on screen is the core's frame (nothing of
the panel over it), a click on the iso slider re-extracts the metaballs off the UI thread
(the log's triangle count is marching cubes' at that level, and the screen shows the core's
frame of the new surface), and the axial slice among the buffer views is the volume's slice."""

from __future__ import annotations

import re
import time

import numpy as np
import pytest

from tools import need_programs

from tests.app.viewer.test_window import ROOT, grab, start_xvfb
from tests.app.viewer.test_window_inspect import SceneApp

SIZE = (300, 560)
SCENE = "scenes/volume_isosurface.toml"
GRAB = (61, 133, 224)          # the dark style's slider grab


def core_frame(iso: float | None = None) -> np.ndarray:
    """The scene's first view by core.render at SIZE, the metaballs at ``iso`` if given."""
    from app.session.volume_controls import reextract
    from core.render import render
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    from core.volume.data import volumes_of
    scene = load_scene(ROOT / SCENE, size=SIZE)
    if iso is not None:
        reextract(scene, volumes_of(scene)[0], iso)
    return render(scene, scene.views[0], RenderSettings.for_scene(scene, size=SIZE)).color


@pytest.mark.xvfb
@pytest.mark.slow
def test_iso_slider_and_slice_view_under_xvfb(tmp_path):
    from app.session.volume_controls import slice_picture
    from core.scene.formats import load_scene
    from core.volume.data import volumes_of
    from core.volume.marching import marching_cubes

    need_programs("Xvfb", "xdotool", "import", install="apt-get install xvfb xdotool imagemagick")
    xvfb, display = start_xvfb()
    app = SceneApp(display, tmp_path, SCENE, "--size", f"{SIZE[0]}x{SIZE[1]}")
    w, h = SIZE
    try:
        app.wait_for(r"frame 1: ", timeout=240)
        app.find_window()
        time.sleep(1.0)
        whole = grab(app, tmp_path / "first.png")
        assert np.array_equal(whole[:h, :w], core_frame())          # nothing over the picture

        # the iso slider: the first slider grab in the panel (the status lines above it
        # change height while the kernels compile: look again before each try)
        asked = None
        for attempt in range(6):
            panel = grab(app, tmp_path / "panel.png")[:, w:]
            rows = np.nonzero((panel == GRAB).all(axis=2).any(axis=1))[0]
            assert len(rows)
            mark = len(app.log())
            app.click(w + 250, int(rows[0]) + 7)
            app.wait_for(r"left click at", 10, mark)
            time.sleep(0.5)
            found = re.compile(r"action: slider iso -> iso ([-\d.e]+) asked").search(
                app.log(), mark)
            if found:
                asked = float(found[1])
                break
        assert asked is not None, "no click reached the iso slider"
        line = app.wait_for(r"volume: metaballs re-extracted at iso ([-\d.e]+): (\d+) "
                            r"triangles", 120, mark)
        iso, count = float(line[1]), int(line[2])
        assert iso == asked and iso > 0.2
        volume = volumes_of(load_scene(ROOT / SCENE))[0]
        assert count == len(marching_cubes(volume.values, iso, "oracle")[1])
        render_line = re.compile(r"frame \d+: ")
        app.wait_for(render_line.pattern, 120, app.log().index(line[0]))
        time.sleep(1.0)
        shown = grab(app, tmp_path / "iso.png")[:h, :w]
        assert not np.array_equal(shown, whole[:h, :w])
        assert np.array_equal(shown, core_frame(iso))

        # v cycles the buffer views to the axial slice: the volume's slice, grey
        for _ in range(12):
            mark = len(app.log())
            app.key("v")
            name = app.wait_for(r"key v -> buffer view: ([\w-]+)", 60, mark)[1]
            if name in ("axial", "picture"):
                break
        assert name == "axial"
        time.sleep(1.0)
        axial = grab(app, tmp_path / "axial.png")[:h, :w]
        assert np.array_equal(axial, slice_picture(volume, "axial", 20, SIZE)[..., :3])
    finally:
        app.stop()
        xvfb.kill()
        xvfb.wait(timeout=10)
