"""Substructuring (Cohen, Greenberg, Immel, Brock 1986): the scene's surfaces meshed into
*patches* that shoot and *elements* that receive.

Takes a :class:`core.scene.model.Scene`; returns :class:`Elements`, plain arrays:

- every scene triangle is cut into ``k x k`` smaller triangles of about one patch's size
  (:func:`subdivide`, a regular barycentric grid), each a patch; every patch into ``m x m``
  elements. Later, :func:`split` cuts chosen elements into four at their edge midpoints
  (adaptive subdivision where the radiosity changes fast).
- a one-sided surface gets one copy facing along its normal (counter-clockwise winding); a
  two-sided one (``Material.two_sided``; by default an open mesh that emits nothing) a second,
  reversed copy facing the other way, with its own radiosity.
- reflectance ρ = k_d · O_d per RGB channel, emission ``Material.emission``.

:func:`check_scene` refuses what the equation cannot use (ρ >= 1 never converges; emission
negative or not finite) with a message naming the mesh.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

EMITTER_PIECES = 4        # an emitting triangle is at least 4 x 4 patches
MIN_AREA = 1e-12
MAX_TRIANGLES = 20_000    # one patch each at least: beyond this the hemicube rows take hours          # relative to the scene's squared size: below it a triangle is dropped


class RadiosityError(ValueError):
    """A scene the radiosity equation cannot use; the message names the mesh and why."""


@dataclass
class Elements:
    """The receiving elements and the shooting patches, all triangles.

    Element arrays (E rows): ``corners`` (E, 3, 3), ``patch`` (E,) the patch it belongs to,
    ``area``, ``normal`` (unit), ``centre``, ``rho`` and ``emission`` (E, 3), ``surface`` (E,)
    the planar piece it came from (a scene triangle's side; vertex values are averaged within
    one surface only, so colours do not bleed over creases or between meshes), ``mesh`` (E,)
    the scene mesh, ``two_sided`` (E,) bool. Patch arrays (P rows): ``patch_corners``,
    ``patch_area``, ``patch_normal``, ``patch_centre``.
    """

    corners: np.ndarray
    patch: np.ndarray
    area: np.ndarray
    normal: np.ndarray
    centre: np.ndarray
    rho: np.ndarray
    emission: np.ndarray
    surface: np.ndarray
    mesh: np.ndarray
    two_sided: np.ndarray
    patch_corners: np.ndarray
    patch_area: np.ndarray
    patch_normal: np.ndarray
    patch_centre: np.ndarray
    scale: float = 1.0            # the scene's size (bounding-box diagonal)

    def __len__(self) -> int:
        return len(self.area)

    @property
    def patches(self) -> int:
        return len(self.patch_area)


def reflectance(material) -> np.ndarray:
    """ρ = k_d · O_d per channel."""
    return float(material.kd) * np.asarray(material.od, dtype=np.float64)


def is_two_sided(mesh) -> bool:
    m = mesh.material
    if m.two_sided is not None:
        return bool(m.two_sided)
    return not mesh.closed and not any(m.emission)


def check_scene(scene) -> None:
    """Raise :class:`RadiosityError` for a material the equation cannot use, or a scene with
    nothing to light it."""
    for i, mesh in enumerate(scene.meshes):
        if not len(mesh.triangles):
            continue
        where = f"mesh {i + 1} ({mesh.name!r})"
        emission = np.asarray(mesh.material.emission, dtype=np.float64)
        if not np.all(np.isfinite(emission)) or np.any(emission < 0):
            raise RadiosityError(f"{where}: emission must be finite and >= 0, "
                                 f"not {tuple(float(x) for x in emission)}")
        rho = reflectance(mesh.material)
        if not np.all(np.isfinite(rho)) or rho.max() >= 1.0:
            raise RadiosityError(f"{where}: reflectance rho = kd * od = "
                                 f"{np.round(rho, 4).tolist()} must stay below 1 in every "
                                 "channel, or the light would never die out (no convergence)")


def has_light(scene) -> bool:
    """Does anything give light: a [[light]] of some intensity, or an emitting mesh?"""
    return any(max(light.intensity) > 0 for light in scene.lights) or any(
        any(m.material.emission) for m in scene.meshes if len(m.triangles))


def subdivide(corners: np.ndarray, k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each triangle ``corners[t]`` (T, 3, 3) cut into ``k[t]**2`` on a regular barycentric
    grid; returns ``(pieces (N, 3, 3), parent (N,))``, the pieces keeping the winding."""
    pieces, parents = [], []
    for kk in np.unique(k):
        kk = int(kk)
        rows = np.flatnonzero(k == kk)
        a, b, c = (corners[rows, i][:, None, :] for i in range(3))
        ij = [(i, j) for i in range(kk) for j in range(kk - i)]
        up = np.array([[(i, j), (i + 1, j), (i, j + 1)] for i, j in ij], dtype=np.float64)
        down = np.array([[(i + 1, j), (i + 1, j + 1), (i, j + 1)] for i, j in ij
                         if i + j + 1 < kk], dtype=np.float64).reshape(-1, 3, 2)
        grid = np.concatenate([up, down]) / kk                  # (n, 3, 2) barycentric (s, t)
        s, t = grid[..., 0].reshape(1, -1, 1), grid[..., 1].reshape(1, -1, 1)
        points = a + s * (b - a) + t * (c - a)                   # (R, n*3, 3)
        pieces.append(points.reshape(len(rows) * len(grid), 3, 3))
        parents.append(np.repeat(rows, len(grid)))
    if not pieces:
        return np.zeros((0, 3, 3)), np.zeros(0, np.int64)
    return np.concatenate(pieces), np.concatenate(parents)


