"""The z-buffer renderer's drawing: FvDFH's viewing pipeline for triangles and lines.

``draw(scene, view, settings, frame, context, timer)``, called by :func:`core.render.render`.
Lines (every edge in wireframe; line-only meshes always): N, Cohen–Sutherland, M_per ·
M_vv3dv, divide by W, midpoint line. Triangles: cull → shade inputs → N → clip → project →
z-buffer → resolve. Each step is one call into the module that implements it; this file only
threads arrays from one to the next and records what ran in ``frame.stats``. Whether a stage
runs is asked of its object in :mod:`core.stages`, the same one the plan asks, and each stage
that ran is named in ``frame.stats["stages run"]``:

1. ``front_faces``: back-face culling, only for meshes declared closed (``core/pipeline/cull.py``).
2. ``shade.prepare``: the mode's per-face or per-vertex work in world coordinates, for the
   faces that survived culling only.
3. ``N_per`` / ``N_par`` on every vertex, each vertex's outcode, and perspective-to-parallel
   M, M_vv3dv (``project.triangle_matrix``) with the divide by W, in one pass
   (``view_points``).
4. ``clip_triangles``: trivial accept/reject by those outcodes, Sutherland–Hodgman for the
   rest (or the kernel ``settings.clipper`` names).
5. ``transform_projective`` of the clipped points, when the clipper made new ones (else the
   device points of step 3 are the frame's).
6. ``rasterize``: the scan-line z-buffer into a visibility buffer (reused between frames).
7. ``shade.resolve``: one colour per visible pixel.
"""

from __future__ import annotations

import numpy as np

from core.camera.film import fill, sample_viewport, to_rgb8
from core.pipeline import clip, project, raster_lines
from core.stages import (CLIP_LINES, CLIP_TRIANGLES, CULL, DECIDED_BY_THE_SHADER, DEPTH_BUFFER,
                         NORMALIZE, PROJECT, SCAN_CONVERSION, SCAN_LINES, Facts, ran)
from core.transforms import apply


def draw(scene, view, settings, frame, context, timer, rasterize=None) -> None:
    """The z-buffer renderer: every triangle with ``settings.shading``, then the line edges
    (all edges in wireframe) with the midpoint line. Fills every pixel of ``frame``.
    ``rasterize``: another visible-surface stage with the rasterizer's signature (the
    scan-line renderer's Watkins), in place of the z-buffer's."""
    projection, shading = settings.projection, settings.shading
    height, width = frame.color.shape[:2]
    n, z_min = context.normalizing_transform(view, projection)
    vp = sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    timer.lap("normalize")
    ran(frame.stats, NORMALIZE, PROJECT)        # N and the viewport: every frame
    facts = Facts.of(scene, settings)           # what the plan's stages decide from
    if CLIP_TRIANGLES.runs(facts):              # the triangles' stages run together, or none
        draw_triangles(frame, scene, view, projection, shading, n, z_min, vp, context, timer,
                       settings, rasterize, facts)
    else:
        fill(frame.color, scene.background)
    if CLIP_LINES.runs(facts):
        line_meshes = [m for m in scene.meshes if shading == "wireframe" or not len(m.triangles)]
        draw_lines(frame.color, line_meshes, projection, n, z_min, vp, scene.line_color, context,
                   timer, frame.stats, settings.clipper, settings.antialias_lines)


# From this many edges a mesh's lines go through the compiled loop (core/pipeline/wireframe.py,
# the same pixels): below it the numpy stages need no numba at start-up (the house: 15 edges).
# Measured: at 5,000 a 1k-triangle wireframe took 4.4 ms CPU in numpy, 0.85 compiled.
COMPILED_LINES_FROM = 256


