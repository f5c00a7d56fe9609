"""The ``.tri`` startup code's back-face rule and vertex normals, as an option (``--course-tri``).

The course's startup code (Assignments 2 and 3) skips triangle i when
``viewpoint.dot_product(T_normals[i]) < 0``: the viewpoint taken as a vector from the world
origin, against the face normal in the file's winding, ``(v1 - v0) x (v2 - v0)``. That is a
true back-face test only when the triangle's plane passes near the origin (the correct test is
``(viewpoint - v0) . N < 0``, FvDFH 15.2.4), so it can drop visible triangles or keep hidden
ones; ``--course-tri`` reproduces it so a student's picture can be held against ours.
Our own rule culls only meshes declared closed, with the correct test.

The startup code also averages, at each vertex (its ``AVERAGE_INCIDENT`` list: every triangle
that names the vertex, vertices being equal coordinates), the normals of *all* the faces
around it; our readers split vertices along creases first (faces meeting at more than the
crease angle, 45 degrees, keep their own normals there). ``--course-tri`` welds the split
vertices back (:func:`averaged_like_the_startup_code`), so the vertex normals are the average
over every incident face again, as the startup code draws Gouraud and Phong.

``course_tri_scene(scene, view)`` returns a scene whose meshes keep only the triangles the
startup code draws; the viewpoint is the view's PRP in world coordinates (for a ``.tri`` file,
its viewpoint). Kept per (scene, view) so a window re-renders without recomputing it.
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np

from core.scene.model import Scene

_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def startup_code_keeps(positions: np.ndarray, triangles: np.ndarray,
                       viewpoint: np.ndarray) -> np.ndarray:
    """Mask of the triangles the startup code draws: ``viewpoint . N >= 0``."""
    p = positions[triangles]                                      # (T, 3, 3)
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    return normals @ np.asarray(viewpoint, dtype=np.float64) >= 0.0


def averaged_like_the_startup_code(mesh):
    """``mesh`` with its coincident vertices welded into one (the startup code's vertex table:
    one entry per distinct coordinate triple) and each vertex normal the mean of every face
    around it (kept in ``normals``, so the faces the back-face rule drops still count, as
    they do in the startup code). A mesh with normals, texture coordinates or other
    per-vertex data of its own is returned as it is (welding would merge what differs)."""
    if (mesh.normals is not None or mesh.uv is not None or mesh.extra
            or len(mesh.triangles) == 0):
        return mesh
    from core.scene.normals import vertex_normals
    positions, inverse = np.unique(mesh.positions, axis=0, return_inverse=True)
    welded = dataclasses.replace(mesh, positions=positions,
                                 triangles=inverse.reshape(-1)[mesh.triangles].astype(np.int64))
    welded.normals = vertex_normals(welded, "mean")       # the notes' unweighted average
    return welded


def course_tri_scene(scene: Scene, view) -> Scene:
    """``scene`` with each mesh's triangles filtered by the startup code's rule and its
    vertex normals averaged over every incident face, as the startup code's are."""
    from core.camera.view import eye_from_view
    per_scene = _cache.setdefault(scene, {})
    if view not in per_scene:
        viewpoint = eye_from_view(view, "perspective").point
        meshes = []
        for mesh in scene.meshes:
            if len(mesh.triangles):
                keep = startup_code_keeps(mesh.positions, mesh.triangles, viewpoint)
                mesh = averaged_like_the_startup_code(mesh)
                mesh = dataclasses.replace(mesh, triangles=mesh.triangles[keep])
            meshes.append(mesh)
        per_scene[view] = dataclasses.replace(scene, meshes=meshes)
    return per_scene[view]
