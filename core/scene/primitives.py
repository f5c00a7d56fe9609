"""Analytic primitives: surfaces given by an equation, not by triangles.

The ray casters intersect them exactly (:mod:`core.renderers.raycast`); the z-buffer draws
their tessellation (:mod:`core.scene.generators`). Scene data only, like :mod:`core.scene.model`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

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


# ----------------------------------------------------------------------------- planes (ray traced)

@dataclass(frozen=True)
class Plane:
    """The infinite plane through ``point`` with normal ``normal`` (the notes' ``Ax + By + Cz
    + D = 0`` with ``(A, B, C) = normal``, ``D = −normal · point``).

    ``checker > 0`` paints it with squares of that side, alternately the material's ``O_d`` and
    ``checker_color``, aligned with :func:`plane_axes` from ``point``. The z-buffer draws the
    square of half-side ``extent`` around ``point`` (:func:`tessellate`); the ray tracer the
    whole plane. Planes are lit from both sides.
    """

    point: tuple[float, float, float]
    normal: tuple[float, float, float]
    material: Material = field(default_factory=Material)
    checker: float = 0.0
    checker_color: tuple[float, float, float] = (0.1, 0.1, 0.1)
    extent: float = 20.0


def plane_axes(normal) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit ``n`` and two unit in-plane axes ``e1, e2`` with ``e1 × e2 = n``."""
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e2 = np.cross(n, helper)
    e2 /= np.linalg.norm(e2)
    return n, np.cross(e2, n), e2


def tessellate(primitive, segments: int = 96) -> list:
    """Meshes that draw ``primitive`` in the z-buffer, each marked ``tessellates=primitive``.

    A sphere: a UV sphere of ``segments`` meridians and ``segments / 2`` bands (closed). A
    plane: its ``extent`` square, as one mesh per checker colour (two-sided, open).
    """
    from core.scene import generators
    if isinstance(primitive, Sphere):
        mesh = generators.uv_sphere(primitive.radius, segments, max(2, segments // 2))
        mesh.positions = mesh.positions + np.asarray(primitive.center, dtype=np.float64)
        mesh.material, mesh.tessellates, mesh.name = primitive.material, primitive, "sphere"
        return [mesh]
    if isinstance(primitive, Plane):
        return _plane_meshes(primitive)
    raise TypeError(f"cannot tessellate {primitive!r}")


def _plane_meshes(plane: Plane) -> list:
    from dataclasses import replace

    from core.scene.model import Mesh
    n, e1, e2 = plane_axes(plane.normal)
    size = plane.checker if plane.checker > 0.0 else 2.0 * plane.extent
    count = max(1, int(np.ceil(plane.extent / size)))
    i, j = np.meshgrid(np.arange(-count, count), np.arange(-count, count), indexing="ij")
    i, j = i.reshape(-1), j.reshape(-1)
    corners = np.array([(0, 0), (1, 0), (1, 1), (0, 1)], dtype=np.float64)
    origin = np.asarray(plane.point, dtype=np.float64)
    meshes = []
    colours = [plane.material] if plane.checker <= 0.0 else [
        plane.material, replace(plane.material, od=tuple(plane.checker_color))]
    for parity, material in enumerate(colours):
        pick = ((i + j) % 2 == parity) if plane.checker > 0.0 else np.ones(len(i), bool)
        a = (i[pick, None] + corners[None, :, 0]) * size                 # (Q, 4)
        b = (j[pick, None] + corners[None, :, 1]) * size
        positions = origin + a[..., None] * e1 + b[..., None] * e2       # (Q, 4, 3)
        q = np.arange(pick.sum()) * 4
        triangles = np.concatenate([np.stack([q, q + 1, q + 2], 1), np.stack([q, q + 2, q + 3], 1)])
        meshes.append(Mesh(positions=positions.reshape(-1, 3), triangles=triangles,
                           normals=np.broadcast_to(n, (len(q) * 4, 3)), closed=False,
                           material=material, name="plane", tessellates=plane))
    return meshes
