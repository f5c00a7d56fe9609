"""Frames drawn progressively: pictures handed over on the way to the final frame.

A renderer whose registry entry says ``progressive`` is drawn in the window by its own
``progressive_drawer`` (the ray tracer tile by tile, radiosity shot by shot, the path tracer
pass by pass: each in its package's ``progressive.py``), or else by :func:`coarse_then_full`.
A drawer is ``f(scene, view, settings, context, render, control)``: ``render`` is the front
door (:func:`core.render.render`, handed in: the renderers sit below it), and ``control`` says
whether a newer request superseded the frame (``check`` raises), takes the progress
(``report(fraction, detail)``) and the pictures on the way (``partial(frame)``). The last
frame a drawer returns is, pixel for pixel, what ``render`` gives.
"""

from __future__ import annotations

import math

import numpy as np

PARTIAL_EVERY = 0.25      # seconds between pictures handed over on the way
COARSE_FIRST = 4          # coarse_then_full's first picture: one pixel per 4 x 4


class Quiet:
    """A control for callers without a window (tests, a batch): never cancelled."""

    cancelled = False

    def check(self) -> None:
        pass

    def report(self, fraction: float, detail: str) -> None:
        pass

    def partial(self, frame) -> None:
        pass


def upscale(color: np.ndarray, factor: int, width: int, height: int) -> np.ndarray:
    """``color`` with each pixel repeated ``factor`` x ``factor`` times, cut to the size."""
    big = np.repeat(np.repeat(color, factor, axis=0), factor, axis=1)
    return big[:height, :width]


def snapshot(frame):
    """A copy of ``frame`` (the window uploads it while the drawer writes the next part)."""
    return type(frame)(rgbx=frame.rgbx.copy(), plan=frame.plan, message=frame.message,
                       stats=dict(frame.stats))


def coarse_then_full(scene, view, settings, context, render, control=None):
    """The frame at 1/``COARSE_FIRST`` of its size through the front door, handed over upscaled
    by pixel repetition, then the full frame (exactly ``core.render``'s); between the two a
    newer request may supersede it."""
    control = control or Quiet()
    width, height = settings.size
    small = (max(1, math.ceil(width / COARSE_FIRST)), max(1, math.ceil(height / COARSE_FIRST)))
    control.report(0.0, f"coarse pass (every {COARSE_FIRST}th pixel)")
    coarse = render(scene, view, settings.replace(size=small, samples=1), context)
    if coarse.message:                        # an invalid view: said once, nothing to refine
        return coarse
    shown = type(coarse)(rgbx=np.empty((height, width, 4), np.uint8), plan=coarse.plan,
                         stats={**coarse.stats, "pass": "coarse"})
    shown.color[:] = upscale(coarse.color, COARSE_FIRST, width, height)
    control.partial(shown)
    control.check()
    control.report(0.2, "full frame")
    frame = render(scene, view, settings, context)
    frame.stats["pass"] = "final"
    return frame
