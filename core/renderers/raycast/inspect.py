"""The exact ray caster's pixel record, for the pixel inspector.

:func:`inspect_pixel` follows ``_trace`` (:mod:`core.renderers.raycast.draw`) for one pixel,
in its order: each sample of the regular grid, its ray (:func:`core.camera.rays.camera_ray`),
the visible hit on the analytic surfaces (``_nearest_hit``), the normal, and the Phong terms
(:func:`core.shading.models.dispatch.lighting_terms`); the samples' mean, background for the
misses, is the pixel.
"""

from __future__ import annotations

import numpy as np

from core.shading.models.dispatch import lighting_terms


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    from core.camera.film import to_rgb8
    from core.camera.rays import CAMERA_BACK, CAMERA_FRONT, camera_ray
    from core.renderers.raycast import draw as raycast
    from core.shading.illumination import unit3
    if not scene.primitives:
        raise ValueError(f"{scene.name} has no analytic primitives: the ray caster draws none")
    f = _frame(scene, view, settings, context)
    side, cam, shapes = f.side, f.cam, f.shapes
    roots, breaks = np.empty(4), np.empty(6)
    j = settings.size[1] - 1 - y               # device row, counted from the bottom
    total, hits, samples = [0.0, 0.0, 0.0], 0, []
    for a in range(side):
        for c in range(side):
            sx, sy = x + (c + 0.5) / side, j + (a + 0.5) / side
            inside, ox, oy, oz, dx, dy, dz = camera_ray(cam, sx, sy)
            shape, t = -1, 0.0
            if inside:
                shape, t = raycast._nearest_hit(shapes, ox, oy, oz, dx, dy, dz, f.vrp, *f.vpn,
                                                cam[CAMERA_FRONT], cam[CAMERA_BACK], breaks,
                                                roots)
            sample = {"device point": [sx, sy], "origin": [ox, oy, oz],
                      "direction": [dx, dy, dz]}
            samples.append(sample)
            if shape < 0:
                sample["hit"] = None
                continue
            p = (ox + t * dx, oy + t * dy, oz + t * dz)
            row = shapes[shape]
            if row[0] == raycast.SPHERE:
                nx, ny, nz, _ = unit3(p[0] - row[1], p[1] - row[2], p[2] - row[3])
            else:
                nx, ny, nz = raycast._torus_normal(*p, row)
            terms = lighting_terms(p, (nx, ny, nz), int(row[6]), f.surfaces, f.lights,
                                   f.ambient, f.eye, f.halfway)
            sample.update({"hit": {"primitive": int(shape), "t": float(t), "point": list(p),
                                   "normal": [nx, ny, nz]}, "phong": terms})
            total = [total[k] + terms["clamped"][k] for k in range(3)]
            hits += 1
    per_pixel = side * side
    missed = per_pixel - hits
    raw = [(total[k] + missed * f.background[k]) / per_pixel for k in range(3)]
    return {"renderer": "raycast", "pixel": [int(x), int(y)],
            "color": to_rgb8(raw).tolist(), "raw": raw, "samples per pixel": per_pixel,
            "coverage": hits / per_pixel, "ray samples": samples}


def _frame(scene, view, settings, context):
    """What every pixel of the frame shares (packed shapes, lights, camera), kept per scene
    for the last view and settings asked."""
    from types import SimpleNamespace
    from core.camera.film import grid_side
    from core.camera.rays import CAMERA_BASIS, CAMERA_VRP, pack_camera
    from core.context import DEFAULT_CONTEXT
    from core.renderers.raycast import draw as raycast
    from core.shading.illumination import (eye_from_view, pack_ambient, pack_eye, pack_lights,
                                           pack_surfaces)
    cache = (context or DEFAULT_CONTEXT).cache(scene)
    held = cache.get("pixel inspector: raycast")
    try:
        if held is not None and held[0] == (view, settings):
            return held[1]
    except (TypeError, ValueError):
        pass
    width, height = settings.size
    cam = pack_camera(view, settings.projection, width, height, settings.keep_aspect)
    f = SimpleNamespace(
        side=grid_side(settings.samples), cam=cam,
        shapes=raycast.pack_shapes(list(scene.primitives)),
        surfaces=pack_surfaces([s.material for s in scene.primitives],
                               [s.two_sided for s in scene.primitives]),
        lights=pack_lights(scene.lights), ambient=pack_ambient(scene.ambient),
        eye=pack_eye(eye_from_view(view, settings.projection)),
        halfway=scene.specular == "halfway", vrp=cam[CAMERA_VRP:CAMERA_VRP + 3],
        vpn=tuple(cam[CAMERA_BASIS + 6:CAMERA_BASIS + 9]),
        background=np.asarray(scene.background, dtype=np.float64).reshape(3))
    cache["pixel inspector: raycast"] = ((view, settings), f)
    return f
