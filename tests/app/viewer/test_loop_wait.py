"""How the window's loop waits (app.viewer.loop.FrameLoop._wait): a camera drag whose frame
has not come sleeps until the next event or the redraw deadline, instead of polling (polling
there spun 600 times a second under Xvfb and took a third of a core from the renderer)."""

from __future__ import annotations

import time
from types import SimpleNamespace

from app.viewer import loop


def _loop(monkeypatch, calls):
    monkeypatch.setattr(loop.glfw, "poll_events", lambda: calls.append(("poll",)))
    monkeypatch.setattr(loop.glfw, "wait_events_timeout",
                        lambda seconds: calls.append(("wait", seconds)))
    win = SimpleNamespace(busy=3, hands=SimpleNamespace(drag=SimpleNamespace(start=(10, 20))),
                          worker=SimpleNamespace(waiting=True), tools=SimpleNamespace(busy=False))
    frames = loop.FrameLoop.__new__(loop.FrameLoop)
    frames.win, frames.state = win, SimpleNamespace(dirty=True, playing=False)
    frames._picture_new, frames._swapped_at = False, time.perf_counter()
    frames._input_waits = False
    return frames


def test_a_drag_waiting_for_its_frame_sleeps_until_the_redraw_deadline(monkeypatch):
    calls = []
    frames = _loop(monkeypatch, calls)
    frames._wait(True)
    (kind, seconds), = calls
    assert kind == "wait" and 0 < seconds <= loop.GESTURE_REDRAW_S


def test_a_new_picture_or_no_drag_is_drawn_at_once_as_before(monkeypatch):
    calls = []
    frames = _loop(monkeypatch, calls)
    frames._picture_new = True                  # the frame came: draw it now
    frames._wait(True)
    frames._picture_new = False
    frames.win.hands.drag = None                # no gesture: the frames after an event
    frames._wait(True)
    frames._swapped_at -= 1.0                   # past the deadline: redrawn
    frames.win.hands.drag = SimpleNamespace(start=(10, 20))
    frames._wait(True)
    assert calls == [("poll",)] * 3


def test_a_key_whose_picture_is_on_its_way_waits_for_it_too(monkeypatch):
    calls = []
    frames = _loop(monkeypatch, calls)
    frames.win.hands.drag = None
    frames._input_waits = True                  # a shading key asked for a new picture
    frames._wait(True)
    frames._swapped_at -= 1.0                   # past the deadline: redrawn
    frames._wait(True)
    (kind, seconds), poll = calls
    assert kind == "wait" and 0 < seconds <= loop.GESTURE_REDRAW_S and poll == ("poll",)
