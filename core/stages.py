"""The z-buffer pipeline's stages, each with the rule that says whether it runs and why.

One :class:`PipelineStage` per stage: its name and ``decide(facts) -> (runs, reason)``, where
:class:`Facts` are the scene and the frame's settings. The plan (:func:`core.plan.plan`) asks
every stage of :data:`PIPELINE` in order; the z-buffer's draw
(:mod:`core.renderers.zbuffer.draw`) asks the same objects before it culls, draws triangles or
draws lines, and names each stage it ran in ``frame.stats["stages run"]``, so that a test holds
the plan against the draw. Where the shading mode's own step decides (normals, lighting,
textures, depth shading: :data:`DECIDED_BY_THE_SHADER`), the draw names what the shader says
it computed, and the test holds the rule below against the shader.

Not to be confused with :mod:`core.shading.stages`, the triangle path's compiled kernels.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

from core.registry import get_renderer, get_shading, shading_names, shading_modes


@dataclass(frozen=True)
class Stage:
    """A stage as planned for one frame: whether it runs, and why (or why not)."""
    name: str
    runs: bool
    reason: str


@dataclass(frozen=True)
class Facts:
    """What the stages decide from: the scene and the settings of one frame.

    ``transparency`` None: what the scene asks for, else what it needs. Each fact is worked
    out once, on first use (a few passes over the meshes, none over triangles)."""
    scene: object
    projection: str = "perspective"
    shading: str = "flat"
    keep_aspect: bool = False
    rasterizer: str = "edge"
    texture_filter: str = "trilinear"
    renderer: str = "zbuffer"
    transparency: str | None = None

    @classmethod
    def of(cls, scene, settings) -> Facts:
        """The facts of a frame drawn with ``settings`` (a RenderSettings)."""
        return cls(scene, settings.projection, settings.shading, settings.keep_aspect,
                   settings.rasterizer, settings.texture_filter, settings.renderer,
                   settings.transparency)

    @cached_property
    def mode(self):
        """The shading mode's registry entry; None for a renderer's own shader (radiosity's)."""
        return get_shading(self.shading) if self.shading in shading_names() else None

    @cached_property
    def solid(self) -> bool:
        """Are triangles drawn? (Wireframe draws edges only.)"""
        shaded = self.mode is None or self.mode.module is not None
        return shaded and self.scene.triangle_count > 0

    @cached_property
    def no_triangles(self) -> str:
        """Why a triangle stage does not run when no triangles are drawn."""
        return ("the scene has no triangles" if self.scene.triangle_count == 0
                else "wireframe draws edges only")

    @cached_property
    def draws_lines(self) -> bool:
        return self.shading == "wireframe" or any(len(m.edges) for m in self.scene.meshes)


@dataclass(frozen=True)
class PipelineStage:
    """A stage of the pipeline: its ``name`` and ``decide(facts) -> (runs, reason)``.
    ``listed(facts)``: whether this frame's pipeline has the stage at all (the colour map only
    for depth shading)."""
    name: str
    decide: Callable[[Facts], tuple[bool, str]]
    listed: Callable[[Facts], bool] = lambda facts: True

    def runs(self, facts: Facts) -> bool:
        return self.decide(facts)[0]

    def planned(self, facts: Facts) -> Stage:
        return Stage(self.name, *self.decide(facts))


def either(runs: bool, why: str, why_not: str) -> tuple[bool, str]:
    """``(runs, why)`` or ``(runs, why_not)``."""
    return runs, why if runs else why_not


def on_triangles(decide):
    """A triangle stage's rule: when no triangles are drawn, it does not run and says why."""
    def decide_on_triangles(facts: Facts) -> tuple[bool, str]:
        return decide(facts) if facts.solid else (False, facts.no_triangles)
    return decide_on_triangles


def lit(decide):
    """A stage of normals or light: depth shading needs neither (a colour map per pixel)."""
    def decide_lit(facts: Facts) -> tuple[bool, str]:
        if facts.shading == "depth":
            return False, "depth shading uses no normals and no light"
        return decide(facts)
    return decide_lit


def lit_at(where: str) -> str:
    """The shading modes that light at ``where`` (their entries' ``lights``), in the plan's
    words: "Gouraud shading", "Phong shading or Toon shading"."""
    return " or ".join(f"{m.label} shading" for m in shading_modes() if m.lights == where)


# -- before the projection: culling, the normals, the lighting ---------------------------------

def _cull(facts):
    closed = any(m.closed and len(m.triangles) for m in facts.scene.meshes)
    return either(closed, "closed, consistently wound meshes: faces turned away are never "
                          "visible", "no mesh is declared closed, so every face may be seen")


def _face_normals(facts):
    return either(facts.mode.normals == "face",
                  f"{facts.shading} shading evaluates the model once per polygon with its normal",
                  f"{facts.shading} shading uses vertex normals")


def _vertex_normals(facts):
    if facts.mode.normals != "vertex":
        return False, f"{facts.shading} shading needs no vertex normals"
    given = all(m.normals is not None for m in facts.scene.meshes if len(m.triangles))
    return either(not given, f"{facts.shading} shading needs a normal at each vertex (average "
                             "of the adjacent faces; vertices are split where faces meet beyond "
                             "the crease angle)",
                  "given with the mesh (by its file or its generator)")


def _lights_at(where: str, why: str):
    """The rule of the stage that evaluates the illumination model at ``where``."""
    def decide(facts):
        return either(facts.mode.lights == where, why, f"not {lit_at(where)}")
    return decide


CULL = PipelineStage("cull back faces", on_triangles(_cull))
FACE_NORMALS = PipelineStage("face normals", lit(on_triangles(_face_normals)))
VERTEX_NORMALS = PipelineStage("vertex normals", lit(on_triangles(_vertex_normals)))
LIGHT_FACES = PipelineStage("illuminate faces", lit(on_triangles(_lights_at(
    "faces", "one evaluation per planar polygon, at its centroid"))))
LIGHT_VERTICES = PipelineStage("illuminate vertices", lit(on_triangles(_lights_at(
    "vertices", "the model at each vertex; intensities are interpolated"))))


# -- normalizing, clipping, projecting, scan-converting -----------------------------------------

def _normalize(facts):
    return True, (f"{'N_per' if facts.projection == 'perspective' else 'N_par'} carries world "
                  "coordinates into the canonical volume")


def _clip_lines(facts):
    return either(facts.draws_lines, "Cohen–Sutherland: trivial accept/reject by outcode, the "
                  "rest clipped plane by plane", "no edges are drawn")


def _project(facts):
    if facts.projection == "parallel":
        how = "M_vv3dv onto the viewport; a parallel view needs no divide"
    else:
        how = "; ".join(
            (["lines: M_per (d = -1), M_vv3dv, divide by W"] if facts.draws_lines else [])
            + (["triangles: perspective-to-parallel M (keeps depth), M_vv3dv, divide by W"]
               if facts.solid else []))
    return True, how + "; " + (
        "the window letterboxed in the viewport (aspect kept)" if facts.keep_aspect else
        "the window stretched over the whole viewport (the course's M_vv3dv)")


def _scan_conversion(facts):
    if facts.rasterizer == "scanline":
        return True, ("the course's scan-line algorithm (edge table, active edge table, spans; "
                      "screen-linear interpolation) with the top-left fill rule")
    return True, ("edge functions over each triangle's box, top-left fill rule, "
                  "perspective-correct interpolation")


def _depth_shading(facts):
    return either(facts.solid, "each pixel's height (or eye distance) through a colour map",
                  "no triangles are drawn")


def _light_pixels(facts):
    return either(facts.mode.lights == "pixels", f"{facts.mode.label} shading: normals "
                  "interpolated, renormalised, the model at every pixel", f"not {lit_at('pixels')}")


def _textures(facts):
    from core.texture.material import plan_stage        # the texture system's own reasons
    runs, why, why_not = plan_stage(facts.scene, facts.shading, facts.texture_filter)
    return either(runs, why, why_not)


NORMALIZE = PipelineStage("normalize", _normalize)
CLIP_LINES = PipelineStage("clip lines", _clip_lines)
CLIP_TRIANGLES = PipelineStage("clip triangles", on_triangles(lambda facts: (
    True, "outcodes first; only triangles that cross the volume go through Sutherland–Hodgman")))
PROJECT = PipelineStage("project", _project)
SCAN_LINES = PipelineStage("scan-convert lines", lambda facts: either(
    facts.draws_lines, "midpoint line into the frame buffer", "no edges are drawn"))
DEPTH_BUFFER = PipelineStage("depth buffer", on_triangles(lambda facts: (
    True, "the z-buffer needs a depth per pixel")))
SCAN_CONVERSION = PipelineStage("z-buffer scan conversion", on_triangles(_scan_conversion))
DEPTH_SHADING = PipelineStage("depth shading", _depth_shading,
                              listed=lambda facts: facts.shading == "depth")
LIGHT_PIXELS = PipelineStage("illuminate pixels", lit(on_triangles(_light_pixels)))
TEXTURES = PipelineStage("texture lookups", on_triangles(_textures))


# -- laid over the picture ---------------------------------------------------------------------

def _transparency(facts):
    """Whether k_t > 0 is laid over the opaque picture, and why (core.effects.transparency)."""
    clear = [m.name or "a mesh" for m in facts.scene.meshes if m.material.kt > 0]
    if not clear:
        return False, "no material has k_t > 0"
    if not facts.solid:
        return False, "no triangles are drawn"
    refused = _refused_by_renderer(facts.renderer)
    if refused:
        return False, refused
    asked = facts.transparency or _asked_transparency(facts.scene)
    if asked == "off":
        return False, f"off: {', '.join(clear)} (k_t > 0) drawn opaque (--transparency off)"
    how = ("each transparent surface blended over what lies behind it, "
           "I = (1 - k_t) I_near + k_t I_far (FvDFH 16.5.1)" if asked == "interpolated"
           else "a mesh of k_t's share of pixels left open (screen door)")
    return True, (f"{asked}: {', '.join(clear)} has k_t > 0, so the scene needs it (the default "
                  f"wherever a material is transparent; --transparency off draws it opaque); "
                  f"{how}")


def _refused_by_renderer(renderer: str) -> str:
    """Why ``renderer`` lays no transparency over its picture ("": it does, or it is not
    registered and the plan is the z-buffer's)."""
    try:
        entry = get_renderer(renderer)
    except ValueError:
        return ""
    if entry.recursive:
        return f"{renderer} refracts through k_t > 0 itself"
    return "" if entry.transparency else f"{renderer} draws k_t > 0 opaque"


def _asked_transparency(scene) -> str:
    from core.settings import needed_transparency
    return getattr(scene, "transparency", None) or needed_transparency(scene)


# core.render wraps the draw in the effect; it names the stage when the effect has run.
TRANSPARENCY = PipelineStage("transparency", _transparency)

# The z-buffer's stages in the order it runs them; a renderer's plan hook may change the list
# (core.plan), and transparency follows whatever it leaves.
PIPELINE = (CULL, FACE_NORMALS, VERTEX_NORMALS, LIGHT_FACES, LIGHT_VERTICES, NORMALIZE,
            CLIP_LINES, CLIP_TRIANGLES, PROJECT, SCAN_LINES, DEPTH_BUFFER, SCAN_CONVERSION,
            DEPTH_SHADING, LIGHT_PIXELS, TEXTURES)

# The stages the shading mode's own vertex step decides (it lists them in its ``computed``).
DECIDED_BY_THE_SHADER = frozenset(s.name for s in (
    FACE_NORMALS, VERTEX_NORMALS, LIGHT_FACES, LIGHT_VERTICES, DEPTH_SHADING, LIGHT_PIXELS,
    TEXTURES))


def triangle_stage_for(facts: Facts):
    """``triangle_stage(name, runs, why, why_not="")``, the helper a renderer's plan hook is
    given: a stage of the triangles, which does not run when none are drawn."""
    def triangle_stage(name: str, runs: bool, why: str, why_not: str = "") -> Stage:
        return Stage(name, *on_triangles(lambda f: either(runs, why, why_not))(facts))
    return triangle_stage


def ran(stats: dict, *stages) -> None:
    """Name ``stages`` (PipelineStage objects or names) in ``stats["stages run"]``."""
    done = stats.setdefault("stages run", [])
    done += [getattr(s, "name", s) for s in stages]
