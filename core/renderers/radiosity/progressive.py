"""Radiosity drawn progressively in the window (:mod:`core.progressive`): unless the scene's
solution for these settings is already in the render context (then every view is one z-buffer
frame), progressive refinement runs shot by shot (:func:`core.radiosity.solution.solve` with a
callback); every ``PARTIAL_EVERY`` seconds the elements' radiosity so far, with the ambient
term for the light not yet shot, is drawn and handed over — the picture brightens step by
step — with "shooting step k, unshot energy x %" as the progress. The final solution is kept.
It stops between shots when the window supersedes it (``control.check`` raises).
"""

from __future__ import annotations

import time

from core.progressive import PARTIAL_EVERY, Quiet


def radiosity_progressively(scene, view, settings, context, render, control=None):
    from core.radiosity.mesh import has_light
    from core.renderers.radiosity.draw import use_solution
    from core.radiosity.solution import Options, Solution, scene_hash, solve
    control = control or Quiet()
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
