"""The status line's value under the cursor (app.viewer.loupe.value_at): RGB, depth and the
visible triangle with its mesh.

The triangle words are checked against hand counts (a triangle's place in its mesh from the
meshes' sizes) and, on a rendered frame, against the pixel inspector's record for the same
pixel (a consistency check: both read the z-buffer's visibility, in our code).
"""

from __future__ import annotations

import numpy as np
import pytest

from app.viewer.loupe import triangle_words, value_at
from core.context import RenderContext
from core.inspect import inspect_pixel
from core.inspect.buffers import buffer
from core.paths import SCENES_DIR
from core.render import render
from core.scene.formats import load_scene
from core.settings import RenderSettings


def test_triangle_words_place_a_scene_triangle_in_its_mesh():
    meshes = [("floor", 2), ("roof", 12), (None, 4)]
    assert triangle_words(-1, meshes) == "background"
    assert triangle_words(0, meshes) == "triangle 0 of 'floor' (scene triangle 0)"
    assert triangle_words(2, meshes) == "triangle 0 of 'roof' (scene triangle 2)"
    assert triangle_words(13, meshes) == "triangle 11 of 'roof' (scene triangle 13)"
    assert triangle_words(14, meshes) == "triangle 0 of 'a mesh' (scene triangle 14)"
    assert triangle_words(99, meshes) == "scene triangle 99"     # a mesh list out of date


def test_the_status_line_names_the_triangle_the_inspector_names():
    scene = load_scene(SCENES_DIR / "three_bars.toml")
    view = scene.views[0]
    settings = RenderSettings.for_scene(scene, size=(80, 60))
    context = RenderContext()
    frame = render(scene, view, settings, context)
    ids, _ = buffer(scene, view, settings, "triangle", context)
    meshes = [(m.name, len(m.triangles)) for m in scene.meshes]
    rows, columns = np.nonzero(ids >= 0)
    assert len(rows) > 100 and (ids < 0).any()
    for k in np.linspace(0, len(rows) - 1, 12).astype(int):
        x, y = int(columns[k]), int(rows[k])
        record = inspect_pixel(scene, view, settings, x, y)
        words = value_at(frame, x, y, ids, meshes)
        r, g, b = (int(c) for c in frame.color[y, x])
        assert words.startswith(f"pixel ({x}, {y}): RGB ({r}, {g}, {b}), depth ")
        assert words.endswith(f"triangle {record['triangle']} of {record['mesh name']!r} "
                              f"(scene triangle {record['scene triangle']})")
    y, x = (int(v[0]) for v in np.nonzero(ids < 0))
    assert value_at(frame, x, y, ids, meshes).endswith("depth empty, background")
    assert "triangle" not in value_at(frame, x, y)            # no buffer: RGB and depth only
    assert value_at(frame, 80, 0, ids, meshes) == "pixel (80, 0): outside the frame"


def test_the_window_s_tools_draw_the_ids_off_the_ui_thread_once_per_frame():
    import time
    from app.viewer.inspector_tools import InspectorTools
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES_DIR / "three_bars.toml", size=(80, 60))
    assert state.frames.update()
    tools = InspectorTools(state)
    assert tools.triangle_ids(state.frame) == (None, ())      # asked: drawn on a thread
    deadline = time.monotonic() + 120
    while tools._picking is not None and time.monotonic() < deadline:
        time.sleep(0.01)
    ids, meshes = tools.triangle_ids(state.frame)
    expected, _ = buffer(state.scene, state.views.current, state.choices.settings(), "triangle")
    assert np.array_equal(ids, expected)
    assert meshes == [(m.name, len(m.triangles)) for m in state.scene.meshes]
    assert tools.triangle_ids(state.frame)[0] is ids           # once per frame
    state.choices.set_renderer("raytrace")                             # keeps no triangle buffer
    assert state.frames.update()
    assert tools.triangle_ids(state.frame) == (None, ()) and tools._picking is None


def test_the_aliasing_view_is_the_aliased_frame_left_and_the_antialiased_right():
    import dataclasses
    from app.viewer.inspector_tools import ALIASED, ANTIALIASED_LINES, InspectorTools
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES_DIR / "house.toml", size=(90, 60))     # the wireframe
    assert state.frames.update()
    tools = InspectorTools(state)
    tools.choose_buffer("aliasing", "test")
    assert tools.buffer == "picture" and tools.busy == "drawing the aliasing view"   # off the UI thread
    tools.settle()
    assert tools.buffer == "aliasing"
    view, settings = state.views.current, state.choices.settings()
    aliased = render(state.scene, view, dataclasses.replace(settings, **ALIASED)).color
    smooth = render(state.scene, view, dataclasses.replace(settings, **ANTIALIASED_LINES)).color
    shown = tools.picture(state.frame)[:, :, :3]
    assert np.array_equal(shown[:, :45], aliased[:, :45])
    assert np.array_equal(shown[:, 45:], smooth[:, 45:])
    # midpoint lines are one colour on the background; Wu's weigh each pixel by coverage
    assert len(np.unique(aliased.reshape(-1, 3), axis=0)) <= 3
    assert len(np.unique(smooth.reshape(-1, 3), axis=0)) > 20
    # the same ink: Wu's line spreads each column's one pixel over two (within 3 %)
    assert smooth[:, 45:].sum() == pytest.approx(aliased[:, 45:].sum(), rel=0.03)


def test_the_row_profile_is_the_luma_of_each_pixel_of_the_row():
    from app.viewer.inspector_tools import row_profile
    color = np.zeros((2, 3, 3), np.uint8)
    color[1] = [[255, 0, 0], [0, 255, 0], [10, 20, 30]]
    assert row_profile(color, 1) == pytest.approx([76.245, 149.685, 0.299 * 10 + 0.587 * 20
                                                   + 0.114 * 30], abs=1e-3)
    assert row_profile(color, 0).tolist() == [0.0, 0.0, 0.0]


def test_the_aliasing_view_is_not_drawn_for_a_ray_tracer_on_the_ui_thread():
    from app.viewer.inspector_tools import InspectorTools
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES_DIR / "three_bars.toml", size=(40, 30))
    state.choices.set_renderer("raytrace")
    assert state.frames.update()
    tools = InspectorTools(state)
    tools.choose_buffer("aliasing", "test")
    tools.settle()
    assert tools.buffer == "picture" and tools.overlay is None


def test_a_filled_scene_s_antialiased_half_is_16_samples_through_mitchell():
    import dataclasses
    from app.viewer.inspector_tools import ANTIALIASED, InspectorTools
    from app.session.state import ViewerState
    state = ViewerState.open(SCENES_DIR / "three_bars.toml", size=(60, 40))
    assert state.frames.update()
    tools = InspectorTools(state)
    tools.choose_buffer("aliasing", "test")
    tools.settle()
    smooth = render(state.scene, state.views.current,
                    dataclasses.replace(state.choices.settings(), **ANTIALIASED)).color
    shown = tools.picture(state.frame)[:, :, :3]
    assert np.array_equal(shown[:, 30:], smooth[:, 30:])
    assert np.array_equal(shown[:, :30], state.frame.color[:, :30])   # the frame: 1 sample
