"""The two-pass renderer's stages in the plan (:func:`core.plan.plan` calls :func:`add_stages`
through the renderer's registry entry): the z-buffer's stages give way to the two passes.

Each stage that runs is named in the frame's ``stats["computed"]`` by the same words
(:mod:`core.renderers.twopass.draw`), so a test can hold the plan and the frame together. Imports
nothing heavy: ``python -m app plan`` loads this module, not the renderer.
"""

from __future__ import annotations

from core.plan import Stage

# The stages' names, also the words the renderer puts in the frame's ``computed``.
SOLUTION, VERTICES, BVH, EYE, HIGHLIGHTS, REFLECTED, REFRACTED, TONE = (
    "radiosity solution (pass 1)", "radiosity at the vertices", "element BVH",
    "eye rays (pass 2)", "specular highlights", "reflected rays", "refracted rays",
    "sRGB tone curve")
KEPT = ("transparency",)       # the stages after the renderer's that stay (the plan's own)


def stages_for(scene) -> list[Stage]:
    """The two passes for ``scene``, each with why it runs or why not."""
    meshes = [m for m in scene.meshes if len(m.triangles)]
    if not meshes:
        return [Stage(name, False, "the scene has no triangles (radiosity meshes triangles)")
                for name in (SOLUTION, VERTICES, BVH, EYE, HIGHLIGHTS, REFLECTED, REFRACTED,
                             TONE)]
    lit = any(max(light.intensity) > 0 for light in scene.lights)
    shiny = [m.name or "a mesh" for m in meshes if m.material.ks > 0]
    mirrors = [m.name or "a mesh" for m in meshes if m.material.kr > 0]
    clear = [m.name or "a mesh" for m in meshes if m.material.kt > 0]
    if shiny and lit:
        highlights = Stage(HIGHLIGHTS, True, f"k_s > 0 ({', '.join(shiny)}): at each hit "
                           "Whitted's local specular term k_s O_s f_att I_p (N·H)^n of each "
                           "point or directional light a shadow ray reaches (hard shadows)")
    else:
        highlights = Stage(HIGHLIGHTS, False, "no [[light]] to make a highlight (an area "
                           "emitter is seen in a mirror by k_r instead)" if not lit else
                           "no material has k_s > 0")
    return [
        Stage(SOLUTION, True, "view-independent: B_i = E_i + ρ_i Σ_j B_j F_ij over the "
              "elements (the radiosity renderer's solution, kept with the scene: solved once "
              "for every view); specular surfaces take part as diffuse ones of ρ = k_d O_d"),
        Stage(VERTICES, True, "each element's radiosity (with the ambient term for the light "
              "not yet shot) area-averaged to its corners within its surface, as the radiosity "
              "renderer displays it"),
        Stage(BVH, True, "the ray tracer's BVH over the elements (one-sided ones and the first "
              "copy of each two-sided pair; the second copies in a BVH of their own)"),
        Stage(EYE, True, "view-dependent: one ray per pixel sample, F..B; at the nearest hit "
              "the diffuse term is the vertex radiosities interpolated with the hit's "
              "barycentrics (what the radiosity renderer shows there)"),
        highlights,
        Stage(REFLECTED, bool(mirrors),
              f"k_r > 0 ({', '.join(mirrors)}): R = I − 2 (N·I) N with weight k_r, shaded "
              "again by radiosity plus specular where it lands, to the ray tracer's max depth"
              if mirrors else "no material has k_r > 0"),
        Stage(REFRACTED, bool(clear),
              f"k_t > 0 ({', '.join(clear)}): Snell's law T = α I + β N with weight k_t "
              "(total internal reflection gives k_t to the reflected ray)"
              if clear else "no material has k_t > 0"),
        Stage(TONE, scene.tone == "srgb",
              "the scene is in physical units (tone = \"srgb\"): the sRGB curve on the summed "
              "radiance" if scene.tone == "srgb" else
              "tone = \"linear\": the summed radiance clamped to [0, 1]"),
    ]


def add_stages(stages: list, triangle_stage, scene=None) -> None:
    """Replace the z-buffer's stages by the two passes (the plan's own stages after them,
    transparency's, stay)."""
    kept = [s for s in stages if s.name in KEPT]
    stages[:] = stages_for(scene) + kept
