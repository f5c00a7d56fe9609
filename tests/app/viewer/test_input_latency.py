"""From an input to the picture that shows it: the window's bookkeeping
(app.viewer.latency) with hand-worked times, and the window bench reading its log lines."""

from __future__ import annotations

import pytest

from app.bench.window_bench import markdown, pictures_between
from app.viewer.latency import InputLatency


def test_the_wait_runs_from_the_first_input_of_the_batch_to_the_swap():
    latency = InputLatency()
    latency.input(1.0)
    latency.input(1.2)                  # the same batch: the first counts
    assert latency.requested(5)         # an input waits for request 5's picture
    latency.drawn(dirty=False)
    assert latency.shown(5, 1.5) == pytest.approx(0.5)
    assert latency.shown(5, 1.7) is None        # a refinement answers no new input


def _two_requests() -> InputLatency:
    """Two turns of the loop, each an input and its request: 1.0 s asks 5, 1.1 s asks 6."""
    latency = InputLatency()
    for at, generation in ((1.0, 5), (1.1, 6)):
        latency.input(at)
        latency.requested(generation)
        latency.drawn(dirty=False)
    return latency


def test_a_newer_picture_answers_the_older_requests_too():
    latency = _two_requests()
    assert latency.shown(6, 1.4) == pytest.approx(0.4)     # from 1.0: the oldest it answers
    assert latency.shown(5, 1.5) is None                   # overtaken: already answered


def test_pictures_in_order_each_answer_their_own_request():
    latency = _two_requests()
    assert latency.shown(5, 1.3) == pytest.approx(0.3)
    assert latency.shown(6, 1.5) == pytest.approx(0.4)


def test_inputs_that_changed_nothing_do_not_start_the_clock():
    latency = InputLatency()
    latency.input(2.0)                  # a key that changed nothing
    latency.drawn(dirty=False)
    assert not latency.requested(6)     # a request no input asked for (the movie's clock)
    latency.input(3.0)
    latency.requested(7)
    latency.drawn(dirty=False)
    assert latency.shown(7, 3.1) == pytest.approx(0.1)


def test_a_change_that_waited_for_its_request_keeps_its_time():
    latency = InputLatency()
    latency.input(4.0)
    latency.drawn(dirty=True)           # changed, but no request this turn (a picture of 0 px)
    latency.input(4.5)
    latency.requested(8)
    latency.drawn(dirty=False)
    assert latency.shown(8, 5.0) == pytest.approx(1.0)


def test_the_window_bench_reads_the_on_screen_lines():
    own = "on screen: request 3, the window's own"
    events = [(100.0, "frame 3: view 1 render=20.5ms"),
              (110.0, f"{own} 6.2 ms (CPU 3.0 ms, swap 1.0 ms), 45 ms after the input"),
              (140.0, "partial frame: trace (pass 1)"),
              (141.0, f"{own} 4.0 ms (CPU 2.0 ms, swap 1.0 ms)"),
              (170.0, f"{own} 5.0 ms (CPU 2.5 ms, swap 1.0 ms), 75 ms after the input"),
              (900.0, f"{own} 50.0 ms (CPU 9.0 ms, swap 1.0 ms), 900 ms after the input")]
    row = pictures_between(events, 90.0, 200.0)
    assert row["pictures"] == 2
    assert row["window_median_ms"] == pytest.approx(5.0)
    assert row["window_cpu_median_ms"] == pytest.approx(2.5)
    assert row["latency_median_ms"] == pytest.approx(60.0)
    assert row["latency_worst_ms"] == pytest.approx(75.0)
    table = markdown({"rows": [{"case": "c", "size": [5, 5], "kind": "orbit", **row}],
                      "load_before": (1.0,), "load_after": (1.0,)})
    assert "| 60 ms (75 ms) | 5.0 ms (2.5 ms) |" in table
