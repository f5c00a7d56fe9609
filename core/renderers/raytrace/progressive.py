"""The window's ray-traced frames, progressive: a coarse picture first, then tile by tile.

A Whitted frame takes seconds on a small machine; the window should not show nothing (or a
frozen z-buffer picture) for that long. :func:`trace_progressively` therefore

1. traces a picture at 1/``f`` of the size in each direction (one ray per ``f`` x ``f``
   block; ``f`` from :func:`core.progressive.coarse_factor`, so that it takes about a tenth
   of a second: ``COARSE`` = 8 before the first is timed) through the front door (``core.render`` with the
   ``"raytrace"`` renderer, so its checks and messages are the usual ones) and hands it over
   upscaled by pixel repetition — the first picture the user sees;
2. then traces the full-size frame tile by tile (``core.renderers.raytrace.draw.trace_tile``, in
   :func:`core.renderers.raytrace.draw.tiles`' order: the centre first), writing each finished tile
   over the coarse picture and handing the picture over every few tiles;
3. returns the finished frame, which is pixel for pixel what ``core.render`` would give
   (the same rays, the same box filter, the same rounding; a test holds them equal).

Between tiles it asks its control (:mod:`core.progressive`) whether a newer request has
superseded it (the view or a setting changed) and stops there.
"""

from __future__ import annotations

import time

import numpy as np

from core.progressive import PARTIAL_EVERY, Quiet, coarse_factor, coarse_picture, snapshot

COARSE = 8                # the first picture before a rate is known: one ray per 8 x 8 pixels
TILE = 32                 # refinement tiles, pixels a side


def _prepare(scene, view, settings):
    """The tracer's per-frame setup for ``settings`` (its film's samples, its letterboxing), as
    its ``draw`` makes it."""
    from core.camera.film import sample_offsets
    from core.renderers.raytrace.draw import TraceOptions, prepare
    offsets = (sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
               if settings.samples > 1 else np.array([settings.pixel_offset], dtype=np.float64))
    return prepare(scene, view, settings.projection, settings.size,
                   TraceOptions.from_settings(settings), offsets, bool(settings.keep_aspect))


def trace_progressively(scene, view, settings, context, render, control=None):
    """The ray-traced frame of ``view`` for ``settings`` (``settings.renderer`` is taken as
    ``"raytrace"``), handing pictures on the way to ``control.partial``."""
    from core.renderers.raytrace.draw import stats_of, tiles, trace_tile
    from core.shading.illumination import to_uint8
    control = control or Quiet()
    settings = settings.replace(renderer="raytrace")
    width, height = settings.size
    factor = coarse_factor(context, "raytrace", width, height, COARSE, least=2)
    frame = coarse_picture(scene, view, settings, context, render, control, factor, "ray")
    if frame.message:                         # an invalid view, nothing to trace: said once
        return frame
    control.partial(snapshot(frame))
    setup = _prepare(scene, view, settings)
    boxes = tiles(width, height, TILE)
    start = last = time.perf_counter()
    for k, (r0, r1, c0, c1) in enumerate(boxes):
        control.check()
        frame.color[r0:r1, c0:c1] = to_uint8(trace_tile(setup, r0, r1, c0, c1))
        control.report((k + 1) / len(boxes), f"refining: tile {k + 1} of {len(boxes)}")
        if time.perf_counter() - last >= PARTIAL_EVERY and k + 1 < len(boxes):
            last = time.perf_counter()
            frame.stats["pass"] = f"tile {k + 1} of {len(boxes)}"
            control.partial(snapshot(frame))
    frame.stats.update(stats_of(setup, time.perf_counter() - start))
    frame.stats["pass"] = "final"
    frame.stats["samples per pixel"] = len(setup.offsets)
    return frame