def draw_lines(color, meshes, projection, n, z_min, vp, line_color, context, timer,
               stats, clipper: str = "cohen-sutherland", antialias: bool = False) -> None:
    """Wireframe: transform, clip (Cohen–Sutherland, or ``clipper``), M_per · M_vv3dv, divide,
    scan-convert."""
    drawn = 0
    for mesh in meshes:
        cache = context.cache(mesh)
        if cache.get("edges", (None,))[0] is not mesh.triangles:
            cache["edges"] = (mesh.triangles, mesh.all_edges())
        edges = cache["edges"][1]
        if len(edges) == 0:
            continue
        if len(edges) >= COMPILED_LINES_FROM and clipper == "cohen-sutherland" and not antialias:
            from core.shading import stages  # noqa: F401 (one BLAS thread, see there)
            from core.pipeline.wireframe import draw_edges
            points = apply(n, mesh.positions)[:, :3]     # as the numpy path: the same pixels
            timer.lap("normalize")
            drawn += draw_edges(points, edges, clip.planes(projection, z_min),
                                project.line_matrix(projection, vp), color, to_rgb8(line_color))
            timer.lap("scan-convert lines")
            continue
        points = apply(n, mesh.positions)[:, :3]
        timer.lap("normalize")
        q0, q1 = clip.clip_lines_with(clipper, points[edges[:, 0]], points[edges[:, 1]],
                                      projection, z_min)
        timer.lap("clip lines")
        d0 = project.project_lines(q0, projection, vp)
        d1 = project.project_lines(q1, projection, vp)
        timer.lap("project")
        (raster_lines.draw_lines_wu if antialias else raster_lines.draw_lines)(
            color, d0, d1, to_rgb8(line_color))
        timer.lap("scan-convert lines")
        drawn += len(q0)
    stats["segments drawn"] = drawn
    stats["computed"].append("line clipping")
    ran(stats, CLIP_LINES, SCAN_LINES)


def draw_triangles(frame, scene, view, projection, shading, n, z_min, vp, context,
                   timer, settings=None, visible_surface=None, facts=None) -> None:
    """Draw every triangle of ``scene`` into ``frame.color`` with ``shading``; with
    ``settings.rasterizer`` "scanline" the course's ET/AET algorithm scan-converts
    (screen-linear weights); ``visible_surface`` (a rasterizer's signature) replaces both.
    ``facts``: what the stages decide from (default: the scene and ``shading``)."""
    rasterizer = settings.rasterizer if settings is not None else "edge"
    facts = facts or Facts(scene, projection, shading)
    from core.shading import stages      # the compiled stages, on first use
    from core.texture.shaders import shading_for        # textured materials: Phong of their own
    shading = shading_for(scene, shading)
    stats = frame.stats
    height, width = frame.color.shape[:2]
    eye = context.eye(view, projection)
    positions, all_triangles = stages.shade.geometry(scene, context)
    culled = (stages.front_faces(scene.meshes, all_triangles, eye, context)
              if CULL.runs(facts) else None)
    kept, triangles = (None, all_triangles) if culled is None else culled
    if kept is not None:
        ran(stats, CULL)
        stats["computed"].append("back-face culling")
        stats["culled"] = int(len(all_triangles) - len(kept))
    timer.lap("cull back faces")

    inputs = stages.shade.prepare(shading, scene, eye, faces=kept, context=context,
                                  lazy=stages.shade.defers_lighting(
                                      stages.shade.get_shader(shading), scene, width * height),
                                  settings=settings)
    stats["computed"].extend(inputs.computed)
    # the shading mode's own vertex step decided these; it names what it computed
    ran(stats, *(name for name in inputs.computed if name in DECIDED_BY_THE_SHADER))
    timer.lap("shade: vertex step", vertex_attrs=inputs.vertex_attrs,
              **({} if inputs.face_rgb is None else {"face_rgb": inputs.face_rgb}))

    clipper = settings.clipper if settings is not None else "cohen-sutherland"
    clipped, source, device, inv_w = _clip_and_project(positions, triangles, kept, inputs, n,
                                                       projection, z_min, vp, context, stats,
                                                       timer, clipper)
    vis = _visible_surfaces(device, inv_w, clipped.triangles, width, height, rasterizer,
                            visible_surface, shading, context, stats,
                            timer)
    inputs.device = (device, inv_w)         # exact (u, v) derivatives per triangle
    stages.shade.resolve(inputs, vis, clipped.triangles, clipped.attrs, source, scene.background,
                         out=frame.color, trusted=True)     # our clipper's and rasterizer's
    frame.depth = vis.depth
    timer.lap("shade: pixel step")


