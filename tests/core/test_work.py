"""core.work: long work stepped in chunks and reported between them, stopped by its watcher."""

from __future__ import annotations

import pytest

from core import work


class Stop(Exception):
    pass


def test_advance_takes_exactly_the_steps_asked_for_in_growing_chunks(monkeypatch):
    # every chunk "takes no time": each is GROWTH times the last, cut at the target
    monkeypatch.setattr(work.time, "perf_counter", lambda: 0.0)
    chunks, seen = [], []
    with work.watching(lambda *report: seen.append(report)):
        assert work.advance("counting", 5, 200, chunks.append) == 200
    assert chunks == [1, 4, 16, 64, 110]
    assert sum(chunks) == 195
    assert [done for _, done, _, _ in seen] == [5, 6, 10, 26, 90, 200]
    assert {(what, total, unit) for what, _, total, unit in seen} == {("counting", 200, "step")}


def test_a_chunk_is_sized_to_the_aim_from_the_last_ones_time():
    assert work.next_chunk(10, 0.5, aim=0.15) == 3          # slower than the aim: fewer
    assert work.next_chunk(10, 0.15, aim=0.15) == 10
    assert work.next_chunk(10, 0.001, aim=0.15) == 10 * work.GROWTH   # growth is capped
    assert work.next_chunk(1, 10.0, aim=0.15) == 1          # never none


def test_a_watcher_that_raises_stops_the_work_between_two_chunks(monkeypatch):
    monkeypatch.setattr(work.time, "perf_counter", lambda: 0.0)
    taken = []

    def watcher(what, done, total, unit):
        if done >= 20:
            raise Stop

    with pytest.raises(Stop), work.watching(watcher):
        work.advance("counting", 0, 10_000, taken.append)
    assert sum(taken) == 21                          # 1 + 4 + 16: stopped after a whole chunk


def test_reports_go_to_this_threads_watcher_only_inside_the_block():
    import threading
    seen = []
    with work.watching(lambda *report: seen.append(report)):
        work.report("here", 1, 2, "row")
        other = threading.Thread(target=work.report, args=("elsewhere", 1, 2))
        other.start()
        other.join()
        with work.watching(None):                    # an inner block nobody watches
            work.report("hidden", 1, 2)
    work.report("after", 2, 2)
    assert seen == [("here", 1, 2, "row")]


def test_the_windows_watcher_checks_its_control_then_reports_the_share_done():
    class Control:
        def __init__(self):
            self.reports, self.cancelled = [], False

        def check(self):
            if self.cancelled:
                raise Stop

        def report(self, fraction, detail):
            self.reports.append((fraction, detail))

    control = Control()
    watch = work.control_watcher(control)
    watch("simulating the actors", 30, 120, "step")
    assert control.reports == [(0.25, "simulating the actors: step 30 of 120")]
    control.cancelled = True
    with pytest.raises(Stop):
        watch("simulating the actors", 60, 120, "step")
    assert len(control.reports) == 1
