"""Frames drawn progressively: pictures handed over on the way to the final frame.

A renderer whose registry entry says ``progressive`` is drawn in the window by its own
``progressive_drawer`` (the ray tracer tile by tile, radiosity shot by shot, the path tracer
pass by pass: each in its package's ``progressive.py``), or else by :func:`coarse_then_full`.
A drawer is ``f(scene, view, settings, context, render, control)``: ``render`` is the front
door (:func:`core.render.render`, handed in: the renderers sit below it), and ``control`` says
whether a newer request superseded the frame (``check`` raises), takes the progress
(``report(fraction, detail)``) and the pictures on the way (``partial(frame)``). The last
frame a drawer returns is, pixel for pixel, what ``render`` gives.

The first picture is coarse so that it follows a moving camera: :func:`coarse_factor` picks
the smallest reduction whose pass the last measured rate (:func:`note_rate`, seconds per ray
of the renderer's one-sample passes, kept in the render context) predicts within
``COARSE_BUDGET`` seconds, so that with the window's own work a drag sees at least eight
pictures a second on any scene at any size; a superseded frame stops right after it.
"""

from __future__ import annotations

import math
import time

import numpy as np

PARTIAL_EVERY = 0.25      # seconds between pictures handed over on the way
COARSE_FIRST = 4          # coarse_then_full's first picture before any rate is known: 1 per 4 x 4
COARSE_BUDGET = 0.08      # seconds a coarse picture may take (a drag then sees >= 8 a second)
COARSE_FACTORS = (2, 4, 8, 16, 32, 64)      # reductions to choose from, finest first


def _rates(context) -> dict:
    """The rates measured so far in ``context`` (none kept without one)."""
    return {} if context is None else context.buffer("progressive rates", None, dict)


def note_rate(context, key: str, seconds: float, rays: int) -> None:
    """A one-sample pass of renderer ``key`` traced ``rays`` rays in ``seconds``."""
    if rays > 0 and seconds > 0:
        _rates(context)[key] = seconds / rays


def coarse_factor(context, key: str, width: int, height: int, default: int,
                  least: int = 1) -> int:
    """One ray per ``f`` x ``f`` pixels for the first picture of ``key`` at ``width`` x
    ``height``: the smallest ``f`` (at least ``least``; 1 means no coarse picture is needed)
    whose one-sample pass takes ``COARSE_BUDGET`` seconds at the last rate; ``default``
    before any rate is known."""
    rate = _rates(context).get(key)
    if rate is None:
        return max(default, least)
    for f in (1,) + COARSE_FACTORS:
        if f >= least and rate * math.ceil(width / f) * math.ceil(height / f) <= COARSE_BUDGET:
            return f
    return COARSE_FACTORS[-1]


def coarse_size(width: int, height: int, factor: int) -> tuple[int, int]:
    return max(1, math.ceil(width / factor)), max(1, math.ceil(height / factor))


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


def coarse_picture(scene, view, settings, context, render, control, factor: int,
                   unit: str = "pixel"):
    """One sample per ``factor`` x ``factor`` pixels through the front door (its checks and
    messages), timed for :func:`note_rate`, reported as the coarse pass, and returned upscaled
    by pixel repetition in a frame of the full size that carries the small one's plan,
    message and stats (``unit``: what a sample is, for the words: "ray", "path")."""
    width, height = settings.size
    small = coarse_size(width, height, factor)
    control.report(0.0, f"coarse pass (one {unit} per {factor} x {factor} pixels)")
    began = time.perf_counter()
    coarse = render(scene, view, settings.replace(size=small, samples=1), context)
    note_rate(context, settings.renderer or "zbuffer", time.perf_counter() - began,
              small[0] * small[1])
    frame = type(coarse)(rgbx=np.empty((height, width, 4), np.uint8), plan=coarse.plan,
                         message=coarse.message, stats=dict(coarse.stats))
    frame.color[:] = upscale(coarse.color, factor, width, height)
    frame.stats["pass"] = f"coarse (1 {unit} per {factor} x {factor} pixels)"
    return frame


def coarse_then_full(scene, view, settings, context, render, control=None):
    """The frame at 1/``f`` of its size through the front door (``f`` from
    :func:`coarse_factor`), handed over upscaled by pixel repetition, then the full frame
    (exactly ``core.render``'s); between the two a newer request may supersede it. A frame
    fast enough to follow the mouse whole is drawn whole."""
    control = control or Quiet()
    width, height = settings.size
    key = settings.renderer or "zbuffer"
    factor = coarse_factor(context, key, width, height, COARSE_FIRST)
    if factor == 1:
        start = time.perf_counter()
        frame = render(scene, view, settings, context)
        note_rate(context, key, (time.perf_counter() - start) / settings.samples, width * height)
        frame.stats["pass"] = "final"
        return frame
    shown = coarse_picture(scene, view, settings, context, render, control, factor)
    if shown.message:                         # an invalid view: said once, nothing to refine
        return shown
    control.partial(shown)
    control.check()
    control.report(0.2, "full frame")
    frame = render(scene, view, settings, context)
    frame.stats["pass"] = "final"
    return frame
