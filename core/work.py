"""Long work that says how far it is and can be stopped between its chunks.

A loop that may run for seconds (a simulation stepping to a time, a frame traced band by
band, a volume marched ray chunk by ray chunk) calls :func:`report` between its chunks:
``report(what, done, total, unit)`` ("simulating the rigid bodies", 1200, 9600, "step").
Whoever started the work may be watching it on this thread (:func:`watching`): the command
line prints a progress line, the window updates its panel and raises to abandon a frame nobody
will see. A watcher that raises stops the work right there, between two chunks, so that what
was computed so far stays whole: a simulation stopped this way is at a step boundary and steps
on from it to the same numbers.

Compiled loops do not see Ctrl+C: Python raises KeyboardInterrupt only when the kernel returns.
So no one call may be long: the simulations call their kernels a step at a time, the tracers a
band of rays at a time. :func:`advance` groups a simulation's steps into chunks of about
``CHUNK_SECONDS`` (sized from the time the last chunk took) and reports between them.

Without a watcher, :func:`report` does nothing; no numbers depend on the chunking.
"""

from __future__ import annotations

import threading
import time
from contextlib import contextmanager
from typing import Callable

CHUNK_SECONDS = 0.15       # a chunk's aim: Ctrl+C and the window's cancel wait at most this
GROWTH = 4                 # a chunk is at most this many times the last (the first steps may
                           # be fast or slow: compiling, an empty world filling up)

Watcher = Callable[[str, float, float, str], None]
_local = threading.local()


def report(what: str, done: float, total: float, unit: str = "") -> None:
    """``what`` is at ``unit`` ``done`` of ``total`` (a step, a row, a ray): tell this
    thread's watcher, which may raise to stop the work here."""
    watcher = getattr(_local, "watcher", None)
    if watcher is not None:
        watcher(what, done, total, unit)


def describe(what: str, done: float, total: float, unit: str = "") -> str:
    """``simulating the rigid bodies: step 1,200 of 9,600``."""
    return f"{what}: {unit + ' ' if unit else ''}{done:,.0f} of {total:,.0f}"


@contextmanager
def watching(watcher: Watcher | None):
    """Within the block, :func:`report` on this thread calls ``watcher(what, done, total,
    unit)`` (None: nobody watches)."""
    before = getattr(_local, "watcher", None)
    _local.watcher = watcher
    try:
        yield watcher
    finally:
        _local.watcher = before


def next_chunk(steps: int, seconds: float, aim: float | None = None) -> int:
    """The steps of the next chunk after ``steps`` took ``seconds``: about ``aim`` seconds'
    worth (default CHUNK_SECONDS), growing at most GROWTH-fold, at least one."""
    aim = CHUNK_SECONDS if aim is None else aim
    if seconds <= 0.0:
        return max(1, steps * GROWTH)
    return max(1, min(steps * GROWTH, int(steps * aim / seconds)))


def advance(what: str, done: int, target: int, run: Callable[[int], None],
            unit: str = "step") -> int:
    """Take ``target - done`` steps as ``run(n)`` calls of about CHUNK_SECONDS each,
    reporting before the first and after each; returns ``target``. ``run(n)`` takes exactly
    n steps, so the steps are the same whatever the chunks."""
    report(what, done, target, unit)
    steps = 1
    while done < target:
        steps = min(steps, target - done)
        start = time.perf_counter()
        run(steps)
        done += steps
        report(what, done, target, unit)
        steps = next_chunk(steps, time.perf_counter() - start)
    return done


def control_watcher(control) -> Watcher:
    """A watcher for a job of the window (:mod:`core.progressive`'s control): stops the work
    once a newer request superseded it (``control.check`` raises) and shows how far it is."""
    def watch(what: str, done: float, total: float, unit: str = "") -> None:
        control.check()
        if total > 0:
            control.report(min(1.0, done / total), describe(what, done, total, unit))
    return watch
