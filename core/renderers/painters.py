"""The painter's renderers: the BSP tree and the depth sort (the notes' approaches 4 and 3).

``draw_bsp`` and ``draw_depth_sort`` have the z-buffer's signature
(``draw(scene, view, settings, frame, context, timer)``) and share its stages: cull, shade
inputs, N, clip, project, the same rasterizer and the same shaders. What differs is how
visibility is decided: they find an order in which to paint the triangles, back to front, and
each later triangle simply covers what was painted before (no depth test):

- ``bsp``: the tree is built once per scene in world space (:mod:`core.visibility.bsp`), kept
  in the render context for every later view, and walked from the eye each frame;
- ``depth-sort``: Newell's sort (:mod:`core.visibility.depth_sort`) each frame, in device
  space after clipping.

Painting goes through ``core.pipeline.raster.rasterize`` unchanged: every triangle is given a
constant depth equal to its rank in the painting order, so "the nearer wins" is exactly "the
later painted wins", the painter's overwrite. The true depth of each pixel is computed
afterwards from the barycentrics (``frame.depth``, for depth cueing and transparency).

``settings.paint_first`` K paints only the first K triangles of the order (the draw-order
slider). :func:`overdraw` counts the writes per pixel; :func:`inspect_pixel` lists them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.camera.film import fill
from core.pipeline import project
from core.pipeline.raster import count_fragments
from core.renderers.zbuffer import _sample_viewport, draw_lines
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


# ------------------------------------------------------------------------------ renderers

def draw_bsp(scene, view, settings, frame, context, timer) -> None:
    """The BSP renderer: the scene's tree, walked from the eye, painted back to front."""
    _draw(scene, view, settings, frame, context, timer, _bsp_painting)


def draw_depth_sort(scene, view, settings, frame, context, timer) -> None:
    """Newell, Newell and Sancha's depth sort, painted back to front."""
    _draw(scene, view, settings, frame, context, timer, _depth_sorted_painting)


def _draw(scene, view, settings, frame, context, timer, painting) -> None:
    height, width = frame.color.shape[:2]
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = _sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    timer.lap("normalize")
    solid = settings.shading != "wireframe" and scene.triangle_count > 0
    if solid:
        p = painting(scene, view, settings, context, timer, n, z_min, vp)
        frame.stats.update(p.stats)
        _update_plan(frame, p.stats)
        vis = _paint(p, width, height, context)
        frame.stats["painted"] = int(len(p.triangles))
        timer.lap("paint", depth=vis.depth, tri=vis.tri, b1=vis.b1, b2=vis.b2)
        _resolve(p, vis, scene, settings, frame)
        frame.depth = true_depth(vis, p, context)
        timer.lap("shade: pixel step")
    else:
        fill(frame.color, scene.background)
    line_meshes = [m for m in scene.meshes
                   if settings.shading == "wireframe" or not len(m.triangles)]
    if line_meshes:
        draw_lines(frame.color, line_meshes, settings.projection, n, z_min, vp,
                   scene.line_color, context, timer, frame.stats)


def _update_plan(frame, stats) -> None:
    """Put this frame's numbers into the plan's painter stage."""
    from core.plan import Stage
    for i, stage in enumerate(frame.plan):
        if stage.name in ("BSP tree", "depth sort") and stage.runs:
            numbers = ", ".join(f"{k} {v}" for k, v in stats.get(stage.name, {}).items())
            frame.plan[i] = Stage(stage.name, True, f"{stage.reason} ({numbers})")


# ------------------------------------------------------------------------- the two orders

def scene_tree(scene, settings, context) -> bsp_tree.BSPTree:
    """The scene's BSP tree for ``settings.bsp_root``, built on first use and kept in the
    render context while the scene (and its arrays) live."""
    from core.shading.shade import geometry
    positions, triangles = geometry(scene, context)
    cache = context.cache(scene)
    key = (settings.bsp_root, settings.seed)
    held = cache.get("bsp")
    if held is None or held[0] is not triangles or held[1] is not positions:
        held = (triangles, positions, {})
        cache["bsp"] = held
    if key not in held[2]:
        held[2][key] = bsp_tree.build(positions, triangles, settings.bsp_root, settings.seed)
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
    return stages.shade.prepare(shading, scene, eye, faces=kept, context=context, lazy=False)


