"""The ``"radiosity"`` renderer: solve once per scene, then every view is a z-buffer frame.

The solution (:func:`core.radiosity.solution.solve`) does not depend on the view; it is kept
in the :class:`core.context.RenderContext` with the scene, keyed by the settings it depends
on, so moving the camera costs one Gouraud frame. Element radiosities go to the vertices
(area-weighted within each surface, :func:`core.radiosity.mesh.vertex_values`) and are drawn by
the z-buffer (:func:`core.renderers.zbuffer.draw.draw_triangles`) with the ``"radiosity"`` shader
of the registry: the vertex values are the colours, interpolated as Gouraud's are. Pixel values
are radiosities clamped to [0, 1] (``scene.tone`` "srgb": through the sRGB curve first).

Display meshes: the two-sided pairs are one mesh marked closed, so back-face culling shows
each side's own copy; the one-sided elements another, drawn from both sides.

What one pixel shows (its element, emission, reflectance, radiosity and the vertex values
interpolated there) is told by :mod:`core.renderers.radiosity.inspect`.
"""

from __future__ import annotations

import numpy as np

from core.camera.film import fill
from core.radiosity.mesh import Elements, has_light, vertex_values
from core.radiosity.solution import Options, Solution, solve
from core.radiosity.tone import tone_map
from core.scene.model import Material, Mesh, Scene

SHADER = "radiosity"


def _register_shader() -> None:
    from core.shading.gouraud import resolve_gouraud
    from core.shading.registry import Shader, register_shader
    from core.arrays import read_only
    from core.shading.shade import concatenated, covered_spans

    def vertex(s, scene, meshes, weighting) -> None:
        s.vertex_attrs = np.ascontiguousarray(concatenated(
            s.context, scene, meshes, "radiosity", lambda m: m.extra["radiosity"], 3))
        s.computed.append("radiosity at vertices")

    def pixel(s, vis, triangles, attrs, source, background8, out) -> None:
        resolve_gouraud(np.ascontiguousarray(vis.tri, dtype=np.int32),
                         np.ascontiguousarray(vis.b1, dtype=np.float64),
                         np.ascontiguousarray(vis.b2, dtype=np.float64), covered_spans(vis),
                         triangles, read_only(attrs), out)

    register_shader(Shader(SHADER, vertex, pixel, varyings=("rgb",), width=3,
                           description="radiosity at the vertices, interpolated (Gouraud)"))


_register_shader()


def display_scene(scene, solution: Solution) -> Scene:
    """The elements as meshes whose vertices carry the shown radiosity (``extra["radiosity"]``)."""
    e = solution.elements
    values = tone_map(solution.shown(), scene.tone)
    meshes = []
    for two_sided in (False, True):
        rows = np.flatnonzero(e.two_sided == two_sided)
        if not len(rows):
            continue
        part = Elements(**{k: (getattr(e, k)[rows] if k in _ELEMENT_FIELDS else getattr(e, k))
                           for k in Elements.__dataclass_fields__})
        positions, triangles, at_vertex = vertex_values(part, values[rows])
        meshes.append(Mesh(positions, triangles, closed=two_sided, material=Material(),
                           name=f"elements ({'two' if two_sided else 'one'}-sided)",
                           extra={"radiosity": at_vertex}))
        meshes[-1].element_rows = rows   # display triangle k is element rows[k] (the inspector)
    return Scene(name=scene.name, meshes=meshes, views=[], lights=[], ambient=(0, 0, 0),
                 background=scene.background, shading="gouraud")


_ELEMENT_FIELDS = ("corners", "patch", "area", "normal", "centre", "rho", "emission", "surface",
                   "mesh", "two_sided")


def solution_for(scene, settings, context) -> Solution:
    """The scene's solution for these settings, solved on first use and kept in ``context``."""
    cache = context.cache(scene)
    options = Options.from_settings(settings)
    held = cache.get("radiosity solution")
    if held is None or held.options != options:
        held = solve(scene, options)
        cache["radiosity solution"] = held
        cache.pop("radiosity display", None)
    return held


def use_solution(scene, solution: Solution, context) -> None:
    """Show ``solution`` (a loaded or a progressive one) for ``scene`` in ``context``."""
    cache = context.cache(scene)
    cache["radiosity solution"] = solution
    cache.pop("radiosity display", None)


def display(scene, solution, context) -> Scene:
    cache = context.cache(scene)
    held = cache.get("radiosity display")
    if held is None or held[0] is not solution:
        held = (solution, display_scene(scene, solution))
        cache["radiosity display"] = held
    return held[1]


def solved_or_said(scene, settings, frame, context):
    """The scene's radiosity solution (one loaded with ``--solution`` first), or None with
    the frame black and the reason in it: nothing emits light (a warning), or the scene
    cannot be solved (its message). The radiosity and two-pass renderers start here."""
    if not has_light(scene):
        fill(frame.color, (0.0, 0.0, 0.0))
        frame.stats.setdefault("warnings", []).append(
            f"{scene.name}: nothing emits light (no material with emission, no [[light]] "
            "of any intensity): the picture is black")
        return None
    try:
        held = context.cache(scene).get("radiosity solution")
        if held is not None and held.stats.get("loaded"):
            return held
        return solution_for(scene, settings, context)
    except ValueError as error:          # RadiosityError: a material, a zero-area scene
        fill(frame.color, (0.0, 0.0, 0.0))
        frame.message = f"{scene.name}: cannot solve for radiosity: {error}"
        return None


def draw(scene, view, settings, frame, context, timer) -> None:
    """Fill ``frame`` with the radiosity solution of ``scene`` seen through ``view``."""
    from core.pipeline import project
    from core.camera.film import sample_viewport
    from core.renderers.zbuffer.draw import draw_triangles
    solution = solved_or_said(scene, settings, frame, context)
    if solution is None:
        return
    timer.lap("radiosity solution")
    shown = display(scene, solution, context)
    n, z_min = context.normalizing_transform(view, settings.projection)
    height, width = frame.color.shape[:2]
    vp = sample_viewport(project.viewport(view.window, width, height, settings.keep_aspect),
                          settings.pixel_offset)
    draw_triangles(frame, shown, view, settings.projection, SHADER, n, z_min, vp, context,
                   timer, settings)
    frame.stats["radiosity"] = {k: v for k, v in solution.stats.items() if k != "rounds"}
    frame.stats["computed"].append("radiosity")


def radiosity_image(solution: Solution, view, projection: str, width: int, height: int
                    ) -> np.ndarray:
    """(H, W, 3) float: the displayed radiosity (vertex values interpolated, no ambient
    term, no tone) at each pixel centre, found by casting a ray per pixel into the elements
    (the oracle tests compare it with the path tracer's radiance)."""
    from core.camera.rays import camera_rays
    from core.raytrace.bvh import build, intersect_rays
    e = solution.elements
    positions, triangles, at_vertex = vertex_values(e, solution.radiosity)
    origins, directions, t_min, t_max = camera_rays(view, projection, width, height)
    # one-sided elements only: of a coplanar two-sided pair the ray could take either copy
    keep = np.flatnonzero(~e.two_sided)
    bvh, _ = build(positions, triangles[keep])
    prim, _, u, v = intersect_rays(bvh, origins, directions, t_min, t_max)
    tri = triangles[keep][np.maximum(prim, 0)]
    image = ((1 - u - v)[:, None] * at_vertex[tri[:, 0]] + u[:, None] * at_vertex[tri[:, 1]]
             + v[:, None] * at_vertex[tri[:, 2]])
    image[prim < 0] = 0.0
    return image.reshape(height, width, 3)
