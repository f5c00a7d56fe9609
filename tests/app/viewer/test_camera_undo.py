"""Undo and redo of camera moves (Ctrl+Z, Ctrl+Shift+Z): a drag is one step, a spin of the
wheel is one step, a click to the next view is one step; undo gives the picture from before,
exactly."""

from __future__ import annotations

import numpy as np

from app.session.state import ViewerState
from app.viewer.hands import CameraHands
from core.paths import SCENES_DIR


def _state():
    state = ViewerState.open(SCENES_DIR / "house.toml", size=(80, 60))
    state.choices.set_shading("flat")
    assert state.frames.update()
    return state, CameraHands(state)


def _drag(hands, x0, y0, x1, y1, steps=6):
    hands.press(x0, y0, pan=False)
    for k in range(1, steps + 1):
        hands.move(x0 + (x1 - x0) * k / steps, y0 + (y1 - y0) * k / steps, threshold=3)
    assert hands.release(x1, y1, threshold=3)


def test_a_drag_is_one_step_and_undo_gives_the_picture_before_it_exactly():
    state, hands = _state()
    before = state.frame.color.copy()
    _drag(hands, 40, 30, 60, 35)
    assert state.frames.update() and not np.array_equal(state.frame.color, before)
    after = state.frame.color.copy()
    assert state.views.history == (1, 0)             # six moves, one step
    assert state.views.undo() and state.frames.update()
    assert state.hand_view is None and np.array_equal(state.frame.color, before)
    assert state.views.history == (0, 1)
    assert state.views.redo() and state.frames.update()
    assert np.array_equal(state.frame.color, after)
    assert not state.views.redo()                    # nothing more to redo


def test_wheel_notches_in_quick_succession_are_one_step_and_a_click_to_the_next_view_another():
    state, hands = _state()
    first = state.views.current
    for _ in range(5):
        assert hands.wheel(1)
    assert state.views.history == (1, 0)
    dollied = state.views.current
    state.views.next_view()                                 # a click on the picture
    assert state.views.history == (2, 0) and state.view_index == 1
    assert state.views.undo() and state.views.current is dollied     # back across the click
    assert state.views.undo() and state.views.current is first
    assert not state.views.undo()


def test_a_new_move_after_undo_drops_the_redo_steps_and_another_scene_the_history():
    state, hands = _state()
    _drag(hands, 40, 30, 60, 35)
    state.views.undo()
    assert state.views.history == (0, 1)
    assert hands.fit()                                # a new change: the undone one is gone
    assert state.views.history == (1, 0)
    assert state.open_scene(SCENES_DIR / "cube.toml")
    assert state.views.history == (0, 0)


def test_on_an_animated_scene_the_users_camera_replaces_the_keyed_one_until_enter():
    state = ViewerState.open(SCENES_DIR / "robot_arm.toml", size=(80, 60))
    hands = CameraHands(state)
    assert state.playback is not None and not state.player.playing
    assert state.frames.update()
    keyed = state.frame.color.copy()
    assert hands.usable == ""
    _drag(hands, 40, 30, 60, 38)
    assert state.frames.update() and not np.array_equal(state.frame.color, keyed)
    assert state.views.label == "your camera (Enter: the scene's)"
    assert hands.wheel(2) and state.frames.update()                 # the wheel too
    moved = state.frame.color.copy()
    state.player.seek(0.5)                                   # the moment changes, not the camera
    assert state.frames.update() and state.views.current is state.hand_view
    assert hands.reset() and state.frames.update()           # Enter: the scene's camera again
    state.player.seek(0.0)
    assert state.frames.update() and np.array_equal(state.frame.color, keyed)
    assert not np.array_equal(moved, keyed)


def test_a_long_drag_on_the_cornell_box_keeps_the_box_in_view():
    # Its VRP is at the eye: turned about the VRP the camera looks away and the picture goes
    # black; about the scene's centre (the default) the box turns in front of it.
    for pivot, least, most in (("scene", 0.5, 1.0), ("vrp", 0.0, 0.05)):
        state = ViewerState.open(SCENES_DIR / "cornell_box.toml", size=(60, 60))
        state.choices.set_renderer("zbuffer")
        hands = CameraHands(state)
        hands.set_pivot(pivot)
        _drag(hands, 30, 30, 45, 30, steps=10)         # a quarter of the ball: ~60 degrees
        assert state.frames.update()
        covered = np.isfinite(state.frame.depth).mean()     # pixels the box is drawn at
        assert least <= covered <= most, (pivot, covered)
