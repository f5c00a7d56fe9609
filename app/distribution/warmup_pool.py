"""The warm-up's steps on every core: worker processes that each take the next step from one
queue, the longest steps first.

numba compiles on the calling thread and is not fork-safe with threads, so the workers are
started with multiprocessing's ``spawn`` method: fresh interpreters that import the warm-up
and build its step list themselves (a step is a closure, not something to send). The parent
puts the step labels on the queue in :func:`order`'s order and one ``None`` per worker after
them; each worker runs steps until it takes a ``None``. What a worker compiles goes to
numba's disk cache, where the other workers (and every later process) load it;
``core.jit.serialised_cache_saves`` keeps two processes saving the same kernel at once from
mixing up its cache files.

A worker says ``begin`` before a step and ``done`` (with the error, if it raised) after it.
A worker that dies in a step (a crash, a kill) fails that step and is replaced while steps
remain; a worker whose parent has gone exits at once (it watches the parent's sentinel), so
killing the warm-up leaves no process compiling on.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import queue
import signal
import threading
import time
import traceback
from dataclasses import dataclass
from typing import Callable, Iterable


def default_jobs() -> int:
    """The cores this process may run on (``os.cpu_count()`` where affinity is unknown)."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def order(labels: Iterable[str], costs: dict[str, float], default_cost: float,
          first: Callable[[str], bool] = lambda label: False,
          later: Callable[[str], bool] = lambda label: False) -> list[str]:
    """``labels`` longest first by ``costs`` (``default_cost`` for a label not measured): the
    ones ``first`` picks ahead of all others, the ones ``later`` picks after the rest. The
    sort is stable: steps of equal cost keep their listed order.

    ``later`` is for steps that mostly reuse kernels other steps compile (the shipped scenes
    after the renderers' own paths): a step's cost is what it compiled when it ran after
    those, and run before them it would compile them too, at the same time as the worker
    that compiles them anyway (measured: ``bezier.toml`` 44 s after the paths, 170 s
    beside them)."""
    labels = list(labels)
    return sorted(labels, key=lambda label: (not first(label), later(label),
                                             -costs.get(label, default_cost)))


@dataclass
class Outcome:
    """One finished step: its label, seconds, and the error (one line) or None."""
    label: str
    seconds: float
    error: str | None = None


# The steps a worker runs, named rather than imported: app.distribution.warmup starts this pool, so
# the pool finds its list by name in the worker process (no import cycle between the two).
STEPS = "app.distribution.warmup_steps:all_steps"
OPENING = "app.distribution.warmup_steps:opening_steps"     # (label, run) of one file's first picture


def _named(target: str):
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


def load_steps(extra: str | None, first: str | None = None):
    """(label, run) of every warm-up step, of ``extra`` (``module:function`` returning
    more of them; the tests' steps), and of the first picture of the file ``first``."""
    todo = _named(STEPS)()
    if extra:
        todo += _named(extra)()
    if first:
        todo += _named(OPENING)(first)
    return todo


def _exit_with_parent() -> None:
    """A daemon thread that ends this process the moment its parent has gone."""
    parent = multiprocessing.parent_process()
    if parent is None:
        return
    from multiprocessing.connection import wait

    def watch():
        wait([parent.sentinel])
        os._exit(3)
    threading.Thread(target=watch, name="exit with the warm-up", daemon=True).start()


def one_line(error: BaseException) -> str:
    """``Type: message (file:line)`` of the innermost frame: one line that names the error."""
    where = ""
    frames = traceback.extract_tb(error.__traceback__)
    if frames:
        where = f" ({os.path.basename(frames[-1].filename)}:{frames[-1].lineno})"
    message = " ".join(str(error).split()) or "(no message)"
    return f"{type(error).__name__}: {message}{where}"


