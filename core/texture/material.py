"""A material's surface maps: colour texture, bump (height) map, normal map, environment map.

:class:`SurfaceMaps` is what a scene's ``material = { texture = …, bump = …, … }`` becomes
(:mod:`core.texture.scenekeys` reads it); it rides on ``Material.extra["maps"]``. A material
with ``bump_demo = { … }`` is the course demo's kind (:class:`DemoMaterial`).

:func:`tangent_frames` gives every vertex the two tangents of its surface's (u, v)
parametrisation, ``∂P/∂u`` and ``∂P/∂v``, averaged over the triangles around it (each
triangle's from its edges and their Δu, Δv: the linear map from (u, v) to the plane of the
triangle), which both Blinn's bump mapping and tangent-space normal maps need.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from core.texture.image import Texture

MAPS_KEY = "maps"                # Material.extra[MAPS_KEY] -> SurfaceMaps


@dataclass
class DemoMaterial:
    """The Java bump demo's material (``J3DPanel``): map, mode and its fixed viewpoint."""

    bump_map: int = 0
    bump: bool = True
    viewpoint: tuple[float, float, float] = (50.0, -50.0, 50.0)


@dataclass
class SurfaceMaps:
    """The maps of one material; any may be None. ``uv_scale`` multiplies (u, v) first."""

    color: Texture | None = None
    height: Texture | None = None
    bump_scale: float = 0.02           # height 1 raises the surface this far (world units)
    normal_map: Texture | None = None
    environment: Texture | None = None  # equirectangular, reflected about the normal
    reflectivity: float = 0.0          # share of the environment in the colour
    uv_scale: tuple[float, float] = (1.0, 1.0)
    demo: DemoMaterial | None = None
    messages: list[str] = field(default_factory=list)   # textures that could not be used

    @property
    def needs_uv(self) -> bool:
        return any(m is not None for m in (self.color, self.height, self.normal_map))

    @property
    def needs_tangents(self) -> bool:
        return self.height is not None or self.normal_map is not None


def maps_of(material) -> SurfaceMaps | None:
    extra = material.extra
    return extra.get(MAPS_KEY)


def tangent_frames(positions: np.ndarray, triangles: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """``(V, 6)``: ∂P/∂u and ∂P/∂v at each vertex (world units per unit of u and v).

    Per triangle: edges E1 = P1 − P0, E2 = P2 − P0 and their (Δu, Δv) give
    ``[∂P/∂u; ∂P/∂v] = [[Δu1, Δv1], [Δu2, Δv2]]⁻¹ [E1; E2]``; a vertex averages the
    triangles around it (weighted by their area in (u, v), so slivers count little).
    Triangles with collinear (u, v) add nothing.
    """
    p = positions[triangles]
    t = uv[triangles]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    du1, dv1 = t[:, 1, 0] - t[:, 0, 0], t[:, 1, 1] - t[:, 0, 1]
    du2, dv2 = t[:, 2, 0] - t[:, 0, 0], t[:, 2, 1] - t[:, 0, 1]
    det = du1 * dv2 - dv1 * du2
    # det · [∂P/∂u; ∂P/∂v] = [[dv2, −dv1], [−du2, du1]] [E1; E2]; weighting by sign(det)·|det|
    # makes each triangle count by its (u, v) area.
    sign = np.sign(det)[:, None]
    dpdu = sign * (dv2[:, None] * e1 - dv1[:, None] * e2)
    dpdv = sign * (-du2[:, None] * e1 + du1[:, None] * e2)
    weight = np.zeros(len(positions))
    frames = np.zeros((len(positions), 6))
    for corner in range(3):
        np.add.at(frames, triangles[:, corner], np.concatenate([dpdu, dpdv], axis=1))
        np.add.at(weight, triangles[:, corner], np.abs(det))
    used = weight > 0
    frames[used] /= weight[used, None]
    return frames


# The shading mode whose frames the textured shader draws when a material has maps
# (core.texture.shaders.shading_for): the one mode that draws textures.
TEXTURED_MODE = "phong"


def _lit_once_per_face_or_vertex(shading: str) -> bool:
    """Whether the registered mode ``shading`` lights faces or vertices (its entry's
    ``lights``), so that it has no per-pixel values to take a texture's."""
    from core.registry import get_shading, shading_names
    return shading in shading_names() and get_shading(shading).lights in ("faces", "vertices")


def plan_stage(scene, shading: str, texture_filter: str = "trilinear") -> tuple[bool, str, str]:
    """``(runs, why, why_not)`` of the plan's "texture lookups" stage (core.plan)."""
    mapped = [m for m in scene.meshes if maps_of(m.material) is not None and len(m.triangles)]
    if not mapped:
        return False, "", "no material has a texture, bump, normal or environment map"
    if _lit_once_per_face_or_vertex(shading):
        return False, "", (f"{shading} shading computes no per-pixel values, which textures, bump "
                           f"and normal maps need: textured materials are drawn with their colour "
                           f"(use {TEXTURED_MODE})")
    if shading not in (TEXTURED_MODE, "textured"):
        return False, "", f"{shading} draws no textures"
    without_uv = [m.name for m in mapped if m.uv is None and maps_of(m.material).needs_uv]
    why = (f"{texture_filter} filtering of the material maps, (u, v) derivatives exact per "
           "pixel; bump/normal maps perturb the Phong normal")
    if without_uv:
        why += (f"; {', '.join(without_uv)} has no (u, v) (a .tri file or an OBJ without vt "
                "has none) and is drawn with its material colour")
    return True, why, ""
