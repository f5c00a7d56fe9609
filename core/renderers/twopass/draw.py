"""The ``"twopass"`` renderer: radiosity for the diffuse part, ray tracing for the specular part.

Pass 1 is the radiosity renderer's solution (:func:`core.renderers.radiosity.draw.solution_for`),
kept in the render context with the scene under the same key and for the same options, so the
two renderers share it (and ``render --solution FILE`` and the window's progressive solve,
:func:`core.renderers.radiosity.progressive.radiosity_progressively`, work for both). Pass 2
(:mod:`core.twopass.second_pass`) traces one eye ray per film sample (the front door runs the
renderer once per sample, as it runs the radiosity renderer); the summed radiance goes through
the scene's tone (``scene.tone``: linear, or the sRGB curve) and is clamped to bytes.

Refused with a message (the picture black): a material whose specular terms cannot be traced
(``k_r``, ``k_t`` or ``k_s`` outside [0, 1], a bad ``ior``), or that radiosity cannot use
(ρ = k_d O_d >= 1, bad emission). A scene with nothing that gives light is drawn black with a
warning, as the radiosity renderer draws it.
"""

from __future__ import annotations

import math
import time

import numpy as np

from core.camera.film import fill
from core.raytrace.whitted import COUNTERS
# The frame's ``computed`` words for each stage that ran are the plan's stage names.
from core.renderers.twopass.plan import (BVH, EYE, HIGHLIGHTS, REFLECTED, REFRACTED, SOLUTION,
                                         TONE, VERTICES)

RAYS_PER_BAND = 1 << 18          # eye rays traced at a time (a band of rows): the progress unit


def check_materials(scene) -> None:
    """Raise ValueError, naming the mesh, for a material the second pass cannot trace."""
    from core.raytrace.optics import check_material
    for i, mesh in enumerate(scene.meshes):
        if not len(mesh.triangles):
            continue
        where = f"mesh {i + 1} ({mesh.name!r})"
        check_material(mesh.material, where)
        ks = mesh.material.ks
        if not (isinstance(ks, (int, float)) and math.isfinite(ks) and 0.0 <= ks <= 1.0):
            raise ValueError(f"{where}: ks must be a number in [0, 1] for the two-pass "
                             f"method's highlights, not {ks!r}")
        n = mesh.material.n
        if not (isinstance(n, (int, float)) and math.isfinite(n) and n >= 0.0):
            raise ValueError(f"{where}: the specular exponent n must be a finite number >= 0, "
                             f"not {n!r}")


def geometry_for(scene, solution, context):
    """The second pass's arrays for ``solution``, made once and kept in ``context``."""
    from core.twopass.second_pass import prepare
    cache = context.cache(scene)
    held = cache.get("twopass geometry")
    if held is None or held[0] is not solution:
        held = (solution, prepare(scene, solution))
        cache["twopass geometry"] = held
    return held[1]


def draw(scene, view, settings, frame, context, timer) -> None:
    """Fill ``frame`` with the two-pass picture of ``scene`` seen through ``view``."""
    from core.camera.rays import camera_rays
    from core.renderers.radiosity.draw import solved_or_said
    from core.radiosity.tone import tone_map
    from core.shading.illumination import to_uint8
    from core.twopass.second_pass import Rules, trace
    from core.work import report
    try:
        check_materials(scene)
    except ValueError as error:
        fill(frame.color, (0.0, 0.0, 0.0))
        frame.message = f"{scene.name}: cannot draw by the two-pass method: {error}"
        return
    solution = solved_or_said(scene, settings, frame, context)
    if solution is None:
        return
    timer.lap("radiosity solution")
    geometry = geometry_for(scene, solution, context)
    frame.stats["computed"] += [SOLUTION, VERTICES, BVH]
    timer.lap("vertex radiosity, element BVH")
    width, height = settings.size
    rules = Rules.from_settings(settings)
    counts = np.zeros(len(COUNTERS), np.int64)
    rows = max(1, RAYS_PER_BAND // max(width, 1))
    radiance = np.empty((height * width, 3))
    began = time.perf_counter()
    for r in range(0, height, rows):
        end = min(r + rows, height)
        origins, directions, t_min, t_max = camera_rays(
            view, settings.projection, width, height, [settings.pixel_offset],
            settings.keep_aspect, (r, end))
        radiance[r * width:end * width] = trace(geometry, origins, directions, t_min, t_max,
                                                rules, counts)
        report("two-pass ray tracing", end, height, "row")
    seconds = time.perf_counter() - began
    frame.color[...] = to_uint8(tone_map(radiance, scene.tone)).reshape(height, width, 3)
    timer.lap("eye rays, specular rays")
    rays = {name: int(c) for name, c in zip(COUNTERS, counts)}
    frame.stats["computed"].append(EYE)
    for stage, counter in ((HIGHLIGHTS, "shadow"), (REFLECTED, "reflected"),
                           (REFRACTED, "refracted")):
        if rays[counter]:
            frame.stats["computed"].append(stage)
    if scene.tone == "srgb":
        frame.stats["computed"].append(TONE)
    frame.stats["twopass"] = {"rays": rays, "trace ms": seconds * 1e3,
                              "radiosity": {k: v for k, v in solution.stats.items()
                                            if k != "rounds"},
                              "max depth": rules.max_depth}
