"""Which stages a scene needs: the renderer runs these and skips the rest.

``plan(scene, projection, shading)`` returns the stages in pipeline order, each with whether it
runs and why (or why not). ``python -m app plan`` prints it and the window shows it; the
renderer follows it and records what it actually allocated and computed in ``Frame.stats`` so
that tests can hold the two against each other.
"""

from __future__ import annotations

from dataclasses import dataclass

from core.registry import Renderer, get_renderer, get_shading, load, shading_modes
from core.scene.model import Scene


@dataclass(frozen=True)
class Stage:
    name: str
    runs: bool
    reason: str


def plan(scene: Scene, projection: str, shading: str, keep_aspect: bool = False,
         rasterizer: str = "edge", texture_filter: str = "trilinear",
         renderer: str = "zbuffer", transparency: str | None = None) -> list[Stage]:
    """The stages for ``scene`` drawn with ``projection`` and ``shading``, in the order the
    renderer runs them (``core/render.py``, ``core/renderers/zbuffer/draw.py``); ``keep_aspect``,
    ``rasterizer`` and ``transparency`` as in :class:`core.settings.RenderSettings`
    (``transparency`` None: what the scene asks for, else what it needs)."""
    mode = get_shading(shading)                 # ValueError naming the modes there are
    solid = mode.module is not None and scene.triangle_count > 0   # wireframe: lines only
    triangle_stage = _triangle_stage_for(scene, solid)
    stages = (_normal_and_lighting_stages(scene, shading, solid, triangle_stage)
              + _drawing_stages(scene, projection, shading, keep_aspect, rasterizer,
                                texture_filter, solid, triangle_stage))
    entry = _entry(renderer)
    if entry is not None and entry.plan_stages:      # the renderer's own stages, in place
        load(entry.plan_stages)(stages, triangle_stage, scene)
    if shading == "depth":
        _depth_shading_stages(stages, solid)
    stages.append(_transparency_stage(scene, solid, renderer, transparency))
    return stages


def _entry(renderer: str) -> Renderer | None:
    """The registry's entry of ``renderer`` (None for a name not registered: the plan of
    the z-buffer's stages alone)."""
    try:
        return get_renderer(renderer)
    except ValueError:
        return None


def _stage(name: str, runs: bool, why: str, why_not: str) -> Stage:
    return Stage(name, runs, why if runs else why_not)


def _triangle_stage_for(scene: Scene, solid: bool):
    """A stage of the triangles: when the scene draws none, why not says so instead."""
    # Why a triangle stage does not run when the scene draws no triangles at all.
    no_triangles = ("the scene has no triangles" if scene.triangle_count == 0
                    else "wireframe draws edges only")

    def triangle_stage(name: str, runs: bool, why: str, why_not: str = "") -> Stage:
        return _stage(name, runs, why, why_not if solid else no_triangles)
    return triangle_stage


def _normal_and_lighting_stages(scene: Scene, shading: str, solid: bool,
                                triangle_stage) -> list[Stage]:
    """Culling, the normals and the lighting before the projection, in the renderer's order."""
    closed = any(m.closed and len(m.triangles) for m in scene.meshes)
    mode = get_shading(shading)                 # what it computes, where it lights
    smooth = solid and mode.normals == "vertex"
    given_normals = all(m.normals is not None for m in scene.meshes if len(m.triangles))
    return [
        triangle_stage("cull back faces", solid and closed,
                       "closed, consistently wound meshes: faces turned away are never visible",
                       "no mesh is declared closed, so every face may be seen"),
        triangle_stage("face normals", solid and mode.normals == "face",
                       f"{shading} shading evaluates the model once per polygon with its "
                       "normal",
                       f"{shading} shading uses vertex normals"),
        triangle_stage("vertex normals", smooth and not given_normals,
                       f"{shading} shading needs a normal at each vertex (average of the adjacent "
                       "faces; vertices are split where faces meet beyond the crease angle)",
                       "given with the mesh (by its file or its generator)" if smooth
                       else f"{shading} shading needs no vertex normals"),
        triangle_stage("illuminate faces", solid and mode.lights == "faces",
                       "one evaluation per planar polygon, at its centroid",
                       f"not {_lit_at('faces')}"),
        triangle_stage("illuminate vertices", solid and mode.lights == "vertices",
                       "the model at each vertex; intensities are interpolated",
                       f"not {_lit_at('vertices')}"),
    ]


def _lit_at(where: str) -> str:
    """The shading modes that light at ``where`` (their entries' ``lights``), in the plan's
    words: "Gouraud shading", "Phong shading or Toon shading"."""
    return " or ".join(f"{m.label} shading" for m in shading_modes() if m.lights == where)


