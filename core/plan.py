"""Which stages a scene needs: the renderer runs these and skips the rest.

``plan(scene, projection, shading)`` returns the stages in pipeline order, each with whether it
runs and why (or why not). ``python -m app plan`` prints it and the window shows it; the
renderer follows it and records what it actually allocated and computed in ``Frame.stats`` so
that tests can hold the two against each other.
"""

from __future__ import annotations

from dataclasses import dataclass

from core.scene import SHADINGS, Scene


@dataclass(frozen=True)
class Stage:
    name: str
    runs: bool
    reason: str


def plan(scene: Scene, projection: str, shading: str) -> list[Stage]:
    if shading not in SHADINGS:
        raise ValueError(f"shading must be one of {', '.join(SHADINGS)}, not {shading!r}")
    n_par_or_per = "N_per" if projection == "perspective" else "N_par"
    has_tris = scene.triangle_count > 0
    has_lines = any(len(m.edges) for m in scene.meshes)
    solid = shading != "wireframe" and has_tris
    closed = any(m.closed and len(m.triangles) for m in scene.meshes)
    file_normals = all(m.normals is not None for m in scene.meshes if len(m.triangles))
    draws_lines = shading == "wireframe" or has_lines

    def no_solid(why_else: str) -> str:
        if not has_tris:
            return "the scene has no triangles"
        if shading == "wireframe":
            return "wireframe draws edges only"
        return why_else

    stages = [
        Stage("normalize", True, f"{n_par_or_per} carries world coordinates into the canonical volume"),
        Stage("cull back faces", solid and closed,
              "closed, consistently wound meshes: faces turned away are never visible" if solid and closed
              else no_solid("no mesh is declared closed, so every face may be seen")),
        Stage("face normals", solid and shading == "flat",
              "flat shading evaluates the model once per face with its normal" if solid and shading == "flat"
              else no_solid(f"{shading} shading uses vertex normals")),
        Stage("vertex normals", solid and shading in ("gouraud", "phong") and not file_normals,
              (f"{shading} shading needs a normal at each vertex (average of the adjacent faces)"
               if solid and shading in ("gouraud", "phong") and not file_normals
               else "given with the mesh (by its file or its generator)"
               if solid and shading in ("gouraud", "phong")
               else no_solid("flat shading needs no vertex normals"))),
        Stage("illuminate faces", solid and shading == "flat",
              "one evaluation per face, at its centroid" if solid and shading == "flat"
              else no_solid("not flat shading")),
        Stage("illuminate vertices", solid and shading == "gouraud",
              "the model at each vertex; intensities are interpolated" if solid and shading == "gouraud"
              else no_solid("not Gouraud shading")),
        Stage("clip lines", draws_lines,
              "Cohen–Sutherland: trivial accept/reject by outcode, the rest clipped plane by plane"
              if draws_lines else "no edges are drawn"),
        Stage("clip triangles", solid,
              "outcodes first; only triangles that cross the volume go through Sutherland–Hodgman"
              if solid else no_solid("")),
        Stage("project", True, _projection_reason(projection, solid, draws_lines)),
        Stage("scan-convert lines", draws_lines,
              "midpoint line into the frame buffer" if draws_lines else "no edges are drawn"),
        Stage("depth buffer", solid,
              "the z-buffer needs a depth per pixel" if solid
              else no_solid("") if not has_tris or shading == "wireframe" else ""),
        Stage("z-buffer scan conversion", solid,
              "scan-line z-buffer with the top-left fill rule" if solid else no_solid("")),
        Stage("illuminate pixels", solid and shading == "phong",
              "Phong shading: normals interpolated, renormalised, the model at every pixel"
              if solid and shading == "phong" else no_solid("not Phong shading")),
    ]
    return stages


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
