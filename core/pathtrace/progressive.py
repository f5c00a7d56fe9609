"""The path tracer drawn progressively in the window (:mod:`core.progressive`): the film's
samples one pass at a time, the running mean shown after each; the last picture is the
renderer's own (same passes, same sums). It stops between passes when the window supersedes
it (``control.check`` raises).
"""

from __future__ import annotations

import time

from core.progressive import PARTIAL_EVERY, Quiet


def pathtrace_progressively(scene, view, settings, context, render, control=None):
    import numpy as np
    from core.pathtrace.renderer import pass_offsets, render_passes
    from core.radiosity.mesh import RadiosityError, has_light
    from core.radiosity.tone import tone_map
    from core.shading.illumination import to_uint8
    control = control or Quiet()
    first = render(scene, view, settings.replace(samples=1), context)     # checks, messages
    if first.message or not has_light(scene) or settings.samples == 1:
        return first if settings.samples == 1 or first.message else \
            render(scene, view, settings, context)
    passes = len(pass_offsets(settings.samples, settings.seed))
    width, height = settings.size
    total = np.zeros((height, width, 3))
    frame = first
    last = time.perf_counter()
    try:
        for k in range(passes):
            control.check()
            radiance, _ = render_passes(scene, view, settings, context, first=k, count=1)
            total += radiance
            control.report((k + 1) / passes, f"path tracing: pass {k + 1} of {passes}")
            if time.perf_counter() - last >= PARTIAL_EVERY and k + 1 < passes:
                last = time.perf_counter()
                frame.color[:] = to_uint8(tone_map(total / (k + 1), scene.tone))
                frame.stats["pass"] = f"pass {k + 1} of {passes}"
                control.partial(type(frame)(rgbx=frame.rgbx.copy(), plan=frame.plan,
                                            stats=dict(frame.stats)))
    except RadiosityError:
        return render(scene, view, settings, context)
    frame.color[:] = to_uint8(tone_map(total / passes, scene.tone))
    frame.stats["pass"] = "final"
    frame.stats["samples per pixel"] = settings.samples
    return frame
