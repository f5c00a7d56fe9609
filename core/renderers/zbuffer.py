"""The triangle pipeline: cull → shade inputs → N → clip → project → z-buffer → resolve.

Called by :func:`core.render.render` for solid shading modes. Each step is one call into the
module that implements it; this file only threads arrays from one to the next and records what
ran in ``frame.stats``:

1. ``front_faces``: back-face culling, only for meshes declared closed (``core/pipeline/cull.py``).
2. ``shade.prepare``: the mode's per-face or per-vertex work in world coordinates, for the
   faces that survived culling only.
3. ``N_per`` / ``N_par`` on every vertex.
4. ``clip_triangles``: trivial accept/reject by outcode, Sutherland–Hodgman for the rest.
5. ``transform_projective``: perspective-to-parallel M, M_vv3dv (``project.triangle_matrix``),
   divide by W.
6. ``rasterize``: the scan-line z-buffer into a visibility buffer (reused between frames).
7. ``shade.resolve``: one colour per visible pixel.
"""

from __future__ import annotations

from threadpoolctl import threadpool_limits

from core.pipeline import project
from core.shading import shade
from core.pipeline.cull import front_faces
from core.pipeline.clip_polygon import clip_triangles
from core.pipeline.raster import VisibilityBuffer, rasterize
from core.pipeline.vertex_kernels import transform_affine, transform_projective

# Our compiled kernels run their own threads (screen bands, pixel rows). OpenBLAS's threads,
# started by numpy's small matrix products, would spin-wait on the same two cores between our
# calls: measured here, a 100k-triangle Gouraud frame took 92 ms with them and 17 ms without.
threadpool_limits(limits=1, user_api="blas")

_buffers: dict[tuple[int, int], VisibilityBuffer] = {}


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
    positions, all_triangles = shade.geometry(scene)
    culled = front_faces(scene.meshes, all_triangles, eye)
    kept, triangles = (None, all_triangles) if culled is None else culled
    if kept is not None:
        stats["computed"].append("back-face culling")
        stats["culled"] = int(len(all_triangles) - len(kept))
    timer.lap("cull back faces")

    inputs = shade.prepare(shading, scene, eye, faces=kept)
    stats["computed"].extend(inputs.computed)
    timer.lap("shade: vertex step", vertex_attrs=inputs.vertex_attrs,
              **({} if inputs.face_rgb is None else {"face_rgb": inputs.face_rgb}))

    points = transform_affine(n, positions)
    timer.lap("normalize", canonical_points=points)

    clipped = clip_triangles(points, triangles, inputs.vertex_attrs, projection, z_min)
    source = clipped.source if kept is None else kept[clipped.source]
    stats["triangles in"] = int(len(inputs.triangles))
    stats["triangles rasterized"] = int(len(clipped.triangles))
    timer.lap("clip triangles", clipped_points=clipped.points, clipped_attrs=clipped.attrs,
              clipped_triangles=clipped.triangles)

    device, inv_w = transform_projective(project.triangle_matrix(projection, z_min, vp),
                                         clipped.points)
    timer.lap("project", device_points=device, inv_w=inv_w)

    vis = rasterize(device, inv_w, clipped.triangles, width, height,
                    out=_visibility_buffer(width, height))
    stats["allocated"].append("depth")
    timer.lap("z-buffer", depth=vis.depth, tri=vis.tri, b1=vis.b1, b2=vis.b2)

    shade.resolve(inputs, vis, clipped.triangles, clipped.attrs, source, scene.background,
                  out=frame.color)
    timer.lap("shade: pixel step")
