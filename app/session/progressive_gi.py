"""The window's radiosity and path-traced frames, progressive, off the UI thread.

- :func:`radiosity_progressively`: unless the scene's solution for these settings is already
  in the render context (then every view is one z-buffer frame), progressive refinement runs
  shot by shot (:func:`core.radiosity.solution.solve` with a callback); every
  ``PARTIAL_EVERY`` seconds the elements' radiosity so far, with the ambient term for the
  light not yet shot, is drawn and handed to the window — the picture brightens step by step —
  with "shooting step k, unshot energy x %" as the progress. The final solution is kept.
- :func:`pathtrace_progressively`: the film's samples one pass at a time, the running mean
  shown after each; the last picture is the renderer's own (same passes, same sums).

Both stop between steps when the window supersedes them (``control.check`` raises).
"""

from __future__ import annotations

import time

from app.session.progressive import PARTIAL_EVERY, _Quiet


def radiosity_progressively(scene, view, settings, context, render, control=None):
    from core.radiosity.mesh import has_light
    from core.radiosity.renderer import use_solution
    from core.radiosity.solution import Options, Solution, scene_hash, solve
    control = control or _Quiet()
    options = Options.from_settings(settings)
    held = context.cache(scene).get("radiosity solution")
    if (held is not None and held.options == options and not held.stats.get("partial")) \
            or not has_light(scene):
        return render(scene, view, settings, context)
    digest = scene_hash(scene)
    last = [time.perf_counter()]

    def shot(solver) -> None:
        control.check()
        detail = (f"shooting step {solver.steps}, unshot energy "
                  f"{100 * solver.unshot_fraction():.1f} %, {len(solver.e)} elements")
        done = 1.0 - solver.unshot_fraction()
        control.report(min(1.0, max(0.0, done)), detail)
        if time.perf_counter() - last[0] >= PARTIAL_EVERY:
            partial = Solution(solver.e, solver.radiosity.copy(), solver.ambient(), digest,
                               options, {"partial": True, "steps": solver.steps})
            use_solution(scene, partial, context)
            frame = render(scene, view, settings, context)
            frame.stats["pass"] = detail
            control.partial(frame)
            last[0] = time.perf_counter()

    try:
        solution = solve(scene, options, shot)
    except ValueError:                       # a material the equation cannot use: its message
        context.cache(scene).pop("radiosity solution", None)
        return render(scene, view, settings, context)
    use_solution(scene, solution, context)
    frame = render(scene, view, settings, context)
    frame.stats["pass"] = "final"
    return frame


def pathtrace_progressively(scene, view, settings, context, render, control=None):
    import numpy as np
    from core.pathtrace.renderer import pass_offsets, render_passes
    from core.radiosity.mesh import RadiosityError, has_light
    from core.radiosity.tone import tone_map
    from core.shading.illumination import to_uint8
    control = control or _Quiet()
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
