"""The ``"normals"`` renderer: each pixel coloured by the unit normal of the surface it sees.

A toy that shows what adding a renderer takes: one module with ``draw`` and one
``register_renderer`` line. Primary rays (:func:`core.camera.rays.camera_rays`) are cast
against the ray tracer's BVH of every triangle (:func:`core.raytrace.bvh.intersect_rays`);
a hit triangle's geometric normal ``N`` becomes the colour ``(N + 1) / 2`` (x red, y green,
z blue), a miss the background.
"""

from __future__ import annotations

import numpy as np

from core.camera.film import to_rgb8
from core.camera.rays import camera_rays
from core.raytrace.bvh import build, intersect_rays


def _triangles(scene):
    meshes = [m for m in scene.meshes if len(m.triangles)]
    if not meshes:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    offsets = np.cumsum([0] + [len(m.positions) for m in meshes])
    return (np.concatenate([m.positions for m in meshes]),
            np.concatenate([m.triangles + offsets[i] for i, m in enumerate(meshes)]))


def draw(scene, view, settings, frame, context, timer=None) -> None:
    width, height = settings.size
    background = to_rgb8(np.asarray(scene.background, float)).reshape(3)
    frame.color[...] = background
    positions, triangles = _triangles(scene)
    if not len(triangles):
        return
    cache = context.cache(scene)
    if "normals renderer BVH" not in cache:
        cache["normals renderer BVH"] = build(positions, triangles)[0]
    bvh = cache["normals renderer BVH"]
    o, d, t0, t1 = camera_rays(view, settings.projection, width, height,
                               [settings.pixel_offset], settings.keep_aspect)
    prim = intersect_rays(bvh, o, d, t0, t1)[0]
    corners = positions[triangles[np.maximum(prim, 0)]]
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    rgb = to_rgb8((normal / np.where(length > 0, length, 1.0) + 1.0) / 2.0)
    frame.color[...] = np.where((prim >= 0)[:, None], rgb, background).reshape(height, width, 3)
    frame.stats["computed"].append("normals")
