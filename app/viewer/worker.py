"""Frames rendered off the window's thread, newest request first.

The window asks for a frame (:meth:`RenderWorker.submit`) and keeps drawing; one background
thread renders it. A request made while another is waiting replaces it (a stale request is
never rendered). A picture finished after a newer request was made is still shown when it is
newer than the one on screen (:meth:`RenderWorker.collect` never goes back in time): while a
drag moves the camera faster than frames are drawn, the window shows each frame as it comes
and the worker draws the newest camera next, instead of showing nothing until the drag stops.
A request made with ``keep_older=False`` (another scene) drops every older picture, so the old
scene never flashes up after the new one was asked for. The picture always ends up showing the
latest choice. While nothing is asked, the thread works through background jobs (the kernels'
warm-up), one short job at a time, so that a frame request waits at most for one of them.

A job submitted with ``control=True`` is called with a :class:`Control`: it can report how far
it is (the progress line), hand over pictures before it is done (:meth:`Control.partial`: the
ray tracer's coarse pass and each refined tile, collected like a finished frame but marked
``final=False``) and learn that a newer request has superseded it (:attr:`Control.cancelled`,
or :meth:`Control.check`, which raises :class:`Cancelled`), so that a long frame stops at its
next tile instead of finishing a picture nobody will see.

No GL here: a job returns a :class:`core.render.Frame` (or raises), and the window thread
uploads it. ``wake`` (glfw.post_empty_event in the window) is called when a result is ready,
so that a window asleep in ``wait_events`` picks it up at once.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass, field
from typing import Callable


@dataclass
class Job:
    """One frame to render: ``run()`` returns the frame; ``what`` is shown while it runs."""

    run: Callable
    what: str
    generation: int = 0
    control: bool = False       # call run(Control) instead of run()
    posted: bool = False        # has it handed over a picture yet?


@dataclass
class Result:
    generation: int
    what: str
    frame: object | None = None
    error: BaseException | None = None
    seconds: float = 0.0
    final: bool = True          # False: a picture on the way (more follow for this request)


class Cancelled(Exception):
    """Raised inside a job by :meth:`Control.check` once a newer request superseded it."""


class Control:
    """What a running job may ask of the worker (given to jobs submitted with control=True)."""

    def __init__(self, worker: "RenderWorker", job: Job):
        self._worker, self._job = worker, job
        self._start = time.perf_counter()

    @property
    def cancelled(self) -> bool:
        """Has a newer request (or the window's closing) made this job's picture stale?"""
        return self._worker._superseded(self._job)

    def check(self) -> None:
        if self.cancelled:
            raise Cancelled(self._job.what)

    def report(self, fraction: float, detail: str) -> None:
        """How far the job is (0..1) and what it does now, for the progress line."""
        self._worker._report(self._job, fraction, detail)

    def partial(self, frame) -> None:
        """A picture before the final one; the window shows it when it collects it. Once the
        job is superseded only its first picture is still taken (a coarse picture drawn for a
        moving camera); the refinements of an abandoned frame are not."""
        self._worker._post(Result(self._job.generation, self._job.what, frame,
                                  seconds=time.perf_counter() - self._start, final=False),
                           self._job)


@dataclass
class Progress:
    """What the worker is doing now, for the status line."""

    what: str = ""
    since: float = 0.0
    frame: bool = False         # is the job running now a frame (not a background job)?
    done: int = 0               # background jobs done / total (the warm-up)
    total: int = 0
    background: list = field(default_factory=list)
    fraction: float | None = None   # how far the running frame is, when its job reports it
    detail: str = ""                # what it does now ("tile 40 of 256", "simulating …")


class RenderWorker:
    """One daemon thread; ``submit`` a :class:`Job`, ``collect`` its :class:`Result`."""

    def __init__(self, wake: Callable[[], None] = lambda: None):
        self._wake = wake
        self._lock = threading.Condition()
        self._pending: Job | None = None
        self._result: Result | None = None
        self._background: list[tuple[str, Callable]] = []
        self._generation = 0
        self._floor = 0                 # results older than this generation are never shown
        self._collected = 0             # the generation of the newest result collected
        self._running: str = ""
        self._since = 0.0
        self._done = 0
        self._total = 0
        self._fraction: float | None = None
        self._detail = ""
        self._stop = False
        self._thread = threading.Thread(target=self._loop, name="render", daemon=True)
        self._thread.start()

    # -- the window's side ---------------------------------------------------------------
    def submit(self, run: Callable, what: str, control: bool = False,
               keep_older: bool = True) -> int:
        """Ask for a frame; replaces any request still waiting and cancels a running one
        that watches its :class:`Control`. Until it arrives, the running one's picture may
        still be shown, unless ``keep_older`` is False. Returns its generation."""
        with self._lock:
            self._generation += 1
            if not keep_older:
                self._floor = self._generation
                if self._result is not None and self._result.generation < self._floor:
                    self._result = None
            self._pending = Job(run, what, self._generation, control)
            self._lock.notify()
            return self._generation

    def add_background(self, jobs: list[tuple[str, Callable]]) -> None:
        """Jobs to run while no frame is asked for (label, callable), in order."""
        with self._lock:
            self._background.extend(jobs)
            self._total += len(jobs)
            self._lock.notify()

    def collect(self) -> Result | None:
        """The newest picture not yet collected, or None. A result of an older request than
        one already collected, or from before a ``keep_older=False`` request, is dropped."""
        with self._lock:
            result, self._result = self._result, None
            if result is None or result.generation < max(self._floor, self._collected):
                return None
            self._collected = result.generation
            return result

    @property
    def waiting(self) -> bool:
        """Is a frame request not yet collected (queued, running, or done but not shown)?"""
        with self._lock:
            return self._pending is not None or self._running.startswith("frame:") or (
                self._result is not None and self._result.generation == self._generation)

    def progress(self) -> Progress:
        with self._lock:
            return Progress(self._running.removeprefix("frame:"), self._since,
                            self._running.startswith("frame:"), self._done, self._total,
                            fraction=self._fraction, detail=self._detail)

    def stop(self) -> None:
        with self._lock:
            self._stop = True
            self._lock.notify()

    # -- the thread's side ---------------------------------------------------------------
    def _superseded(self, job: Job) -> bool:
        with self._lock:
            return self._stop or job.generation != self._generation

    def _report(self, job: Job, fraction: float, detail: str) -> None:
        with self._lock:
            if job.generation == self._generation:
                self._fraction, self._detail = float(fraction), detail
        self._wake()

    def _post(self, result: Result, job: Job | None = None) -> None:
        with self._lock:
            self._keep(result, job)
        self._wake()

    def _keep(self, result: Result, job: Job | None) -> None:
        """(The lock held.) Keep ``result`` for :meth:`collect` unless a newer one waits there,
        it is older than the floor, or its job, superseded, already handed over a picture."""
        first = job is None or not job.posted
        if job is not None:
            job.posted = True
        superseded = result.generation != self._generation
        waiting = self._result.generation if self._result is not None else 0
        if (result.generation >= max(self._floor, waiting, self._collected)
                and not (superseded and not first)):
            self._result = result

    def _next(self):
        with self._lock:
            while not self._stop and self._pending is None and not self._background:
                self._lock.wait()
            if self._stop:
                return None
            if self._pending is not None:
                job, self._pending = self._pending, None
                self._running, self._since = "frame:" + job.what, time.perf_counter()
                self._fraction, self._detail = None, ""
                return job
            label, run = self._background.pop(0)
            self._running, self._since = label, time.perf_counter()
            return Job(run, label, generation=-1)

    def _loop(self) -> None:
        while True:
            job = self._next()
            if job is None:
                return
            start = time.perf_counter()
            result = Result(job.generation, job.what)
            try:
                result.frame = job.run(Control(self, job)) if job.control else job.run()
            except Cancelled:                       # superseded: its picture is not wanted
                result = None
            except BaseException as error:          # shown by the window, never fatal here
                result.error = error
            if result is None:
                with self._lock:
                    self._running = ""
                continue
            result.seconds = time.perf_counter() - start
            if job.generation < 0 and result.error is not None:
                logging.getLogger("fvd").warning("background job %r failed: %s: %s", job.what,
                                                 type(result.error).__name__, result.error)
            with self._lock:
                self._running = ""      # and its result kept at once: never "not waiting"
                if job.generation < 0:
                    self._done += 1
                else:
                    self._keep(result, job if result.error is None else None)
            self._wake()
