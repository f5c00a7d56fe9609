"""The path tracer drawn progressively in the window (:mod:`core.progressive`): a coarse
one-sample picture first (it follows a moving camera), then the film's samples one pass at a
time, the running mean shown every ``PARTIAL_EVERY`` seconds with its samples per pixel and
time, until ``settings.samples`` (the window asks for the renderer's ``samples_at_rest``, 256,
unless the user chose another number). The last picture is the renderer's own (same passes,
same sums). It stops between passes when the window supersedes it (``control.check`` raises).
"""

from __future__ import annotations

import time

import numpy as np

from core.progressive import (COARSE_FIRST, PARTIAL_EVERY, Quiet, coarse_factor, coarse_picture,
                              note_rate, snapshot)


def pathtrace_progressively(scene, view, settings, context, render, control=None):
    from core.renderers.pathtrace.draw import render_passes
    from core.radiosity.mesh import RadiosityError, has_light
    from core.radiosity.tone import tone_map
    from core.shading.illumination import to_uint8
    control = control or Quiet()
    width, height = settings.size
    factor = coarse_factor(context, "pathtrace", width, height, COARSE_FIRST, least=2)
    frame = coarse_picture(scene, view, settings, context, render, control, factor, "path")
    if frame.message:                         # an invalid view: said once, nothing to refine
        return frame
    if not has_light(scene):                  # the renderer's own message for a dark scene
        return render(scene, view, settings, context)
    control.partial(snapshot(frame))
    passes = settings.samples
    total = np.zeros((height, width, 3))
    start = last = time.perf_counter()
    try:
        for k in range(passes):
            control.check()
            began = time.perf_counter()
            radiance, _ = render_passes(scene, view, settings, context, first=k, count=1)
            note_rate(context, "pathtrace", time.perf_counter() - began, width * height)
            total += radiance
            spent = time.perf_counter() - start
            done = f"{k + 1} of {passes} samples per pixel, {spent:.1f} s"
            control.report((k + 1) / passes, f"path tracing: {done}")
            if k + 1 < passes and (k == 0 or time.perf_counter() - last >= PARTIAL_EVERY):
                last = time.perf_counter()
                frame.color[:] = to_uint8(tone_map(total / (k + 1), scene.tone))
                frame.stats.update({"pass": done, "samples per pixel": k + 1})
                control.partial(snapshot(frame))
    except RadiosityError:                    # what the scene lacks: the renderer's message
        return render(scene, view, settings, context)
    frame.color[:] = to_uint8(tone_map(total / passes, scene.tone))
    frame.stats["pass"] = "final"
    frame.stats["samples per pixel"] = passes
    return frame
