"""The triangle pipeline: shade inputs → N → cull → clip → project → z-buffer → resolve.

Called by :func:`core.render.render` for solid shading modes. Each step is one call into the
module that implements it; this file only threads arrays from one to the next and records what
ran in ``frame.stats``:

1. ``shade.prepare``: the mode's per-face or per-vertex work in world coordinates.
2. ``N_per`` / ``N_par`` on every vertex (vectorised).
3. Back-face culling, only for meshes declared closed, in world coordinates: a face is kept
   when the eye is on the outer side of its plane (perspective) or the direction towards the
   viewer is (parallel). Face planes do not depend on the view, so they are cached per mesh.
4. ``clip_triangles``: trivial accept/reject by outcode, Sutherland–Hodgman for the rest.
5. ``project_triangles``: perspective-to-parallel M, M_vv3dv, divide by W.
6. ``rasterize``: the scan-line z-buffer into a visibility buffer (reused between frames).
7. ``shade.resolve``: one colour per visible pixel.
"""

from __future__ import annotations

import weakref

import numpy as np
from threadpoolctl import threadpool_limits

from core import project, shade
from core.clip_polygon import clip_triangles
from core.raster import VisibilityBuffer, rasterize
from core.transforms import apply

# Our compiled kernels run their own threads (screen bands, pixel rows). OpenBLAS's threads,
# started by numpy's small matrix products, would spin-wait on the same two cores between our
# calls: measured here, a 100k-triangle Gouraud frame took 92 ms with them and 17 ms without.
threadpool_limits(limits=1, user_api="blas")

_planes_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_buffers: dict[tuple[int, int], VisibilityBuffer] = {}


def _face_planes(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Unnormalised outward normals ``(T, 3)`` and plane constants ``n·v0`` ``(T,)``."""
    if mesh not in _planes_cache:
        p, t = mesh.positions, mesh.triangles
        v0 = p[t[:, 0]]
        normal = np.cross(p[t[:, 1]] - v0, p[t[:, 2]] - v0)
        _planes_cache[mesh] = (normal, np.einsum("ij,ij->i", normal, v0))
    return _planes_cache[mesh]


def front_faces(scene, eye) -> np.ndarray | None:
    """Indices (into all meshes' triangles, in scene order) of the faces that may be seen.

    None when no mesh is closed (nothing is culled). Faces exactly edge-on are kept.
    """
    if not any(m.closed and len(m.triangles) for m in scene.meshes):
        return None
    keep = []
    for mesh in scene.meshes:
        if not mesh.closed:
            keep.append(np.ones(len(mesh.triangles), dtype=bool))
            continue
        normal, d = _face_planes(mesh)
        if eye.point is not None:
            keep.append(normal @ eye.point - d >= 0.0)
        else:
            keep.append(normal @ eye.direction >= 0.0)
    return np.flatnonzero(np.concatenate(keep))


def _visibility_buffer(width: int, height: int) -> VisibilityBuffer:
    """One buffer per framebuffer size, reused from frame to frame (the z-buffer's memory)."""
    if (width, height) not in _buffers:
        _buffers.clear()                    # a resize drops the old size
        _buffers[(width, height)] = VisibilityBuffer.allocate(width, height)
    return _buffers[(width, height)]


def render_solid(frame, scene, view, projection, shading, n, z_min, vp, timer) -> None:
    """Draw every triangle of ``scene`` into ``frame.color`` with ``shading``."""
    stats = frame.stats
    height, width = frame.color.shape[:2]
    eye = shade.eye_from_view(view, projection)
    inputs = shade.prepare(shading, scene, eye)
    stats["computed"].extend(inputs.computed)
    timer.lap("shade: vertex step")

    points = apply(n, inputs.positions)[:, :3]
    timer.lap("normalize")

    kept = front_faces(scene, eye)
    triangles = inputs.triangles if kept is None else inputs.triangles[kept]
    if kept is not None:
        stats["computed"].append("back-face culling")
        stats["culled"] = int(len(inputs.triangles) - len(kept))
    timer.lap("cull back faces")

    clipped = clip_triangles(points, triangles, inputs.vertex_attrs, projection, z_min)
    source = clipped.source if kept is None else kept[clipped.source]
    stats["triangles in"] = int(len(inputs.triangles))
    stats["triangles rasterized"] = int(len(clipped.triangles))
    timer.lap("clip triangles")

    device, inv_w = project.project_triangles(clipped.points, projection, z_min, vp)
    timer.lap("project")

    vis = rasterize(device, inv_w, clipped.triangles, width, height,
                    out=_visibility_buffer(width, height))
    stats["allocated"].append("depth")
    timer.lap("z-buffer")

    shade.resolve(inputs, vis, clipped.triangles, clipped.attrs, source, scene.background,
                  out=frame.color)
    timer.lap("shade: pixel step")