def _drawing_stages(scene: Scene, projection: str, shading: str, keep_aspect: bool,
                    rasterizer: str, texture_filter: str, solid: bool,
                    triangle_stage) -> list[Stage]:
    """Normalizing, clipping, projecting and scan-converting, in the renderer's order."""
    draws_lines = shading == "wireframe" or any(len(m.edges) for m in scene.meshes)
    return [
        _stage("normalize", True,
               f"{'N_per' if projection == 'perspective' else 'N_par'} carries world coordinates "
               "into the canonical volume", ""),
        _stage("clip lines", draws_lines,
               "Cohen–Sutherland: trivial accept/reject by outcode, the rest clipped plane by "
               "plane", "no edges are drawn"),
        triangle_stage("clip triangles", solid,
                       "outcodes first; only triangles that cross the volume go through "
                       "Sutherland–Hodgman"),
        _stage("project", True, _projection_reason(projection, solid, draws_lines) + "; "
               + ("the window letterboxed in the viewport (aspect kept)" if keep_aspect else
                  "the window stretched over the whole viewport (the course's M_vv3dv)"), ""),
        _stage("scan-convert lines", draws_lines, "midpoint line into the frame buffer",
               "no edges are drawn"),
        triangle_stage("depth buffer", solid, "the z-buffer needs a depth per pixel"),
        triangle_stage("z-buffer scan conversion", solid,
                       "the course's scan-line algorithm (edge table, active edge table, spans; "
                       "screen-linear interpolation) with the top-left fill rule"
                       if rasterizer == "scanline" else
                       "edge functions over each triangle's box, top-left fill rule, "
                       "perspective-correct interpolation"),
        triangle_stage("illuminate pixels", solid and get_shading(shading).lights == "pixels",
                       f"{get_shading(shading).label} shading: normals interpolated, "
                       "renormalised, the model at every pixel", f"not {_lit_at('pixels')}"),
        triangle_stage("texture lookups", *_texture_stage(scene, shading, texture_filter)),
    ]


def _transparency_stage(scene, solid, renderer, transparency) -> Stage:
    """Whether k_t > 0 is laid over the opaque picture, and why (core.effects.transparency)."""
    from core.settings import needed_transparency
    clear = [m.name or "a mesh" for m in scene.meshes if m.material.kt > 0]
    if transparency is None:
        transparency = getattr(scene, "transparency", None) or needed_transparency(scene)
    name = "transparency"
    if not clear:
        return Stage(name, False, "no material has k_t > 0")
    if not solid:
        return Stage(name, False, "no triangles are drawn")
    entry = _entry(renderer)
    if entry is not None and entry.recursive:
        return Stage(name, False, f"{renderer} refracts through k_t > 0 itself")
    if entry is not None and not entry.transparency:
        return Stage(name, False, f"{renderer} draws k_t > 0 opaque")
    if transparency == "off":
        return Stage(name, False, f"off: {', '.join(clear)} (k_t > 0) drawn opaque "
                                  "(--transparency off)")
    how = ("each transparent surface blended over what lies behind it, "
           "I = (1 - k_t) I_near + k_t I_far (FvDFH 16.5.1)" if transparency == "interpolated"
           else "a mesh of k_t's share of pixels left open (screen door)")
    return Stage(name, True, f"{transparency}: {', '.join(clear)} has k_t > 0, so the scene "
                             f"needs it (the default wherever a material is transparent; "
                             f"--transparency off draws it opaque); {how}")


def _depth_shading_stages(stages: list, solid: bool) -> None:
    """Depth shading needs no normals and no light: a colour map per pixel."""
    unlit = ("face normals", "vertex normals", "illuminate faces", "illuminate vertices",
             "illuminate pixels")
    for i, s in enumerate(stages):
        if s.name in unlit:
            stages[i] = Stage(s.name, False, "depth shading uses no normals and no light")
    at = next((i for i, s in enumerate(stages)
               if s.name in ("z-buffer scan conversion", "scan-line visible surface")), None)
    if at is None:                  # a renderer that scan-converts nothing has no colour map
        return
    stages.insert(at + 1, Stage("depth shading", solid,
                            "each pixel's height (or eye distance) through a colour map"
                            if solid else "no triangles are drawn"))


def _texture_stage(scene, shading, texture_filter):   # the texture system's own reasons
    from core.texture.material import plan_stage
    return plan_stage(scene, shading, texture_filter)


def _projection_reason(projection: str, solid: bool, lines: bool) -> str:
    if projection == "parallel":
        return "M_vv3dv onto the viewport; a parallel view needs no divide"
    steps = []
    if lines:
        steps.append("lines: M_per (d = -1), M_vv3dv, divide by W")
    if solid:
        steps.append("triangles: perspective-to-parallel M (keeps depth), M_vv3dv, divide by W")
    return "; ".join(steps)


def plan_as_dict(stages: list[Stage]) -> dict:
    """The JSON shape of ``python -m app plan``: the stages that run, and those left out with why."""
    return {
        "runs": [{"stage": s.name, "why": s.reason} for s in stages if s.runs],
        "left_out": [{"stage": s.name, "why": s.reason} for s in stages if not s.runs],
    }
