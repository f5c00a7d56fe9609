"""Painting triangles in a given order through the unchanged rasterizer: what the painter's
renderers (:mod:`core.renderers.painters`) and transparency (:mod:`core.effects.transparency`)
share.

A :class:`Painting` is a list of triangles in painting order, already clipped and projected,
with the shader's attributes. :func:`painting` makes one for a view (the BSP tree's walk or
Newell's sort: the ``painting`` of ``settings.renderer``'s registry entry); :func:`paint`
rasterizes it with every triangle at the constant depth of its rank in the order, so "the
nearer wins" is exactly "the later painted wins", the painter's overwrite; :func:`true_depth`
recovers each pixel's real depth from the barycentrics afterwards.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.pipeline import project
from core.camera.film import sample_viewport
from core.registry import get_renderer, load
from core.visibility import bsp as bsp_tree


@dataclass
class Painting:
    """Triangles in painting order, projected: ``device`` (V, 3) and ``inv_w`` (V,), the
    ``triangles`` (F, 3) over them with the shader's ``attrs`` (V, K), and ``source`` (F,) the
    scene triangle each one is (part of). ``inputs`` is the shader's vertex step."""

    device: np.ndarray
    inv_w: np.ndarray
    triangles: np.ndarray
    attrs: np.ndarray
    source: np.ndarray
    inputs: object
    stats: dict


# ------------------------------------------------------------------------- the two orders

def scene_tree(scene, settings, context) -> bsp_tree.BSPTree:
    """The scene's BSP tree for the painters' ``bsp_root``, built on first use and kept in
    the render context while the scene (and its arrays) live."""
    from core.shading.shade import geometry
    positions, triangles = geometry(scene, context)
    cache = context.cache(scene)
    root_rule = settings.options_of("bsp").bsp_root
    key = (root_rule, settings.seed)
    held = cache.get("bsp")
    if held is None or held[0] is not triangles or held[1] is not positions:
        held = (triangles, positions, {})
        cache["bsp"] = held
    if key not in held[2]:
        held[2][key] = bsp_tree.build(positions, triangles, root_rule, settings.seed)
    return held[2][key]


def _front_sources(stages, scene, triangles, eye, context):
    """``(kept faces or None, mask (T,) of the faces that may be seen)``."""
    culled = stages.front_faces(scene.meshes, triangles, eye, context)
    if culled is None:
        return None, None
    kept = culled[0].copy()
    mask = np.zeros(len(triangles), np.bool_)
    mask[kept] = True
    return kept, mask


def _inputs(stages, scene, settings, eye, kept, context):
    from core.texture.shaders import shading_for
    shading = shading_for(scene, settings.shading)
    return stages.shade.prepare(shading, scene, eye, faces=kept, context=context, lazy=False,
                                settings=settings)


def bsp_painting(scene, view, settings, context, timer, n, z_min, vp) -> Painting:
    from core.shading import stages
    eye = stages.shade.eye_from_view(view, settings.projection)
    positions, triangles = stages.shade.geometry(scene, context)
    tree = scene_tree(scene, settings, context)
    timer.lap("BSP tree")
    order = bsp_tree.back_to_front(tree, eye)
    kept, mask = _front_sources(stages, scene, triangles, eye, context)
    stats = {"BSP tree": tree.stats()}
    if mask is not None:
        order = order[mask[tree.source[order]]]
        stats["culled"] = int(len(triangles) - len(kept))
    stats["painted total"] = int(len(order))      # before the draw-order slider's cut
    first = settings.options_of("bsp").paint_first        # the draw-order slider
    if first is not None:
        order = order[:max(first, 0)]
    timer.lap("BSP traversal")
    inputs = _inputs(stages, scene, settings, eye, kept, context)
    attrs = split_attributes(inputs.vertex_attrs, tree.recipe)
    timer.lap("shade: vertex step")
    points = stages.transform_affine(n, tree.points)
    clipped = stages.clip_triangles(points, tree.fragments[order], attrs, settings.projection,
                                    z_min, clipper=settings.clipper)
    keep_order = np.argsort(clipped.source, kind="stable")     # the clipper puts cut ones last
    source = tree.source[order][clipped.source[keep_order]]
    timer.lap("clip triangles")
    device, inv_w = stages.transform_projective(
        project.triangle_matrix(settings.projection, z_min, vp), clipped.points)
    timer.lap("project")
    return Painting(device, inv_w, clipped.triangles[keep_order], clipped.attrs, source, inputs,
                    stats)


