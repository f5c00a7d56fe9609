"""Python's cyclic garbage collector, paused while the program starts.

Starting the viewer creates a few hundred thousand objects (modules, numba's types and
kernels, the scene) and almost no garbage, yet the collector ran about 170 times during one
start, each pass over everything alive: 39 ms of the sphere's ~0.6 s to its first picture,
57 ms of the textured floor's. ``python -m app`` pauses it from its first line; it resumes
when the viewer's first frame is on screen (at the latest 5 s after the start), or, for the
other commands, once their arguments are read. What is alive then lives as long as the
program, so it is frozen out of later collections (``gc.freeze``): they pass over what the
session makes, not over numba's type tables.
"""

from __future__ import annotations

import gc

LATEST_S = 5.0          # the viewer resumes collecting by then, frame or not


def pause() -> None:
    gc.disable()


def resume() -> None:
    """Collect again (no-op when collecting already: in tests, or resumed before)."""
    if not gc.isenabled():
        gc.freeze()
        gc.enable()
