"""What one pixel of a radiosity frame shows: its element, patch, emission, reflectance, radiosity
and the vertex values interpolated there (the pixel's colour).

It reads the frame the front door draws (``render``, handed over by
:func:`core.inspect.inspect_pixel`: this package, below it, does not import it) and the
solution the renderer (:mod:`core.renderers.radiosity.draw`) kept in the context.
"""

from __future__ import annotations

import numpy as np

from core.renderers.radiosity.draw import display


def inspect_pixel(scene, view, settings, x, y, context, *, render) -> dict:
    """The element seen at image pixel (x, y): its emission, reflectance, radiosity, and the
    vertex values interpolated there (the pixel's colour); ``render`` is the front door."""
    frame = render(scene, view, settings, context)
    record = {"renderer": "radiosity", "pixel": [int(x), int(y)],
              "color": [int(c) for c in frame.color[y, x]]}
    if frame.message:
        record["message"] = frame.message
        return record
    vis = context.buffer("visibility", (settings.size[0], settings.size[1]), lambda: None)
    solution = context.cache(scene)["radiosity solution"]
    shown = display(scene, solution, context)
    record["solution"] = {k: v for k, v in solution.stats.items() if k != "rounds"}
    t = int(vis.tri[y, x]) if vis is not None else -1
    if t < 0:
        record["hit"] = None
        return record
    element = element_at(scene, shown, view, settings, context, x, y)
    if element is None:
        record["hit"] = None
        return record
    e = solution.elements
    record.update({"element": int(element), "patch": int(e.patch[element]),
                   "mesh": scene.meshes[int(e.mesh[element])].name,
                   "area": float(e.area[element]),
                   "emission": e.emission[element].tolist(), "reflectance": e.rho[element].tolist(),
                   "radiosity": solution.radiosity[element].tolist(),
                   "ambient": solution.ambient[element].tolist()})
    w1, w2 = float(vis.b1[y, x]), float(vis.b2[y, x])
    record["barycentric"] = [1.0 - w1 - w2, w1, w2]
    return record


def element_at(scene, shown, view, settings, context, x, y):
    """The element drawn at (x, y): a ray through the pixel centre to the nearest display
    triangle (the z-buffer and the ray see the same surface)."""
    from core.camera.rays import primary_rays
    from core.raytrace.bvh import build, intersect_rays
    origins, directions, inside = primary_rays(view, settings.projection, settings.size[0],
                                               settings.size[1], np.array([[0.5, 0.5]]),
                                               settings.keep_aspect, (y, y + 1), (x, x + 1))
    positions = np.concatenate([m.positions for m in shown.meshes])
    offsets = np.cumsum([0] + [len(m.positions) for m in shown.meshes])
    triangles = np.concatenate([m.triangles + offsets[i] for i, m in enumerate(shown.meshes)])
    rows = np.concatenate([m.element_rows for m in shown.meshes])
    # Of a two-sided pair (coplanar) only the copy facing the ray can be the one drawn.
    corners = positions[triangles]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    two = np.concatenate([np.full(len(m.triangles), m.closed) for m in shown.meshes])
    keep = np.flatnonzero(~two | (normal @ directions[0] < 0.0))
    triangles, rows = triangles[keep], rows[keep]
    bvh, _ = build(positions, triangles)
    prim, _, _, _ = intersect_rays(bvh, origins, directions)
    return None if prim[0] < 0 else rows[prim[0]]
