"""Renderers behind :func:`core.render.render`, found by name (``RenderSettings.renderer``).

A renderer is a function ``draw(scene, view, settings, frame, context, timer)`` that fills
``frame.color`` (every pixel) for a view already checked to be valid, and records what it did
in ``frame.stats``. It may draw one sample per pixel only: the front door runs it once per film
sample when ``settings.samples > 1`` unless it says it samples pixels itself
(``samples_itself=True``, as a ray caster does).

Each renderer is one package here, ``core/renderers/<name>/``, all of one shape:

- ``draw.py``: ``draw``, the registered function;
- ``inspect.py``: ``inspect_pixel``, its pixel inspector (and ``buffers``, its buffer views);
- where it has them, ``plan.py`` (its stages in the plan, importing nothing heavy),
  ``options.py`` (its settings, a frozen dataclass) and ``progressive.py`` (its drawer for
  the window's pictures on the way).

One :func:`register_renderer` line below names them by module path, so that choosing a
renderer imports it (and its compiled kernels) only when it is first used, and planning a
frame imports only its stages. The algorithms a renderer draws with are systems outside this
package, which it imports: the pipeline (:mod:`core.pipeline`), the visible-surface
algorithms (:mod:`core.visibility`), the ray tracer's BVH and ray tree (:mod:`core.raytrace`),
radiosity's solvers (:mod:`core.radiosity`), the path tracer's kernel
(:mod:`core.pathtrace`), the two-pass method's second pass (:mod:`core.twopass`) and the
volumes' data, marching cubes and marcher (:mod:`core.volume`).

To add a renderer, copy a package such as ``core/renderers/raycast/`` and add one
:func:`register_renderer` line below.

- ``zbuffer``: the FvDFH pipeline, lines and triangles (:mod:`core.renderers.zbuffer`);
- ``bsp``, ``depth-sort``: the painter's algorithms (:mod:`core.renderers.painters`);
- ``scanline``: Watkins' scan-line visible-surface algorithm (:mod:`core.renderers.scanline`);
- ``raycast``: the exact analytic surfaces of ``scene.primitives`` (:mod:`core.renderers.raycast`);
- ``raytrace``: the Whitted ray tracer (:mod:`core.renderers.raytrace`);
- ``radiosity``: radiosity, drawn Gouraud by the z-buffer (:mod:`core.renderers.radiosity`);
- ``pathtrace``: the path tracer (:mod:`core.renderers.pathtrace`);
- ``twopass``: the two-pass method, radiosity's solution for the diffuse part and Whitted's
  rays for the specular part (:mod:`core.renderers.twopass`);
- ``volume``: the opaque geometry by the z-buffer, then the scene's volumes ray-marched
  (emission–absorption, MIP), cut at the z-buffer's depth (:mod:`core.renderers.volume`).
"""

from __future__ import annotations

from core.registry import (Renderer, get_renderer, names_that, register_renderer,  # noqa: F401
                           renderer_names, renderers, unregister_renderer)

# The built-in renderers: their functions, and what each can do (core/registry.py names
# the fields).
register_renderer("zbuffer", "core.renderers.zbuffer.draw:draw",
                  inspector="core.renderers.zbuffer.inspect:inspect_pixel",
                  description="the FvDFH viewing pipeline: clip, project, scan-line z-buffer",
                  label="Z-buffer", transparency=True, shaders=True, rasterizes=True,
                  triangle_ids=True, drawn_by="z-buffer, {settings.rasterizer} rasterizer",
                  status="", key="R", bench="zbuffer")
register_renderer("raycast", "core.renderers.raycast.draw:draw", samples_itself=True,
                  inspector="core.renderers.raycast.inspect:inspect_pixel",
                  description="the analytic surfaces ray-cast exactly (the reference)",
                  label="Ray cast (exact analytic surfaces)", in_menu=False, ray_depth=True,
                  analytic=True,
                  drawn_by="ray cast (exact)")
register_renderer("raytrace", "core.renderers.raytrace.draw:draw", samples_itself=True,
                  inspector="core.renderers.raytrace.inspect:inspect_pixel",
                  description="Whitted ray tracing: shadows, mirrors, glass (core.raytrace)",
                  label="Ray traced", recursive=True, progressive=True, analytic=True,
                  progressive_drawer="core.renderers.raytrace.progressive:trace_progressively",
                  options="core.renderers.raytrace.options:RaytraceOptions", ray_depth=True,
                  blur_per_ray=True, drawn_by="ray traced", status="ray traced", key="R",
                  title="ray traced", bench="raytrace",
                  warm_up=(("ray traced (Whitted)", "closed", {"shading": "phong"}),))
register_renderer("radiosity", "core.renderers.radiosity.draw:draw",
                  inspector="core.renderers.radiosity.inspect:inspect_pixel",
                  description="radiosity (hemicube or ray-cast form factors, progressive "
                              "refinement), drawn Gouraud by the z-buffer (core.radiosity)",
                  label="Radiosity", emitters=True, textures=False, progressive=True,
                  progressive_drawer="core.renderers.radiosity.progressive:"
                                     "radiosity_progressively",
                  options="core.renderers.radiosity.options:RadiosityOptions",
                  drawn_by="radiosity ({options.form_factors} form factors, {options.solver})",
                  status="radiosity", title="radiosity", bench="gi",
                  warm_up=tuple((f"radiosity ({method})", "box",
                                 {"form_factors": method, "max_elements": 64,
                                  "hemicube_resolution": 16})
                                for method in ("hemicube", "raycast")),
                  quick={"hemicube_resolution": 16, "max_elements": 64, "converge": 0.99})
