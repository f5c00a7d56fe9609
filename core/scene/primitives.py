"""Analytic primitives: surfaces given by an equation, not by triangles.

The ray casters intersect them exactly (:mod:`core.renderers.raycast`); the z-buffer draws
their tessellation (:mod:`core.scene.generators`). Scene data only, like :mod:`core.scene.model`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from core.scene.model import Material


@dataclass(frozen=True)
class Sphere:
    """The sphere ``|P − center| = radius``."""

    center: tuple[float, float, float]
    radius: float
    material: Material = field(default_factory=Material)
    two_sided: bool = False


@dataclass(frozen=True)
class Torus:
    """The ring torus around ``axis`` through ``center``: core circle radius ``major`` (R),
    tube radius ``minor`` (r < R)."""

    center: tuple[float, float, float]
    major: float
    minor: float
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    material: Material = field(default_factory=Material)
    two_sided: bool = False
