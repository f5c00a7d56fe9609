"""Cheap warm-up steps for the tests of ``python -m app warmup`` (``--extra-steps
tests.warmup_steps:steps``, chosen with ``--only``): a small kernel compiled into numba's
cache, a step that waits for a kill, one that fails, and two that can only finish together.

Where a step needs a folder (to say it has started, or to meet the other), it is
``FVD_WARMUP_TEST_DIR``.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import numba


@numba.njit(cache=True)
def scaled_sum(values, factor):
    """A kernel of the tests' own, cached beside this file."""
    total = 0.0
    for v in values:
        total += v * factor
    return total


def _folder() -> Path:
    return Path(os.environ["FVD_WARMUP_TEST_DIR"])


def _quick():
    import numpy as np
    assert scaled_sum(np.arange(4.0), 2.0) == 12.0


def _say(name: str) -> None:
    """``name.PID`` holding the pid, whole when it appears (a test reads it at once; on a busy
    machine a plain write let it read the file still empty)."""
    partial = _folder() / f".{name}.{os.getpid()}.partial"
    partial.write_text(str(os.getpid()))
    os.replace(partial, _folder() / f"{name}.{os.getpid()}")


def _waits_for_a_kill():
    _say("sleeping")
    time.sleep(600)


def _fails():
    return 1 / 0


def _meet(mine: str, other: str):
    """Start, then wait for ``other`` to have started: only two workers at once finish both."""
    _say(mine)
    for _ in range(1200):
        if any(_folder().glob(f"{other}.*")):
            return
        time.sleep(0.05)
    raise TimeoutError(f"{other} never started while {mine} ran")


def steps():
    return [("test: quick kernel", _quick),
            ("test: waits for a kill", _waits_for_a_kill),
            ("test: fails", _fails),
            ("test: meets B", lambda: _meet("A", "B")),
            ("test: meets A", lambda: _meet("B", "A"))]
