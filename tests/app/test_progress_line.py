"""The progress line of long commands (app.progress_line), on a clock the test moves."""

from __future__ import annotations

import io

from app.progress_line import PLAIN_EVERY, REDRAW, SHOW_AFTER, ProgressLine, duration


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


class Terminal(io.StringIO):
    def isatty(self):
        return True


def line(stream=None, quiet=False):
    clock = Clock()
    return ProgressLine(stream or io.StringIO(), quiet=quiet, clock=clock), clock


def test_nothing_is_shown_before_the_command_has_run_a_while():
    progress, clock = line()
    progress("simulating the rigid bodies", 10, 1000, "step")
    clock.now += SHOW_AFTER / 2
    progress("simulating the rigid bodies", 20, 1000, "step")
    assert progress.stream.getvalue() == ""


def test_a_plain_line_says_what_how_far_how_long_and_what_is_left():
    progress, clock = line()
    progress("simulating the rigid bodies", 0, 1000, "step")
    clock.now += 2.0
    progress("simulating the rigid bodies", 250, 1000, "step")
    assert progress.stream.getvalue() == ("simulating the rigid bodies: step 250 of 1,000 "
                                          "(25 %); 2 s, about 6 s left\n")


def test_plain_lines_are_occasional():
    progress, clock = line()
    for k in range(200):                              # a report every 0.1 s for 20 s
        clock.now += 0.1
        progress("ray tracing", k, 200, "row")
    lines = progress.stream.getvalue().splitlines()
    assert len(lines) == 1 + int((20 - SHOW_AFTER) // PLAIN_EVERY)
    assert all(text.startswith("ray tracing: row ") for text in lines)


def test_on_a_terminal_one_line_is_redrawn_in_place_a_few_times_a_second():
    progress, clock = line(Terminal())
    for k in range(80):                               # a report every 1/16 s for 5 s
        clock.now += 0.0625
        progress("ray marching", k, 100, "ray")
    out = progress.stream.getvalue()
    assert "\n" not in out
    draws = out.split("\r\x1b[K")[1:]
    assert len(draws) == (5 - SHOW_AFTER) / REDRAW + 1           # from 1.5 s on, every 0.25 s
    assert draws[-1] == "ray marching: ray 79 of 100 (79 %); 5 s, about 1 s left"
    progress.say("note: a line that stays")
    assert progress.stream.getvalue().endswith("\r\x1b[Knote: a line that stays\n")


def test_a_line_longer_than_the_terminal_is_cut_so_that_it_can_be_rewritten(monkeypatch):
    import os
    import shutil
    monkeypatch.setattr(shutil, "get_terminal_size", lambda *a: os.terminal_size((40, 24)))
    progress, clock = line(Terminal())
    clock.now += 2.0
    progress("simulating the rigid bodies", 5, 10, "step")
    assert progress.stream.getvalue() == "\r\x1b[K" + "simulating the rigid bodies: step 5 ..."  # 39


def test_quiet_shows_nothing():
    progress, clock = line(quiet=True)
    progress("simulating the actors", 0, 10, "step")
    clock.now += 60
    progress("simulating the actors", 5, 10, "step")
    assert progress.stream.getvalue() == ""


def test_nested_works_share_the_line_and_an_outer_report_ends_the_inner_ones():
    progress, clock = line()
    progress("rendering the frames", 0, 90, "frame")
    progress("simulating the rigid bodies", 0, 240, "step")
    clock.now += 20.0
    progress("simulating the rigid bodies", 120, 240, "step")
    assert progress.stream.getvalue().splitlines()[-1] == (
        "rendering the frames: frame 0 of 90 (0 %); simulating the rigid bodies: step 120 of "
        "240 (50 %); 20 s")
    clock.now += 20.0
    progress("rendering the frames", 3, 90, "frame")
    assert progress.stream.getvalue().splitlines()[-1] == (
        "rendering the frames: frame 3 of 90 (3 %); 40 s, about 19 min left")
    assert progress.doing() == "rendering the frames: frame 3 of 90"


def test_the_stop_line_says_what_ran_for_how_long_and_what_stays():
    progress, clock = line()
    progress("ray tracing", 0, 3000, "row")
    clock.now += 12.0
    progress("ray tracing", 1200, 3000, "row")
    assert progress.stopped("nothing was written") == (
        "stopped by Ctrl+C after 12 s (ray tracing: row 1,200 of 3,000): nothing was written")
    progress("ray tracing", 3000, 3000, "row")               # done: it leaves the line
    assert progress.stopped() == "stopped by Ctrl+C after 12 s"


def test_durations_read_as_a_person_says_them():
    assert [duration(s) for s in (4.4, 99, 100, 5999, 6000, 36000)] == [
        "4 s", "99 s", "2 min", "100 min", "1.7 h", "10.0 h"]