def _frames(corners):
    cross = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(cross, axis=1)
    area = 0.5 * length
    normal = cross / np.where(length > 0, length, 1.0)[:, None]
    return area, normal, corners.mean(axis=1)


@dataclass
class Surfaces:
    """The scene's planar pieces, one row per side of a scene triangle that takes part (a
    two-sided mesh's triangles twice, the second copy reversed), in the order an element's
    ``surface`` counts them: ``corners`` (S, 3, 3), ``rho`` and ``emission`` (S, 3), ``mesh``
    (S,) the scene mesh, ``two_sided`` (S,), ``triangle`` (S,) the triangle's index in its
    mesh, ``reversed`` (S,) the reversed copy of a two-sided pair; ``scale`` the scene's size.
    What a renderer that draws from a solution needs to find an element's source triangle
    (the two-pass renderer's vertex normals and sides)."""

    corners: np.ndarray
    rho: np.ndarray
    emission: np.ndarray
    mesh: np.ndarray
    two_sided: np.ndarray
    triangle: np.ndarray
    reversed: np.ndarray
    scale: float


def surfaces(scene) -> Surfaces:
    """The scene's surfaces (:class:`Surfaces`), zero-area triangles left out, as
    :func:`mesh_scene` meshes them. Raises :class:`RadiosityError` for a scene without
    triangles or of only zero-area ones."""
    tris, rho, emission, mesh_of, sided, index, flipped = [], [], [], [], [], [], []
    for i, mesh in enumerate(scene.meshes):
        if not len(mesh.triangles):
            continue
        corners = mesh.positions[mesh.triangles]
        copies = [corners] + ([corners[:, ::-1]] if is_two_sided(mesh) else [])
        for k, c in enumerate(copies):
            tris.append(c)
            n = len(c)
            rho.append(np.repeat(reflectance(mesh.material)[None], n, axis=0))
            emission.append(np.repeat(np.asarray(mesh.material.emission, float)[None], n, axis=0))
            mesh_of.append(np.full(n, i))
            sided.append(np.full(n, len(copies) == 2))
            index.append(np.arange(n))
            flipped.append(np.full(n, k == 1))
    if not tris:
        raise RadiosityError("no triangles to mesh into patches")
    corners = np.concatenate(tris)
    lo, hi = corners.reshape(-1, 3).min(axis=0), corners.reshape(-1, 3).max(axis=0)
    scale = float(np.linalg.norm(hi - lo)) or 1.0
    area, _, _ = _frames(corners)
    keep = area > MIN_AREA * scale * scale                       # zero-area triangles drop out
    if not keep.any():
        raise RadiosityError("every triangle has zero area")
    return Surfaces(corners[keep], np.concatenate(rho)[keep], np.concatenate(emission)[keep],
                    np.concatenate(mesh_of)[keep], np.concatenate(sided)[keep],
                    np.concatenate(index)[keep], np.concatenate(flipped)[keep], scale)