def _worker(tasks, results, extra: str | None, first: str | None = None) -> None:
    """Run the steps the queue hands out, until a ``None``."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)       # the parent decides; it terminates us
    _exit_with_parent()
    try:
        todo = dict(load_steps(extra, first))
    except BaseException as error:                     # noqa: BLE001  (reported, not raised)
        results.put(("broken", os.getpid(), one_line(error)))
        return
    while True:
        label = tasks.get()
        if label is None:
            return
        results.put(("begin", os.getpid(), label))
        start = time.perf_counter()
        try:
            todo[label]()
            error = None
        except Exception as failure:                   # noqa: BLE001  (one line per step)
            error = one_line(failure)
        results.put(("done", os.getpid(), (label, time.perf_counter() - start, error)))


def run_parallel(labels: list[str], jobs: int, *, extra: str | None = None,
                 first: str | None = None,
                 on_begin: Callable[[str], None] = lambda label: None,
                 on_outcome: Callable[[Outcome], None] = lambda outcome: None) -> list[Outcome]:
    """Run the steps ``labels`` (in that order off the queue) on ``jobs`` worker processes;
    ``on_begin(label)`` when a worker takes one, ``on_outcome(outcome)`` when it ends. On
    KeyboardInterrupt (SIGINT, or SIGTERM turned into it by the caller) the workers are
    terminated before it propagates."""
    pool = _Pool(labels, jobs, extra, first, on_begin, on_outcome)
    try:
        while not pool.done():
            try:
                pool.handle(pool.results.get(timeout=0.5))
                continue
            except queue.Empty:
                pass
            pool.replace_dead_workers()
            if not pool.done() and not any(w.is_alive() for w in pool.workers):
                pool.fail_the_rest("no worker process is left to run it")
    finally:
        pool.close()
    return [pool.outcomes[label] for label in labels]


class _Pool:
    """The queue of steps, its worker processes, and what each step came to."""

    def __init__(self, labels, jobs, extra, first, on_begin, on_outcome):
        self.context = multiprocessing.get_context("spawn")
        self.tasks, self.results = self.context.Queue(), self.context.Queue()
        self.labels, self.extra, self.first = labels, extra, first
        self.on_begin, self.on_outcome = on_begin, on_outcome
        jobs = max(1, min(jobs, len(labels)))
        for label in labels:
            self.tasks.put(label)
        for _ in range(jobs):
            self.tasks.put(None)
        self.workers = [self.start() for _ in range(jobs)] if labels else []
        self.running: dict[int, str] = {}              # pid → the label it is on
        self.outcomes: dict[str, Outcome] = {}

    def start(self):
        worker = self.context.Process(target=_worker,
                                      args=(self.tasks, self.results, self.extra, self.first),
                                      name="warm-up worker", daemon=True)
        worker.start()
        return worker

    def done(self) -> bool:
        return len(self.outcomes) >= len(self.labels)

    def finish(self, outcome: Outcome) -> None:
        self.outcomes[outcome.label] = outcome
        self.on_outcome(outcome)

    def fail_the_rest(self, why: str) -> None:
        for label in self.labels:
            if label not in self.outcomes:
                self.finish(Outcome(label, 0.0, why))

    def handle(self, message) -> None:
        kind, pid, payload = message
        if kind == "begin":
            self.running[pid] = payload
            self.on_begin(payload)
        elif kind == "done":
            self.running.pop(pid, None)
            self.finish(Outcome(*payload))
        elif kind == "broken":                         # it could not even list the steps
            self.fail_the_rest(f"the worker could not start: {payload}")

    def replace_dead_workers(self) -> None:
        """A worker that died: its step failed, and a new worker takes the steps still queued."""
        for k, worker in enumerate(self.workers):
            if worker.is_alive() or worker.exitcode == 0:
                continue
            while True:                                # what it said before it died
                try:
                    self.handle(self.results.get_nowait())
                except queue.Empty:
                    break
            label = self.running.pop(worker.pid, None)
            if label is not None and label not in self.outcomes:
                self.finish(Outcome(label, 0.0, f"the worker process died (exit code "
                                                f"{worker.exitcode})"))
            if not self.done():
                self.workers[k] = self.start()         # for the steps still queued

    def close(self) -> None:
        for worker in self.workers:
            if worker.is_alive():
                worker.terminate()
        for worker in self.workers:
            worker.join(timeout=5)
            if worker.is_alive():
                worker.kill()
                worker.join(timeout=5)
        for q in (self.tasks, self.results):
            q.close()
            q.cancel_join_thread()