def depth_sorted_painting(scene, view, settings, context, timer, n, z_min, vp) -> Painting:
    from core.shading import stages
    from core.visibility.depth_sort import depth_sort
    eye = stages.shade.eye_from_view(view, settings.projection)
    positions, triangles = stages.shade.geometry(scene, context)
    kept, _ = _front_sources(stages, scene, triangles, eye, context)
    faces = triangles if kept is None else triangles[kept]
    inputs = _inputs(stages, scene, settings, eye, kept, context)
    timer.lap("shade: vertex step")
    points = stages.transform_affine(n, positions)
    clipped = stages.clip_triangles(points, faces, inputs.vertex_attrs, settings.projection, z_min,
                                    clipper=settings.clipper)
    timer.lap("clip triangles")
    device, inv_w = stages.transform_projective(
        project.triangle_matrix(settings.projection, z_min, vp), clipped.points)
    timer.lap("project")
    ordered = depth_sort(device, inv_w, clipped.triangles)
    timer.lap("depth sort")
    source = clipped.source[ordered.source]
    if kept is not None:
        source = kept[source]
    triangles_out = ordered.triangles
    total = int(len(triangles_out))
    first = settings.options_of("depth-sort").paint_first  # the draw-order slider
    if first is not None:
        triangles_out = triangles_out[:max(first, 0)]
        source = source[:len(triangles_out)]
    attrs = split_attributes(clipped.attrs, ordered.recipe)
    stats = {"depth sort": dict(ordered.counts), "painted total": total}
    if kept is not None:
        stats["culled"] = int(len(triangles) - len(kept))
    return Painting(ordered.device, ordered.inv_w, triangles_out, attrs, source, inputs, stats)


def split_attributes(attrs: np.ndarray, recipe: np.ndarray) -> np.ndarray:
    """``attrs`` (V, K) followed by one row per split vertex, ``(1 - t) A_a + t A_b`` for
    each ``(a, b, t)`` of ``recipe``, in order (a split vertex may be cut again)."""
    attrs = np.ascontiguousarray(attrs, dtype=np.float64)
    out = np.empty((len(attrs) + len(recipe), attrs.shape[1]))
    out[:len(attrs)] = attrs
    if len(recipe) and attrs.shape[1]:
        _interpolate_rows(out, len(attrs), recipe)
    return out


def _interpolate_rows(out, start, recipe):
    from core.visibility._kernels import interpolate_rows
    interpolate_rows(out, start, np.ascontiguousarray(recipe))


# ---------------------------------------------------------------------------------- paint

def paint_ranks(p: Painting):
    """Each triangle on its own three vertices with the constant depth of its paint rank
    (later nearer), for ``rasterize``: ``(xy_z (3F, 3), inv_w (3F,), triangles (3F/3, 3))``."""
    count = len(p.triangles)
    corners = p.triangles.reshape(-1)
    xy_z = p.device[corners].copy()
    xy_z[:, 2] = np.repeat(-1.0 + (np.arange(count) + 1.0) / (count + 1.0), 3)
    return xy_z, p.inv_w[corners], np.arange(3 * count, dtype=np.int64).reshape(-1, 3)


def paint(p: Painting, width, height, context):
    from core.shading import stages
    xy_z, inv_w, triangles = paint_ranks(p)
    return stages.rasterize(xy_z, inv_w, triangles, width, height,
                            out=context.buffer("painter visibility", (width, height),
                                               lambda: stages.VisibilityBuffer.allocate(width,
                                                                                        height)))


def resolve(p: Painting, vis, scene, settings, frame) -> None:
    from core.shading import stages
    vis.planes = None
    if stages.shade.get_shader(p.inputs.mode).needs_derivatives:
        vis.planes = stages.barycentric_planes(p.device, p.inv_w, p.triangles)
    p.inputs.device = (p.device, p.inv_w)
    stages.shade.resolve(p.inputs, vis, p.triangles, p.attrs, p.source, scene.background,
                         out=frame.color, trusted=True)     # our clipper's and rasterizer's


def true_depth(vis, p: Painting, context=None) -> np.ndarray:
    """``(H, W)``: the canonical depth of the painted surface at each pixel centre (larger
    nearer, -inf where nothing was painted), from the barycentrics: depth is affine in the
    screen, so its weights are the perspective-correct ones divided by 1/W, renormalised."""
    from core.visibility._kernels import depth_from_barycentrics
    depth = (np.empty(vis.tri.shape) if context is None
             else context.scratch("painted depth", vis.tri.shape))
    depth_from_barycentrics(np.ascontiguousarray(vis.tri, dtype=np.int32), vis.b1, vis.b2,
                            np.ascontiguousarray(p.triangles), p.device, p.inv_w, depth)
    return depth


def painting(scene, view, settings, context=None, timer=None, order=None) -> Painting | None:
    """The painting a frame of ``settings.renderer`` (a painter: its registry entry's
    ``painting``) would paint, or None when it would paint no triangle (wireframe, no
    triangles, an invalid view). ``order``: another painting function (transparency's)."""
    from core.context import DEFAULT_CONTEXT
    context = context or DEFAULT_CONTEXT
    if settings.shading == "wireframe" or scene.triangle_count == 0 or view is None:
        return None
    order = order or get_renderer(settings.renderer).painting
    if order is None:
        raise ValueError(f"the {settings.renderer} renderer paints in no order (it is not a "
                         f"painter's)")
    width, height = settings.size
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    return load(order)(scene, view, settings, context, timer or _NoClock(), n, z_min, vp)



class _NoClock:
    """A stand-in for the front door's per-stage clock when nobody times the stages."""

    def lap(self, stage, **arrays) -> None:
        pass


@dataclass
class SimpleFrame:
    color: np.ndarray