def _bsp_painting(scene, view, settings, context, timer, n, z_min, vp) -> Painting:
    from core.renderers import triangles as stages
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
    if settings.paint_first is not None:
        order = order[:max(settings.paint_first, 0)]
    timer.lap("BSP traversal")
    inputs = _inputs(stages, scene, settings, eye, kept, context)
    attrs = split_attributes(inputs.vertex_attrs, tree.recipe)
    timer.lap("shade: vertex step")
    points = stages.transform_affine(n, tree.points)
    clipped = stages.clip_triangles(points, tree.fragments[order], attrs, settings.projection,
                                    z_min)
    keep_order = np.argsort(clipped.source, kind="stable")     # the clipper puts cut ones last
    source = tree.source[order][clipped.source[keep_order]]
    timer.lap("clip triangles")
    device, inv_w = stages.transform_projective(
        project.triangle_matrix(settings.projection, z_min, vp), clipped.points)
    timer.lap("project")
    return Painting(device, inv_w, clipped.triangles[keep_order], clipped.attrs, source, inputs,
                    stats)


def _depth_sorted_painting(scene, view, settings, context, timer, n, z_min, vp) -> Painting:
    from core.renderers import triangles as stages
    from core.visibility.depth_sort import depth_sort
    eye = stages.shade.eye_from_view(view, settings.projection)
    positions, triangles = stages.shade.geometry(scene, context)
    kept, _ = _front_sources(stages, scene, triangles, eye, context)
    faces = triangles if kept is None else triangles[kept]
    inputs = _inputs(stages, scene, settings, eye, kept, context)
    timer.lap("shade: vertex step")
    points = stages.transform_affine(n, positions)
    clipped = stages.clip_triangles(points, faces, inputs.vertex_attrs, settings.projection, z_min)
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
    if settings.paint_first is not None:
        triangles_out = triangles_out[:max(settings.paint_first, 0)]
        source = source[:len(triangles_out)]
    attrs = split_attributes(clipped.attrs, ordered.recipe)
    stats = {"depth sort": dict(ordered.counts)}
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


def _paint(p: Painting, width, height, context):
    from core.renderers import triangles as stages
    xy_z, inv_w, triangles = paint_ranks(p)
    return stages.rasterize(xy_z, inv_w, triangles, width, height,
                            out=context.buffer("painter visibility", (width, height),
                                               lambda: stages.VisibilityBuffer.allocate(width,
                                                                                        height)))


def _resolve(p: Painting, vis, scene, settings, frame) -> None:
    from core.renderers import triangles as stages
    vis.planes = None
    if stages.shade.get_shader(p.inputs.mode).needs_derivatives:
        vis.planes = stages.barycentric_planes(p.device, p.inv_w, p.triangles)
    p.inputs.settings = settings
    p.inputs.device = (p.device, p.inv_w)
    stages.shade.resolve(p.inputs, vis, p.triangles, p.attrs, p.source, scene.background,
                         out=frame.color)


def true_depth(vis, p: Painting, context=None) -> np.ndarray:
    """``(H, W)``: the canonical depth of the painted surface at each pixel centre (larger
    nearer, -inf where nothing was painted), from the barycentrics: depth is affine in the
    screen, so its weights are the perspective-correct ones divided by 1/W, renormalised."""
    depth = np.full(vis.tri.shape, -np.inf)
    covered = vis.tri >= 0
    t = p.triangles[vis.tri[covered]]
    b = np.stack([1.0 - vis.b1[covered] - vis.b2[covered], vis.b1[covered], vis.b2[covered]], 1)
    screen = b / p.inv_w[t]
    depth[covered] = (screen * p.device[t, 2]).sum(1) / screen.sum(1)
    return depth


# ---------------------------------------------------------------- looking at the painting

