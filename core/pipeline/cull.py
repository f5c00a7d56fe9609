"""Back-face culling (FvDFH 15.2.4), in world coordinates, before clipping.

For a mesh declared closed and consistently wound (counter-clockwise seen from outside), a face
whose outer side is turned away from the viewer can never be seen: the z-buffer would hide it
behind the front of the same mesh. A face is kept when the eye lies on the outer side of its
plane, ``N·E - N·V0 >= 0`` (perspective, E the PRP), or when the direction towards the viewer
does, ``N·D >= 0`` (parallel). Faces exactly edge-on are kept. Meshes that are not closed keep
every face.

The face planes (unnormalised normal N and constant ``N·V0``) do not depend on the view and are
computed once per mesh; the per-frame test is one compiled pass over the faces that writes the
kept triangles directly (no boolean mask, no gather afterwards).
"""

from __future__ import annotations

import numpy as np

from core.context import DEFAULT_CONTEXT, RenderContext
from core.jit import njit, prange


def face_planes(mesh, context: RenderContext = DEFAULT_CONTEXT) -> tuple[np.ndarray, np.ndarray]:
    """Unnormalised outward normals ``(T, 3)`` and plane constants ``N·V0`` ``(T,)`` of a mesh
    (kept in ``context`` while the mesh and its arrays live)."""
    cache = context.cache(mesh)
    held = cache.get("face planes")
    if held is not None and held[0] is mesh.positions and held[1] is mesh.triangles:
        return held[2], held[3]
    p, t = mesh.positions, mesh.triangles
    v0 = p[t[:, 0]]
    normal = np.cross(p[t[:, 1]] - v0, p[t[:, 2]] - v0)
    d = np.einsum("ij,ij->i", normal, v0)
    cache["face planes"] = (mesh.positions, mesh.triangles, normal, d)
    return normal, d


@njit(cache=True)
def _keep_front(normal, d, triangles, first, eye, eye_is_point, kept, kept_triangles, count):
    """Append the front faces of one mesh (its rows start at ``first``); returns the new count."""
    ex, ey, ez = eye[0], eye[1], eye[2]
    for t in range(normal.shape[0]):
        side = normal[t, 0] * ex + normal[t, 1] * ey + normal[t, 2] * ez
        if eye_is_point:
            side -= d[t]
        if side >= 0.0:
            kept[count] = first + t
            for c in range(3):
                kept_triangles[count, c] = triangles[first + t, c]
            count += 1
    return count


# From this many faces the test runs on all cores, in chunks: each chunk counts its front
# faces, then writes them at its offset (the same order as one pass).
PARALLEL_FACES = 50_000
CHUNKS = 64


@njit(cache=True, parallel=True, nogil=True)
def _keep_front_parallel(normal, d, triangles, first, eye, eye_is_point, kept, kept_triangles,
                         count):
    n = normal.shape[0]
    front = np.empty(n, np.bool_)
    counts = np.zeros(CHUNKS + 1, np.int64)
    ex, ey, ez = eye[0], eye[1], eye[2]
    for c in prange(CHUNKS):
        here = 0
        for t in range(c * n // CHUNKS, (c + 1) * n // CHUNKS):
            side = normal[t, 0] * ex + normal[t, 1] * ey + normal[t, 2] * ez
            if eye_is_point:
                side -= d[t]
            front[t] = side >= 0.0
            here += front[t]
        counts[c + 1] = here
    for c in range(CHUNKS):
        counts[c + 1] += counts[c]
    for c in prange(CHUNKS):
        at = count + counts[c]
        for t in range(c * n // CHUNKS, (c + 1) * n // CHUNKS):
            if front[t]:
                kept[at] = first + t
                for k in range(3):
                    kept_triangles[at, k] = triangles[first + t, k]
                at += 1
    return count + counts[CHUNKS]


@njit(cache=True)
def _keep_all(triangles, first, n, kept, kept_triangles, count):
    for t in range(n):
        kept[count] = first + t
        for c in range(3):
            kept_triangles[count, c] = triangles[first + t, c]
        count += 1
    return count


def front_faces(meshes, triangles: np.ndarray, eye,
                context: RenderContext = DEFAULT_CONTEXT) -> tuple[np.ndarray, np.ndarray] | None:
    """The faces that may be seen: ``(kept indices (K,), kept triangles (K, 3))``.

    ``triangles`` are all meshes' triangles in scene order over one vertex array (what
    ``shade.prepare`` built); ``eye`` is ``shade.eye_from_view``'s answer. Returns None when no
    mesh is closed, so that nothing is copied.
    """
    if not any(m.closed and len(m.triangles) for m in meshes):
        return None
    # written every frame: held by the context, so no fresh (page-faulting) memory each time
    kept = context.scratch("kept faces", (len(triangles),), np.int64)
    kept_triangles = context.scratch("kept triangles", (len(triangles), 3), np.int64)
    eye_is_point = eye.point is not None
    e = np.asarray(eye.point if eye_is_point else eye.direction, dtype=np.float64)
    count, first = 0, 0
    for mesh in meshes:
        n = len(mesh.triangles)
        if mesh.closed and n:
            normal, d = face_planes(mesh, context)
            keep = _keep_front_parallel if n >= PARALLEL_FACES else _keep_front
            count = keep(normal, d, triangles, first, e, eye_is_point, kept, kept_triangles,
                         count)
        elif n:
            count = _keep_all(triangles, first, n, kept, kept_triangles, count)
        first += n
    return kept[:count], kept_triangles[:count]
