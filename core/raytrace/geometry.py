"""A scene packed for the ray tracer's kernels: one BVH over every mesh's triangles, the
analytic spheres and planes as rows, and one material row per surface.

- Meshes that tessellate an analytic primitive (``mesh.tessellates``) are left out: the
  primitive itself is traced. ``scene.primitives`` adds spheres and planes (a torus is left to
  its tessellation, if the scene has one).
- Vertex normals are :func:`core.scene.normals.vertex_normals` with the notes' "mean"
  weighting — the ones the z-buffer's Phong shading interpolates — so that a ray-traced pixel
  and a rasterized one evaluate the model with the same normal.
- Spheres have a BVH of their own over their boxes (``sphere_*``), so 10,000 of them cost a
  ray a few box tests, not 10,000 quadratics.
- Surfaces: ``pack_surfaces`` rows (the Phong model's, shared with the z-buffer), meshes first,
  then spheres, then planes; ``optics`` ``(M, 3)``: ``k_r, k_t, ior``; ``checker`` ``(M, 4)``:
  square side (0: plain) and the second colour.

The packing is kept per scene (weakly) and rebuilt when the scene's meshes are replaced.
"""

from __future__ import annotations

import time
import weakref
from typing import NamedTuple

import numpy as np

from core.arrays import read_only
from core.raytrace import bvh as bvh_module
from core.raytrace.optics import check_material
from core.scene.normals import vertex_normals
from core.scene.primitives import Plane, Sphere, plane_axes
from core.shading.illumination import pack_surfaces

# Columns of a sphere row and of a plane row.
SPHERE_COLUMNS = 5        # cx, cy, cz, r, surface
PLANE_COLUMNS = 13        # a, b, c, d (unit normal), surface, e1 (3), e2 (3), point·e1, point·e2


class Packed(NamedTuple):
    """Everything the kernels read about the scene (numba takes it as one argument).

    The first five fields are the BVH's (:class:`core.raytrace.bvh.BVH`), by the same names,
    so the traversal reads a Packed as a tree (numba's parallel loops take flat tuples only).
    """

    box: np.ndarray
    first: np.ndarray
    count: np.ndarray
    tri: np.ndarray
    prim: np.ndarray
    corners: np.ndarray        # (T, 3) int64: each scene triangle's vertices
    normals: np.ndarray        # (V, 3) unit vertex normals
    face_surface: np.ndarray   # (T,) int64: the surface row of each triangle
    spheres: np.ndarray        # (S, 5)
    planes: np.ndarray         # (P, 13)
    surfaces: np.ndarray       # (M, 11) the Phong model's rows
    optics: np.ndarray         # (M, 3) k_r, k_t, ior
    checker: np.ndarray        # (M, 4) side, colour
    # The spheres' own BVH (bvh.BoxTree over their boxes): a ray tests O(log S) of them.
    sphere_box: np.ndarray
    sphere_first: np.ndarray
    sphere_count: np.ndarray
    sphere_item: np.ndarray


class Texturing(NamedTuple):
    """The z-buffer's texture data for the traced meshes (:mod:`core.texture.surface`):
    ``attrs`` ``(V, 14)`` the varyings (normal, position, (u, v), ∂P/∂u, ∂P/∂v) of every
    vertex, ``maps`` ``(M, 7)`` each surface's textures (−1: none; spheres and planes have
    none), and the packed texels, levels and texture table."""

    attrs: np.ndarray
    maps: np.ndarray
    texels: np.ndarray
    levels: np.ndarray
    textures: np.ndarray


class Packing(NamedTuple):
    packed: Packed
    build: bvh_module.BuildReport
    scale: float               # the size of the scene's bounded part (for ray offsets)
    seconds: float
    texturing: Texturing       # what the textured meshes need (maps all −1 when none is)
    textured: bool             # any surface has a texture, bump, normal or environment map


_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def traced_meshes(scene) -> list:
    return [m for m in scene.meshes if m.tessellates is None
            and len(m.triangles)]


def traced_primitives(scene) -> tuple[list, list]:
    """The spheres and planes traced exactly: ``scene.primitives``' and those a mesh
    tessellates, each once (by identity), in the order they are packed."""
    spheres = [p for p in scene.primitives if isinstance(p, Sphere)]
    planes = [p for p in scene.primitives if isinstance(p, Plane)]
    seen = {id(p) for p in spheres + planes}        # by identity: a set, not a scan per mesh
    for mesh in scene.meshes:
        prim = mesh.tessellates
        if isinstance(prim, (Sphere, Plane)) and id(prim) not in seen:
            seen.add(id(prim))
            (spheres if isinstance(prim, Sphere) else planes).append(prim)
    return spheres, planes


def pack(scene) -> Packing:
    """The scene as the kernels read it (cached while the scene and its meshes live).

    Raises ValueError (naming the mesh or primitive) for a material the tracer cannot use.
    """
    meshes = traced_meshes(scene)
    spheres, planes = traced_primitives(scene)
    key = tuple(id(a) for m in meshes for a in (m, m.positions, m.triangles)) + tuple(
        id(p) for p in spheres + planes)
    entry = _cache.get(scene)
    if entry is not None and entry[0] == key:
        return entry[1]
    packing = _pack(meshes, spheres, planes)
    _cache[scene] = (key, packing)
    return packing


def forget(scene) -> None:
    """Drop ``scene``'s packing, so that the next :func:`pack` builds it from nothing (the
    bench times the build)."""
    _cache.pop(scene, None)


