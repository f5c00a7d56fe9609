"""What one pixel of a two-pass frame shows: its ray tree, each ray with the element it hit,
the diffuse term pass 1 gives there, the highlight, and the weight it carries.

It reads the frame the front door draws (``render``, handed over by
:func:`core.inspect.inspect_pixel`) and traces the pixel's centre again through the same
geometry (:func:`core.twopass.second_pass.trace` with a ``tree``), so the record's summed
radiance is the pixel's own (the colour is the frame's, supersampled or not).
"""

from __future__ import annotations

import numpy as np


def inspect_pixel(scene, view, settings, x, y, context, *, render) -> dict:
    """The ray tree of image pixel (x, y) (its centre), and the frame's colour there."""
    from core.camera.rays import camera_rays
    from core.raytrace.whitted import COUNTERS
    from core.renderers.twopass.draw import geometry_for
    from core.twopass.second_pass import Rules, trace
    frame = render(scene, view, settings, context)
    record = {"renderer": "twopass", "pixel": [int(x), int(y)],
              "color": [int(c) for c in frame.color[y, x]]}
    if frame.message or frame.stats.get("warnings"):
        record["message"] = frame.message or frame.stats["warnings"][0]
        return record
    solution = context.cache(scene)["radiosity solution"]
    geometry = geometry_for(scene, solution, context)
    width, height = settings.size
    rays = camera_rays(view, settings.projection, width, height, [settings.pixel_offset],
                       settings.keep_aspect, (y, y + 1), (x, x + 1))
    tree: list = []
    counts = np.zeros(len(COUNTERS), np.int64)
    radiance = trace(geometry, *rays, Rules.from_settings(settings), counts, tree)
    record.update({"radiance": radiance[0].tolist(), "tone": scene.tone, "rays": tree,
                   "counts": {name: int(c) for name, c in zip(COUNTERS, counts) if c},
                   "solution": {k: v for k, v in solution.stats.items() if k != "rounds"}})
    return record
