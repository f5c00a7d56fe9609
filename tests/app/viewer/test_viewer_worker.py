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


def _slow_job(name, started, release, ran):
    def job():
        ran.append(name)
        started.set()
        release.wait(5)
        return name + " frame"
    return job


def test_a_picture_a_newer_request_overtook_is_still_shown_but_never_after_a_newer_one():
    # A camera that moves faster than frames are drawn: each finished frame is shown as it
    # comes (the window would otherwise show nothing until the drag stops), in order.
    started, release, ran = threading.Event(), threading.Event(), []
    worker = RenderWorker()
    try:
        first = worker.submit(_slow_job("first", started, release, ran), "first")
        assert started.wait(5)
        second = worker.submit(lambda: ran.append("second") or "second frame", "second")
        release.set()
        shown = []
        deadline = time.monotonic() + 10
        while len(shown) < 2 and time.monotonic() < deadline:
            result = worker.collect()
            if result is not None:
                shown.append((result.generation, result.frame))
            time.sleep(0.001)
        # the overtaken frame came first (it may be skipped if the newer one finished before
        # it was collected, but it never comes after the newer one)
        assert shown[-1] == (second, "second frame")
        assert all(g == first for g, _ in shown[:-1])
        assert worker.collect() is None and not worker.waiting
    finally:
        worker.stop()


def test_an_older_result_waiting_is_never_collected_after_a_newer_one():
    worker = RenderWorker()
    try:
        g = worker.submit(lambda: "a", "a")
        result = _wait(worker)
        assert result.generation == g and result.frame == "a"
        from app.viewer.worker import Result
        worker._post(Result(g - 1, "older", "older frame"))        # late, from before "a"
        assert worker.collect() is None
    finally:
        worker.stop()


def test_another_scenes_request_drops_the_old_scenes_picture():
    started, release, ran = threading.Event(), threading.Event(), []
    worker = RenderWorker()
    try:
        worker.submit(_slow_job("old scene", started, release, ran), "old scene")
        assert started.wait(5)
        worker.submit(lambda: "new scene frame", "new scene", keep_older=False)
        release.set()
        assert _wait(worker).frame == "new scene frame"     # the old scene's never shows
        assert ran == ["old scene"]
    finally:
        worker.stop()