def _clip_and_project(positions, triangles, kept, inputs, n, projection, z_min, vp, context,
                      stats, timer, clipper):
    """Normalize, clip and project the kept triangles: (the clipped triangles, the scene
    triangle each came from, their device points, 1/W)."""
    from core.shading import stages
    count = len(positions)
    points = context.scratch("canonical points", (count, 3))
    codes = context.scratch("outcodes", (count,), np.uint8)
    m = context.remembered("triangle matrix", (projection, z_min, vp),
                           lambda: project.triangle_matrix(projection, z_min, vp))
    device = context.scratch("device points", (count, 3))
    inv_w = context.scratch("1/W", (count,))
    # N, the outcodes and M with the divide, in one pass over the vertices
    any_outside = stages.view_points(n, m, positions, projection == "perspective", z_min,
                                     points, codes, device, inv_w)
    timer.lap("normalize", canonical_points=points)

    clipped = stages.clip_triangles(points, triangles, inputs.vertex_attrs, projection, z_min,
                                    before_clip=inputs.before_clip, clipper=clipper,
                                    codes_found=(codes, any_outside))
    source = clipped.source if kept is None else kept[clipped.source]
    stats["triangles in"] = int(len(inputs.triangles))
    stats["triangles rasterized"] = int(len(clipped.triangles))
    ran(stats, CLIP_TRIANGLES)
    timer.lap("clip triangles", clipped_points=clipped.points, clipped_attrs=clipped.attrs,
              clipped_triangles=clipped.triangles, source=source)

    if clipped.points is not points:        # the clipper made new points: project them all
        count = len(clipped.points)
        device, inv_w = stages.transform_projective(
            m, clipped.points, out=context.scratch("clipped device points", (count, 3)),
            inv_w=context.scratch("clipped 1/W", (count,)))
    timer.lap("project", device_points=device, inv_w=inv_w)
    return clipped, source, device, inv_w


def _visible_surfaces(device, inv_w, triangles, width, height, rasterizer, visible_surface,
                      shading, context, stats, timer):
    """Scan-convert into the visibility buffer (depth, triangle, barycentrics) with the edge
    or scan-line rasterizer, or ``visible_surface`` when given."""
    from core.shading import stages
    rasterize = stages.rasterize
    if rasterizer == "scanline":
        from core.pipeline.raster_scanline import rasterize
    if visible_surface is not None:
        rasterize, rasterizer = visible_surface, getattr(visible_surface, "name", "other")
    stats["rasterizer"] = rasterizer
    # the barycentrics only for a shader that reads them, or an inspection that shows them
    weights = {} if rasterize is not stages.rasterize else {
        "barycentrics": (stages.shade.get_shader(shading).barycentrics
                         or getattr(timer, "keeps_arrays", False))}
    vis = rasterize(device, inv_w, triangles, width, height,
                    out=context.buffer("visibility", (width, height),
                                       lambda: stages.VisibilityBuffer.allocate(width, height)),
                    **weights)
    if rasterize is not stages.rasterize:
        vis.forget_spans()       # speed: the edge rasterizer clears and shades only its spans
    stats["allocated"].append("depth")
    ran(stats, DEPTH_BUFFER, getattr(visible_surface, "stage", SCAN_CONVERSION.name))
    vis.planes = None
    if stages.shade.get_shader(shading).needs_derivatives:
        vis.planes = stages.barycentric_planes(device, inv_w, triangles)
        stats["computed"].append("barycentric derivatives")
    timer.lap(getattr(visible_surface, "stage", "z-buffer"), depth=vis.depth, tri=vis.tri,
              b1=vis.b1, b2=vis.b2)
    return vis