register_renderer("pathtrace", "core.renderers.pathtrace.draw:draw", samples_itself=True,
                  inspector="core.renderers.pathtrace.inspect:inspect_pixel",
                  description="Kajiya's rendering equation by path tracing on the BVH "
                              "(core.pathtrace)",
                  label="Path traced", emitters=True, recursive=True, caustics=True,
                  textures=False,
                  progressive=True,
                  progressive_drawer="core.renderers.pathtrace.progressive:"
                                     "pathtrace_progressively",
                  samples_at_rest=256,
                  options="core.renderers.pathtrace.options:PathtraceOptions",
                  drawn_by="path traced, {settings.samples} paths per pixel, "
                           "{options.sampler}",
                  status="path traced", title="path traced", bench="gi",
                  warm_up=(("path traced", "box", {}),), quick={"samples": 1})
register_renderer("twopass", "core.renderers.twopass.draw:draw",
                  inspector="core.renderers.twopass.inspect:inspect_pixel",
                  plan_stages="core.renderers.twopass.plan:add_stages",
                  description="the two-pass method: radiosity for the diffuse part, Whitted "
                              "ray tracing for the specular part (core.twopass)",
                  label="Two-pass (radiosity, then ray tracing)", emitters=True,
                  recursive=True, textures=False, progressive=True,
                  progressive_drawer="core.renderers.radiosity.progressive:"
                                     "radiosity_progressively",
                  options="core.renderers.radiosity.options:RadiosityOptions", ray_depth=True,
                  drawn_by="two-pass: radiosity ({options.form_factors} form factors, "
                           "{options.solver}), then Whitted's eye rays",
                  status="two-pass", title="two-pass", bench="gi",
                  warm_up=(("two-pass (radiosity, then rays)", "box",
                            {"form_factors": "raycast", "max_elements": 64}),),
                  quick={"hemicube_resolution": 16, "max_elements": 64, "converge": 0.99})
register_renderer("bsp", "core.renderers.painters.draw:draw_bsp",
                  inspector="core.renderers.painters.inspect:inspect_pixel",
                  plan_stages="core.renderers.painters.plan:bsp_stages",
                  description="a BSP tree built once in world space, painted back to front",
                  label="BSP tree (painter's)", transparency=True, shaders=True,
                  options="core.renderers.painters.options:PainterOptions",
                  painting="core.visibility.paint:bsp_painting", rasterizes=True,
                  status="drawn by the BSP tree", bench="painters",
                  warm_up=(("BSP tree (painter's)", "small", {"shading": "flat"}),))
register_renderer("scanline", "core.renderers.scanline.draw:draw",
                  inspector="core.renderers.scanline.inspect:inspect_pixel",
                  plan_stages="core.renderers.scanline.plan:add_stages",
                  description="Watkins' scan-line visible-surface algorithm (FvDFH 15.6): edge, "
                              "polygon and active edge tables, depth only at span ends",
                  label="Scan line (Watkins)", transparency=True, shaders=True,
                  rasterizes=True, triangle_ids=True, bench="painters",
                  warm_up=(("scan-line visible surface (Watkins)", "small",
                            {"shading": "phong"}),))
register_renderer("depth-sort", "core.renderers.painters.draw:draw_depth_sort",
                  inspector="core.renderers.painters.inspect:inspect_pixel",
                  plan_stages="core.renderers.painters.plan:depth_sort_stages",
                  description="Newell, Newell and Sancha's depth sort, painted back to front",
                  label="Depth sort (Newell, painter's)", transparency=True, shaders=True,
                  options="core.renderers.painters.options:PainterOptions",
                  painting="core.visibility.paint:depth_sorted_painting", rasterizes=True,
                  status="drawn by the depth sort", bench="painters",
                  warm_up=(("depth sort (painter's), depth-cued", "small",
                            {"shading": "gouraud", "depth_cue": True}),))
register_renderer("volume", "core.renderers.volume.draw:draw",
                  inspector="core.renderers.volume.inspect:inspect_pixel",
                  description="volumes ray-marched (emission-absorption with gradient "
                              "shading, or MIP) over the z-buffer's opaque geometry "
                              "(core.volume)",
                  label="Volume (ray marching)", shaders=True, progressive=True,
                  volumes=True, bench="volume")


def held_instead(scene) -> list[str]:
    """What a scene that gives a surface renderer nothing to draw holds instead, one phrase
    each with the renderer that draws it: its line edges and its ray-marched volumes."""
    return [note for note in (line_edges_note(scene), volumes_note(scene)) if note]


def line_edges_note(scene) -> str | None:
    """The meshes of line edges alone, which only the z-buffer draws; None if there are none."""
    lines = [m.name for m in scene.meshes if len(m.edges) and not len(m.triangles)]
    return f"line edges ({', '.join(lines)}): drawn by the z-buffer only" if lines else None


def volumes_note(scene) -> str | None:
    """The scene's ray-marched volumes (an isosurface is a mesh) and the renderers that draw
    them; None if it has none."""
    from core.volume.data import volumes_of
    marched = [v.name for v in volumes_of(scene) if v.mode != "isosurface"]
    return (f"the volumes drawn by ray marching ({', '.join(marched)}): --renderer "
            f"{' or '.join(names_that('volumes'))} draws them" if marched else None)