def _pack(meshes, spheres, planes) -> Packing:
    start = time.perf_counter()
    materials = [m.material for m in meshes] + [s.material for s in spheres] + [
        p.material for p in planes]
    names = ([f"mesh {m.name!r}" for m in meshes] + [f"sphere {i + 1}" for i in range(len(spheres))]
             + [f"plane {i + 1}" for i in range(len(planes))])
    for material, name in zip(materials, names):
        check_material(material, name)
    two_sided = [not m.closed for m in meshes] + [s.two_sided for s in spheres] + [True] * len(planes)
    surfaces = pack_surfaces(materials, two_sided)
    optics = np.array([[m.kr, m.kt, m.ior]
                       for m in materials], dtype=np.float64).reshape(-1, 3)
    checker = np.zeros((len(materials), 4))
    for i, plane in enumerate(planes):
        row = len(meshes) + len(spheres) + i
        checker[row, 0] = plane.checker
        checker[row, 1:4] = plane.checker_color

    sizes = [len(m.positions) for m in meshes]
    offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    positions = np.concatenate([m.positions for m in meshes]) if meshes else np.zeros((0, 3))
    corners = (np.concatenate([m.triangles + offset[i] for i, m in enumerate(meshes)])
               if meshes else np.zeros((0, 3), np.int64)).astype(np.int64)
    normals = (np.concatenate([vertex_normals(m, "mean") for m in meshes]) if meshes
               else np.zeros((0, 3)))
    face_surface = np.repeat(np.arange(len(meshes), dtype=np.int64),
                             [len(m.triangles) for m in meshes])
    tree, report = bvh_module.build(positions, corners)

    sphere_rows = np.zeros((len(spheres), SPHERE_COLUMNS))
    for i, s in enumerate(spheres):
        if not (np.all(np.isfinite(s.center)) and np.isfinite(s.radius) and s.radius > 0.0):
            raise ValueError(f"sphere {i + 1}: needs a finite centre and a positive radius")
        sphere_rows[i, :3], sphere_rows[i, 3] = s.center, s.radius
        sphere_rows[i, 4] = len(meshes) + i
    plane_rows = np.zeros((len(planes), PLANE_COLUMNS))
    for i, p in enumerate(planes):
        normal = np.asarray(p.normal, dtype=np.float64)
        if not (np.all(np.isfinite(normal)) and np.linalg.norm(normal) > 0.0
                and np.all(np.isfinite(p.point))):
            raise ValueError(f"plane {i + 1}: needs a finite point and a non-zero normal")
        n, e1, e2 = plane_axes(normal)
        plane_rows[i, :3], plane_rows[i, 3] = n, -float(n @ np.asarray(p.point, dtype=np.float64))
        plane_rows[i, 4] = len(meshes) + len(spheres) + i
        plane_rows[i, 5:8], plane_rows[i, 8:11] = e1, e2
        plane_rows[i, 11], plane_rows[i, 12] = e1 @ p.point, e2 @ p.point   # checker origin

    scale = _scale(positions, sphere_rows, plane_rows)
    sphere_tree = bvh_module.build_boxes(sphere_rows[:, :3] - sphere_rows[:, 3:4],
                                         sphere_rows[:, :3] + sphere_rows[:, 3:4])
    packed = Packed(*tree, corners, np.ascontiguousarray(normals, dtype=np.float64), face_surface,
                    sphere_rows, plane_rows, surfaces, optics, checker, *sphere_tree)
    texturing = _texturing(meshes, len(materials), positions, normals)
    textured = bool(np.any(texturing.maps[:, :4] >= 0))
    return Packing(packed, report, scale, time.perf_counter() - start, texturing, textured)


def _texturing(meshes, surfaces: int, positions, normals) -> Texturing:
    """The textured meshes' varyings and maps, packed as the z-buffer's textured shader packs
    them (the same filters then sample the same texels)."""
    from core.texture.material import maps_of
    from core.texture.shaders import mesh_varyings
    from core.texture.surface import VARYING_COLUMNS, pack_maps
    all_maps = [maps_of(m.material) for m in meshes]
    usable = [m if m is not None and m.demo is None else None for m in all_maps]
    if not any(m is not None for m in usable):
        maps = np.full((surfaces, 7), -1.0)
        return Texturing(read_only(np.zeros((0, VARYING_COLUMNS))), maps,
                         np.zeros((1, 4), np.float32),
                         np.array([[0, 1, 1]], np.int64), np.zeros((0, 3), np.int64))
    texels, levels, textures, rows = pack_maps(usable + [None] * (surfaces - len(meshes)))
    varyings = np.concatenate([mesh_varyings(m) for m in meshes])
    attrs = np.ascontiguousarray(np.concatenate([normals, positions, varyings], axis=1))
    # read-only, as the z-buffer's are: textured_at then compiles once for both renderers
    return Texturing(read_only(attrs), rows, texels, levels, textures)


def _scale(positions, spheres, planes) -> float:
    """The diagonal of the box around the triangles, spheres and the planes' points."""
    points = [positions[np.isfinite(positions).all(axis=1)]]
    if len(spheres):
        points += [spheres[:, :3] - spheres[:, 3:4], spheres[:, :3] + spheres[:, 3:4]]
    if len(planes):
        points.append(-planes[:, 3:4] * planes[:, :3])       # the point nearest the origin
    every = np.concatenate(points) if points else np.zeros((0, 3))
    if len(every) == 0:
        return 1.0
    diagonal = float(np.linalg.norm(every.max(axis=0) - every.min(axis=0)))
    return max(diagonal, float(np.abs(every).max()), 1e-300)