def painting(scene, view, settings, context=None, timer=None) -> Painting | None:
    """The painting a frame of ``settings.renderer`` (bsp or depth-sort) would paint, or None
    when it would paint no triangle (wireframe, no triangles, an invalid view)."""
    from core.context import DEFAULT_CONTEXT
    from core.render import Timer
    context = context or DEFAULT_CONTEXT
    if settings.shading == "wireframe" or scene.triangle_count == 0 or view is None:
        return None
    width, height = settings.size
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = _sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    make = {"bsp": _bsp_painting, "depth-sort": _depth_sorted_painting}[settings.renderer]
    return make(scene, view, settings, context, timer or Timer({}), n, z_min, vp)


def overdraw(scene, view, settings, context=None) -> np.ndarray:
    """``(H, W)`` int32: how many times each pixel is written. For bsp and depth-sort every
    painted fragment covering the pixel centre is a write; for the z-buffer (any other
    renderer name) it is the number of fragments scan-converted there, each of which is
    depth-tested (an upper bound on its writes: FvDFH's cost of the z-buffer)."""
    from core.renderers import triangles as stages
    width, height = settings.size
    if settings.renderer in ("bsp", "depth-sort"):
        p = painting(scene, view, settings, context)
        if p is None:
            return np.zeros((height, width), np.int32)
        xy_z, inv_w, triangles = paint_ranks(p)
        return count_fragments(xy_z, inv_w, triangles, width, height)
    kept = {}

    def grab(stage, arrays):
        if stage == "project":
            kept["device"] = arrays["device_points"].copy()
            kept["inv_w"] = arrays["inv_w"].copy()
        if stage == "clip triangles":
            kept["triangles"] = arrays["clipped_triangles"].copy()

    from core.render import render
    render(scene, view, settings.replace(renderer="zbuffer", samples=1), context, inspect=grab)
    if "triangles" not in kept:
        return np.zeros((height, width), np.int32)
    return count_fragments(kept["device"], kept["inv_w"], kept["triangles"], width,
                                  height)


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The pixel's history (RenderDoc's pixel history): every triangle painted over pixel
    ``(x, y)`` (x right, y down, row 0 at the top), in painting order, with its colour; the
    last one is what the frame shows."""
    from core.context import DEFAULT_CONTEXT
    from core.render import render
    context = context or DEFAULT_CONTEXT
    width, height = settings.size
    frame = render(scene, view, settings.replace(samples=1), context)
    record = {"renderer": settings.renderer, "pixel": [int(x), int(y)],
              "color": [int(c) for c in frame.color[y, x]], "writes": []}
    p = painting(scene, view, settings.replace(samples=1), context)
    if p is None or frame.message:
        record["message"] = frame.message or "no triangles are painted"
        return record
    record["painted triangles"] = int(len(p.triangles))
    record.update({k: v for k, v in frame.stats.items() if k in ("BSP tree", "depth sort")})
    xy_z, inv_w, triangles = paint_ranks(p)
    from core.renderers import triangles as stages
    covered = count_fragments(xy_z, inv_w, triangles, width, height)
    if covered[y, x] == 0:
        return record
    # which painted triangles cover the pixel: rasterize only the candidates whose box holds it
    px, py = x + 0.5, height - 1 - y + 0.5
    corners = p.device[p.triangles]
    near = np.flatnonzero((corners[:, :, 0].min(1) <= px + 1) & (corners[:, :, 0].max(1) >= px - 1)
                          & (corners[:, :, 1].min(1) <= py + 1)
                          & (corners[:, :, 1].max(1) >= py - 1))
    for rank in near:
        one = stages.rasterize(xy_z[3 * rank:3 * rank + 3], inv_w[3 * rank:3 * rank + 3],
                               np.array([[0, 1, 2]], np.int64), width, height)
        if one.tri[y, x] < 0:
            continue
        single = Painting(p.device, p.inv_w, p.triangles[rank:rank + 1], p.attrs,
                          p.source[rank:rank + 1], p.inputs, {})
        vis = _paint(single, width, height, context)
        color = np.empty((height, width, 3), np.uint8)
        _resolve(single, vis, scene, settings, SimpleFrame(color))
        record["writes"].append({"rank": int(rank), "triangle": int(p.source[rank]),
                                 "color": [int(c) for c in color[y, x]],
                                 "depth": float(true_depth(vis, single)[y, x])})
    return record


@dataclass
class SimpleFrame:
    color: np.ndarray
