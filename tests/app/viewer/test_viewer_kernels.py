"""The window's kernel gate (app/viewer/kernels.py) while the warm-up compiles elsewhere.

A frame whose kernels are cached is drawn at once; one that would compile waits, saying so,
until the warm-up has done its scene, then is drawn; a newer request ends the wait; once the
warm-up has finished nothing is refused. The warm-up here is a stand-in with the same
attributes as app.distribution.warmup.BackgroundWarmup, driven by the test (a consistency check of
the gate's logic, not of the processes: tests/app/distribution/test_warmup_*.py hold those).
"""

from __future__ import annotations

import threading

import numba
import pytest

from app.viewer.kernels import KernelsNotReady, compiles_refused, gated, status
from app.viewer.worker import Cancelled


class FakeWarmup:
    """What the gate reads of a BackgroundWarmup; ``ready`` scenes and ``finished`` are set
    by the test (or by ``on_wait`` when the gate waits)."""

    def __init__(self, total=10, on_wait=None):
        self.total, self.done, self.current = total, 0, []
        self.finished, self.ok, self.failed = False, True, []
        self.ready: set = set()             # files whose first picture is compiled
        self.ready_all: set = set()         # files whose every-setting step is done
        self.waits: list = []
        self.on_wait = on_wait

    def ready_for(self, scene, every_setting=False):
        return self.finished or scene in self.ready_all or (
            not every_setting and scene in self.ready)

    def wait_for(self, scene, timeout, every_setting=False):
        self.waits.append(scene if not every_setting else (scene, "every setting"))
        if self.on_wait is not None:
            self.on_wait(self, self.waits[-1])

    def wait(self, timeout):
        self.waits.append(None)
        if self.on_wait is not None:
            self.on_wait(self, None)


class FakeControl:
    def __init__(self, cancel_after=None):
        self.reports, self.checks, self.cancel_after = [], 0, cancel_after

    def check(self):
        self.checks += 1
        if self.cancel_after is not None and self.checks > self.cancel_after:
            raise Cancelled("superseded")

    def report(self, fraction, detail):
        self.reports.append((fraction, detail))


def fresh_kernel():
    """A kernel no process has compiled: its first call compiles (a numba:compile event)."""
    @numba.njit
    def add_one(x):
        return x + 1
    return add_one


def test_a_compile_is_refused_inside_the_block_only():
    kernel = fresh_kernel()
    with compiles_refused():
        with pytest.raises(KernelsNotReady, match="add_one"):
            kernel(1)
    assert kernel(1) == 2                         # outside it compiles as usual
    with compiles_refused():
        assert kernel(2) == 3                     # and, compiled, is not refused again


def test_refusal_is_per_thread():
    kernel, result = fresh_kernel(), []
    with compiles_refused():
        thread = threading.Thread(target=lambda: result.append(kernel(5)))
        thread.start()
        thread.join()
    assert result == [6]


def test_a_frame_that_needs_no_kernel_is_drawn_at_once():
    warmup = FakeWarmup()
    control = FakeControl()
    assert gated(lambda c: "frame", warmup, "house.toml")(control) == "frame"
    assert warmup.waits == [] and control.reports == []


def test_a_frame_waits_for_its_scenes_steps_then_draws():
    kernel = fresh_kernel()
    tries = []

    def run(control):
        tries.append(1)
        return kernel(41)

    def on_wait(warmup, scene):
        warmup.done += 1
        if warmup.done == 3:                      # the scene's steps are done: "compile" it
            warmup.ready.add("torus.toml")
            kernel.compile("int64(int64)")        # as the worker processes' cache would hold

    warmup = FakeWarmup(on_wait=on_wait)
    control = FakeControl()
    assert gated(run, warmup, "torus.toml")(control) == 42
    assert len(tries) == 2 and warmup.waits == ["torus.toml"] * 3
    fraction, detail = control.reports[-1]
    assert fraction == pytest.approx(0.2) and "add_one" in detail and "2 of 10" in detail


def test_a_kernel_the_scenes_steps_did_not_make_waits_for_the_whole_warm_up():
    kernel = fresh_kernel()

    def on_wait(warmup, waited):
        if waited is None:                        # waiting for everything now
            warmup.finished = True
        elif isinstance(waited, tuple):           # its every-setting step done: still missing
            warmup.ready_all.add(waited[0])
        else:
            warmup.ready.add(waited)              # its first picture done, yet still missing

    warmup = FakeWarmup(on_wait=on_wait)
    assert gated(lambda c: kernel(1), warmup, "odd.obj")(FakeControl()) == 2
    # its first picture, then its every setting, then everything; then compiled here
    assert warmup.waits == ["odd.obj", ("odd.obj", "every setting"), None]


def test_a_frame_without_a_file_waits_for_the_whole_warm_up():
    kernel = fresh_kernel()

    def on_wait(warmup, waited):
        warmup.finished = True

    warmup = FakeWarmup(on_wait=on_wait)
    assert gated(lambda c: kernel(1), warmup, None)(FakeControl()) == 2
    assert warmup.waits == [None]


def test_a_newer_request_ends_the_wait():
    kernel = fresh_kernel()
    warmup = FakeWarmup()                         # never ready
    with pytest.raises(Cancelled):
        gated(lambda c: kernel(1), warmup, "torus.toml")(FakeControl(cancel_after=2))
    assert len(warmup.waits) == 2


def test_after_the_warm_up_nothing_is_refused():
    kernel = fresh_kernel()
    warmup = FakeWarmup()
    warmup.finished = True
    assert gated(lambda c: kernel(1), warmup, "torus.toml")(FakeControl()) == 2


def test_status_lines():
    warmup = FakeWarmup(total=12)
    warmup.done, warmup.current = 5, ["terrain.toml"]
    assert status(warmup) == ("compiling kernels in worker processes: 5 of 12 steps "
                              "(terrain.toml)")
    warmup.finished = True
    assert status(warmup) == "all kernels ready"
    warmup.ok, warmup.failed = False, ["step terrain.toml: ValueError: boom"]
    assert status(warmup).startswith("kernel warm-up failed (step terrain.toml: ValueError")
    assert status(None) == ""