def mesh_scene(scene, max_elements: int = 2000, elements_per_patch: int = 4) -> Elements:
    """The scene's triangles as patches and elements, about ``max_elements`` elements in all
    (before adaptive subdivision adds any). ``elements_per_patch``: 1 or 4 (``m`` = 1 or 2)."""
    check_scene(scene)
    s = surfaces(scene)
    corners, rho, emission, mesh_of, sided, scale = (s.corners, s.rho, s.emission, s.mesh,
                                                     s.two_sided, s.scale)
    area, _, _ = _frames(corners)
    if len(corners) > MAX_TRIANGLES:
        raise RadiosityError(f"{len(corners)} triangles (two-sided ones counted "
                             f"twice) are too many for radiosity (at most {MAX_TRIANGLES:,}); "
                             "draw it path traced (Render › Path traced, or --renderer "
                             "pathtrace)")
    # A scene with more triangles than the budget: each triangle one patch and one element.
    m = 2 if elements_per_patch >= 4 and 4 * len(corners) <= max_elements else 1
    k = _pieces_per_side(area, max(1, max_elements // (m * m)))
    # An emitter shoots from each patch's centre as a point would: cut small lights finer.
    k[emission.max(axis=1) > 0] = np.maximum(k[emission.max(axis=1) > 0], EMITTER_PIECES)
    patch_corners, parent = subdivide(corners, k)
    element_corners, patch = subdivide(patch_corners, np.full(len(patch_corners), m))
    return _elements(element_corners, patch, patch_corners, parent[patch], rho, emission,
                     mesh_of, sided, scale)


def _pieces_per_side(area: np.ndarray, patches: int) -> np.ndarray:
    """``k`` per triangle so that the k² pieces are of about equal area, ``patches`` in all."""
    target = area.sum() / patches
    k = np.maximum(1, np.floor(np.sqrt(area / target)).astype(np.int64))
    while (k * k).sum() > patches and k.max() > 1:
        target *= 1.15
        k = np.maximum(1, np.floor(np.sqrt(area / target)).astype(np.int64))
    return k


def _elements(element_corners, patch, patch_corners, surface, rho, emission, mesh_of, sided,
              scale) -> Elements:
    area, normal, centre = _frames(element_corners)
    p_area, p_normal, p_centre = _frames(patch_corners)
    return Elements(corners=element_corners, patch=patch.astype(np.int64), area=area,
                    normal=normal, centre=centre, rho=rho[surface], emission=emission[surface],
                    surface=surface.astype(np.int64), mesh=mesh_of[surface],
                    two_sided=sided[surface], patch_corners=patch_corners, patch_area=p_area,
                    patch_normal=p_normal, patch_centre=p_centre, scale=scale)


def split(e: Elements, chosen: np.ndarray) -> Elements:
    """``e`` with the elements ``chosen`` (indices) cut into four at their edge midpoints;
    patches stay as they are."""
    chosen = np.asarray(chosen, dtype=np.int64)
    keep = np.ones(len(e), bool)
    keep[chosen] = False
    pieces, parent = subdivide(e.corners[chosen], np.full(len(chosen), 2))
    rows = np.concatenate([np.flatnonzero(keep), chosen[parent]])
    corners = np.concatenate([e.corners[keep], pieces])
    area, normal, centre = _frames(corners)
    return Elements(corners=corners, patch=e.patch[rows], area=area, normal=normal, centre=centre,
                    rho=e.rho[rows], emission=e.emission[rows], surface=e.surface[rows],
                    mesh=e.mesh[rows], two_sided=e.two_sided[rows], patch_corners=e.patch_corners,
                    patch_area=e.patch_area, patch_normal=e.patch_normal,
                    patch_centre=e.patch_centre, scale=e.scale)


def vertex_values(e: Elements, values: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Element values (E, k) carried to the element corners for Gouraud display: each vertex
    gets the area-weighted mean of the elements of its surface that meet there.

    Returns ``(positions (V, 3), triangles (E, 3), vertex_values (V, k))``: vertices shared
    within a surface (welded by exact position), never across surfaces."""
    points = e.corners.reshape(-1, 3)
    key = np.concatenate([np.repeat(e.surface, 3)[:, None].astype(np.float64), points], axis=1)
    unique, inverse = np.unique(key, axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    weight = np.repeat(e.area, 3)
    total = np.zeros((len(unique), values.shape[1]))
    np.add.at(total, inverse, values.repeat(3, axis=0) * weight[:, None])
    norm = np.zeros(len(unique))
    np.add.at(norm, inverse, weight)
    return unique[:, 1:], inverse.reshape(-1, 3), total / np.maximum(norm, 1e-300)[:, None]
