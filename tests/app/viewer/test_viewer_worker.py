"""The window's render worker: frames off the UI thread, the newest request wins."""

from __future__ import annotations

import threading
import time

from app.viewer.worker import RenderWorker


def _wait(worker, timeout=10.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        result = worker.collect()
        if result is not None:
            return result
        time.sleep(0.01)
    raise AssertionError("no result")


def test_a_newer_request_supersedes_a_waiting_and_a_running_one():
    started, release, ran = threading.Event(), threading.Event(), []

    def slow():
        ran.append("slow")
        started.set()
        release.wait(5)
        return "slow frame"

    worker = RenderWorker()
    worker.submit(slow, "slow")
    assert started.wait(5)
    worker.submit(lambda: ran.append("stale") or "stale frame", "stale")   # still waiting ...
    worker.submit(lambda: ran.append("new") or "new frame", "new")         # ... replaced
    assert worker.waiting and worker.progress().what == "slow" and worker.progress().frame
    release.set()
    result = _wait(worker)
    assert result.frame == "new frame" and ran == ["slow", "new"]   # the stale one never ran
    assert worker.collect() is None and not worker.waiting
    worker.stop()


def test_errors_come_back_and_background_jobs_wait_for_frames():
    order = []
    worker = RenderWorker()
    gate = threading.Event()
    worker.add_background([("warm 1", lambda: gate.wait(5) and order.append("warm 1")),
                           ("warm 2", lambda: order.append("warm 2"))])
    time.sleep(0.1)                       # warm 1 is running
    worker.submit(lambda: order.append("frame") or 1 / 0, "broken")
    gate.set()
    result = _wait(worker)
    assert isinstance(result.error, ZeroDivisionError)
    deadline = time.monotonic() + 5
    while worker.progress().done < 2 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert order == ["warm 1", "frame", "warm 2"] and worker.progress().total == 2
    worker.stop()
