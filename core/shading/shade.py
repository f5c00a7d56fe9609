"""Shading: flat, Gouraud and Phong (FvDFH 16.2.3–16.2.5; Assignment #3) on a visibility buffer.

The z-buffer pass (``core.pipeline.raster``) leaves, per pixel, the index of the visible (post-clip)
triangle and the perspective-correct barycentric weights of its vertices. Shading is then two
small steps per mode, a "vertex" step before clipping and a "pixel" step after rasterizing
(tinyrenderer's shader split; the z-buffer knows nothing about light):

=========  ==========================================  =======================================
mode       before clipping (world coordinates)         per pixel (resolve)
=========  ==========================================  =======================================
flat       face normals; the model once per face at    the face's colour: ``face_rgb[source]``
           its centroid → ``face_rgb (T, 3)``
gouraud    vertex normals; the model at every vertex   the three vertex colours interpolated
           → RGB carried as 3 attributes by the clipper   with the barycentrics
phong      vertex normals and positions → 6 attributes  normal and position interpolated, the
           carried by the clipper                       normal renormalised, the model evaluated
=========  ==========================================  =======================================

Interpolating with perspective-correct barycentrics is FvDFH's incremental interpolation
along the edges and the scan line, done once per visible pixel. The model is
:mod:`core.shading.illumination`; normals come from :mod:`core.scene.normals` (flat computes no vertex normals,
Gouraud no per-pixel normals). Meshes that are not closed are lit from both sides: the normal
is turned to the viewer per face (flat), per vertex (Gouraud) or per pixel (Phong).

How ``core.render`` calls it (all arrays float64 / int64, world coordinates)::

    eye = shade.eye_from_view(view, projection)             # PRP, or the direction to the viewer
    shading = shade.prepare(mode, scene, eye)               # ShadeInput
    # shading.positions (V, 3), shading.triangles (T, 3): every mesh's triangles, in scene
    # order, over one vertex array; shading.vertex_attrs (V, K), K = 0 / 3 / 6.
    # ... transform shading.positions by N, cull (kept = indices of the triangles kept),
    clipped = clip_triangles(points, shading.triangles[kept], shading.vertex_attrs, projection, z_min)
    vis = rasterize(..., clipped.triangles, width, height)
    image = shade.resolve(shading, vis, clipped.triangles, clipped.attrs,
                          kept[clipped.source], scene.background)  # (H, W, 3) uint8, row 0 top

``source`` given to :func:`resolve` must index ``shading.triangles`` (the triangles before any
culling), hence ``kept[clipped.source]`` when faces were culled. ``shading.computed`` names the
stages that ran, in :func:`core.plan.plan`'s words. Colours are clamped to [0, 1] where the
model is evaluated (a Gouraud vertex colour is clamped before it is interpolated, as GL does)
and turned into bytes rounded half up (:func:`core.shading.illumination.to_uint8`).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field
from typing import Callable, NamedTuple

import numpy as np
from numba import njit, prange

from core.shading.illumination import (Eye, eye_from_view, pack_ambient, pack_eye, pack_lights,
                               pack_surfaces, phong_point, quantize, to_uint8,
                               unit3)
from core.scene.normals import WEIGHTINGS, face_normals, vertex_normals

__all__ = ["MODES", "ShadeInput", "Eye", "eye_from_view", "prepare", "resolve"]

MODES = ("flat", "gouraud", "phong")


@dataclass
class ShadeInput:
    """What :func:`prepare` computed for one frame, and what :func:`resolve` needs.

    ``positions`` ``(V, 3)`` and ``triangles`` ``(T, 3)`` are all meshes' vertices and
    triangles in scene order (mesh ``i``'s vertices start at ``vertex_offset[i]``);
    ``vertex_attrs`` ``(V, K)`` is what the clipper must carry (flat: K = 0; Gouraud: RGB;
    Phong: normal then position); ``face_rgb`` ``(T, 3)`` the flat colours (None otherwise);
    ``face_surface`` ``(T,)`` the row of ``surfaces`` (the mesh) of each triangle.
    Arrays that do not depend on the view (positions, triangles, Phong's attributes) are kept
    between frames and are read-only.
    """

    mode: str
    positions: np.ndarray
    triangles: np.ndarray
    vertex_attrs: np.ndarray
    face_rgb: np.ndarray | None
    face_surface: np.ndarray
    vertex_surface: np.ndarray
    vertex_offset: np.ndarray
    surfaces: np.ndarray
    lights: np.ndarray
    ambient: np.ndarray
    eye: np.ndarray
    halfway: bool
    faces: np.ndarray          # (F,) the faces that will be drawn; only these are lit
    computed: list[str] = field(default_factory=list)


# --------------------------------------------------------------------------------------------
# Work that does not depend on the view, kept while the mesh (or the scene) lives: face and
# vertex normals per mesh; the concatenated arrays per scene. Cached arrays are read-only.

_mesh_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_scene_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _read_only(value):
    for a in value if isinstance(value, tuple) else (value,):
        if isinstance(a, np.ndarray):
            a.flags.writeable = False
    return value


def _cached(cache, owner, arrays: tuple, key: str, compute: Callable[[], object]):
    """``compute()`` once per ``owner``, again whenever one of ``arrays`` is replaced.

    The entry holds the arrays it was computed from (so their ids cannot be reused while it
    lives) and is dropped with the owner. Arrays changed in place are not noticed: a scene is
    data that the stages never change (core.scene).
    """
    entry = cache.get(owner)
    if entry is None or len(entry[0]) != len(arrays) or any(
            a is not b for a, b in zip(entry[0], arrays)):
        entry = (arrays, {})
        cache[owner] = entry
    if key not in entry[1]:
        entry[1][key] = _read_only(compute())
    return entry[1][key]


def _mesh_arrays(mesh) -> tuple:
    return (mesh.positions, mesh.triangles, mesh.normals)


def _scene_arrays(meshes) -> tuple:
    return tuple(meshes) + tuple(a for m in meshes for a in _mesh_arrays(m))


def _mesh_face_normals(mesh) -> np.ndarray:
    return _cached(_mesh_cache, mesh, _mesh_arrays(mesh), "face normals",
                   lambda: face_normals(mesh.positions, mesh.triangles)[0])


def _mesh_vertex_normals(mesh, weighting: str) -> np.ndarray:
    return _cached(_mesh_cache, mesh, _mesh_arrays(mesh), f"vertex normals {weighting}",
                   lambda: vertex_normals(mesh, weighting))


def _concatenated(scene, meshes, key: str, parts: Callable, width: int, dtype=np.float64):
    """The per-mesh arrays ``parts(mesh)`` of all meshes, one after another (cached)."""
    def join():
        arrays = [parts(m) for m in meshes]
        return np.concatenate(arrays) if arrays else np.zeros((0, width), dtype)
    return _cached(_scene_cache, scene, _scene_arrays(meshes), key, join)


def _geometry(scene, meshes):
    """``positions, triangles, face_surface, vertex_surface, vertex_offset`` of all meshes."""
    def build():
        sizes = np.array([len(m.positions) for m in meshes], dtype=np.int64)
        offset = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        positions = np.concatenate([m.positions for m in meshes]) if meshes else np.zeros((0, 3))
        triangles = (np.concatenate([m.triangles + offset[i] for i, m in enumerate(meshes)])
                     if meshes else np.zeros((0, 3), np.int64)).astype(np.int64)
        face_surface = np.repeat(np.arange(len(meshes), dtype=np.int64),
                                 [len(m.triangles) for m in meshes])
        vertex_surface = np.repeat(np.arange(len(meshes), dtype=np.int64), sizes)
        return positions, triangles, face_surface, vertex_surface, offset[:-1].copy()
    return _cached(_scene_cache, scene, _scene_arrays(meshes), "geometry", build)


# --------------------------------------------------------------------------------------------
# The vertex step of each mode


# Below this many faces or vertices one core is quicker: waking the second costs ~0.1 ms.
PARALLEL_ITEMS = 20_000


@njit(cache=True)
def _phong_face(positions, triangles, f, normals, face_surface, surfaces, lights, ambient, eye,
                halfway, out):
    """The model once for face ``f``, at its centroid with its face normal."""
    i0, i1, i2 = triangles[f, 0], triangles[f, 1], triangles[f, 2]
    cx = (positions[i0, 0] + positions[i1, 0] + positions[i2, 0]) / 3.0
    cy = (positions[i0, 1] + positions[i1, 1] + positions[i2, 1]) / 3.0
    cz = (positions[i0, 2] + positions[i1, 2] + positions[i2, 2]) / 3.0
    r, g, b = phong_point(cx, cy, cz, normals[f, 0], normals[f, 1], normals[f, 2],
                          face_surface[f], surfaces, lights, ambient, eye, halfway)
    out[f, 0], out[f, 1], out[f, 2] = r, g, b


@njit(cache=True, parallel=True)
def _phong_faces_parallel(positions, triangles, faces, normals, face_surface, surfaces, lights,
                          ambient, eye, halfway, out):
    for k in prange(faces.shape[0]):
        _phong_face(positions, triangles, faces[k], normals, face_surface, surfaces, lights,
                    ambient, eye, halfway, out)


@njit(cache=True)
def _phong_faces_serial(positions, triangles, faces, normals, face_surface, surfaces, lights,
                        ambient, eye, halfway, out):
    for k in range(faces.shape[0]):
        _phong_face(positions, triangles, faces[k], normals, face_surface, surfaces, lights,
                    ambient, eye, halfway, out)


def _prepare_flat(s: ShadeInput, scene, meshes, weighting) -> None:
    """One evaluation per face, at its centroid with its face normal (FvDFH 16.2.3)."""
    normals = _concatenated(scene, meshes, "face normals", _mesh_face_normals, 3)
    s.face_rgb = np.zeros((len(s.triangles), 3))          # faces not in s.faces stay unlit
    kernel = _phong_faces_parallel if len(s.faces) >= PARALLEL_ITEMS else _phong_faces_serial
    kernel(s.positions, s.triangles, s.faces, normals, s.face_surface, s.surfaces, s.lights,
           s.ambient, s.eye, s.halfway, s.face_rgb)
    s.computed += ["face normals", "illuminate faces"]


def _all_vertex_normals(s: ShadeInput, scene, meshes, weighting) -> np.ndarray:
    if any(m.normals is None and len(m.triangles) for m in meshes):
        s.computed.append("vertex normals")
    return _concatenated(scene, meshes, f"vertex normals {weighting}",
                         lambda m: _mesh_vertex_normals(m, weighting), 3)


def _prepare_gouraud(s: ShadeInput, scene, meshes, weighting) -> None:
    """The model at each vertex; the clipper and the resolve interpolate RGB (FvDFH 16.2.4)."""
    normals = _all_vertex_normals(s, scene, meshes, weighting)
    s.vertex_attrs = np.zeros((len(s.positions), 3))      # vertices no face uses stay unlit
    vertices = _used_vertices(s.triangles, s.faces, len(s.positions))
    kernel = _phong_vertices_parallel if len(vertices) >= PARALLEL_ITEMS else _phong_vertices_serial
    kernel(s.positions, normals, vertices, s.vertex_surface, s.surfaces, s.lights, s.ambient,
           s.eye, s.halfway, s.vertex_attrs)
    s.computed.append("illuminate vertices")


@njit(cache=True)
def _used_vertices(triangles, faces, vertex_count):
    """Indices of the vertices that the faces ``faces`` use, each once, in vertex order."""
    used = np.zeros(vertex_count, dtype=np.bool_)
    for k in range(faces.shape[0]):
        for c in range(3):
            used[triangles[faces[k], c]] = True
    return np.flatnonzero(used)


@njit(cache=True)
def _phong_vertex(positions, normals, i, vertex_surface, surfaces, lights, ambient, eye, halfway,
                  out):
    """The model at vertex ``i`` with its vertex normal (FvDFH 16.2.4)."""
    r, g, b = phong_point(positions[i, 0], positions[i, 1], positions[i, 2],
                          normals[i, 0], normals[i, 1], normals[i, 2], vertex_surface[i],
                          surfaces, lights, ambient, eye, halfway)
    out[i, 0], out[i, 1], out[i, 2] = r, g, b


@njit(cache=True, parallel=True)
def _phong_vertices_parallel(positions, normals, vertices, vertex_surface, surfaces, lights,
                             ambient, eye, halfway, out):
    for k in prange(vertices.shape[0]):
        _phong_vertex(positions, normals, vertices[k], vertex_surface, surfaces, lights, ambient,
                      eye, halfway, out)


@njit(cache=True)
def _phong_vertices_serial(positions, normals, vertices, vertex_surface, surfaces, lights,
                           ambient, eye, halfway, out):
    for k in range(vertices.shape[0]):
        _phong_vertex(positions, normals, vertices[k], vertex_surface, surfaces, lights, ambient,
                      eye, halfway, out)


def _prepare_phong(s: ShadeInput, scene, meshes, weighting) -> None:
    """Normals and world positions to interpolate; the model runs per pixel (FvDFH 16.2.5).

    Nothing here depends on the view, so the attribute array is kept with the scene."""
    normals = _all_vertex_normals(s, scene, meshes, weighting)
    s.vertex_attrs = _cached(_scene_cache, scene, _scene_arrays(meshes),
                             f"phong attributes {weighting}",
                             lambda: np.concatenate([normals, s.positions], axis=1))
    s.computed.append("illuminate pixels")


# --------------------------------------------------------------------------------------------
# The pixel step of each mode (numba; rows in parallel, pixels in order along the scan line)


@njit(cache=True, parallel=True)
def _resolve_flat(tri, source, face_rgb, background8, out):
    height, width = tri.shape
    for row in prange(height):
        for col in range(width):
            t = tri[row, col]
            if t < 0:
                for c in range(3):
                    out[row, col, c] = background8[c]
            else:
                f = source[t]
                for c in range(3):
                    out[row, col, c] = quantize(face_rgb[f, c])


@njit(cache=True, parallel=True)
def _resolve_gouraud(tri, b1, b2, triangles, rgb, background8, out):
    height, width = tri.shape
    for row in prange(height):
        for col in range(width):
            t = tri[row, col]
            if t < 0:
                for c in range(3):
                    out[row, col, c] = background8[c]
                continue
            i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            w1, w2 = b1[row, col], b2[row, col]
            w0 = 1.0 - w1 - w2
            for c in range(3):
                out[row, col, c] = quantize(w0 * rgb[i0, c] + w1 * rgb[i1, c] + w2 * rgb[i2, c])


@njit(cache=True, parallel=True)
def _resolve_phong(tri, b1, b2, triangles, attrs, source, face_surface, surfaces, lights,
                   ambient, eye, halfway, background8, out):
    height, width = tri.shape
    for row in prange(height):
        for col in range(width):
            t = tri[row, col]
            if t < 0:
                for c in range(3):
                    out[row, col, c] = background8[c]
                continue
            i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            w1, w2 = b1[row, col], b2[row, col]
            w0 = 1.0 - w1 - w2
            nx = w0 * attrs[i0, 0] + w1 * attrs[i1, 0] + w2 * attrs[i2, 0]
            ny = w0 * attrs[i0, 1] + w1 * attrs[i1, 1] + w2 * attrs[i2, 1]
            nz = w0 * attrs[i0, 2] + w1 * attrs[i1, 2] + w2 * attrs[i2, 2]
            px = w0 * attrs[i0, 3] + w1 * attrs[i1, 3] + w2 * attrs[i2, 3]
            py = w0 * attrs[i0, 4] + w1 * attrs[i1, 4] + w2 * attrs[i2, 4]
            pz = w0 * attrs[i0, 5] + w1 * attrs[i1, 5] + w2 * attrs[i2, 5]
            nx, ny, nz, _ = unit3(nx, ny, nz)        # renormalise the interpolated normal
            r, g, b = phong_point(px, py, pz, nx, ny, nz, face_surface[source[t]], surfaces,
                                  lights, ambient, eye, halfway)
            out[row, col, 0] = quantize(r)
            out[row, col, 1] = quantize(g)
            out[row, col, 2] = quantize(b)


class _Shader(NamedTuple):
    prepare: Callable
    attribute_count: int


SHADERS = {
    "flat": _Shader(_prepare_flat, 0),
    "gouraud": _Shader(_prepare_gouraud, 3),
    "phong": _Shader(_prepare_phong, 6),
}


# --------------------------------------------------------------------------------------------
# What the renderer calls


def geometry(scene) -> tuple[np.ndarray, np.ndarray]:
    """``(positions (V, 3), triangles (T, 3))``: all meshes over one vertex array, scene order
    (cached with the scene; the same arrays :func:`prepare` puts in its ShadeInput)."""
    positions, triangles, *_ = _geometry(scene, list(scene.meshes))
    return positions, triangles


def prepare(mode: str, scene, eye: Eye, weighting: str = "mean",
            faces: np.ndarray | None = None) -> ShadeInput:
    """The vertex step of ``mode`` for every mesh of ``scene`` seen from ``eye``.

    ``eye`` is :func:`eye_from_view`'s answer. ``weighting`` picks the vertex-normal average
    (:data:`core.scene.normals.WEIGHTINGS`; the notes' ``"mean"`` by default). ``faces``, when given,
    are the indices (into :func:`geometry`'s triangles) of the only faces that will be drawn,
    e.g. those back-face culling kept: flat lights only those faces and Gouraud only their
    vertices. Raises ValueError for an unknown mode or weighting.
    """
    if mode not in SHADERS:
        raise ValueError(f"shading must be one of {MODES}, not {mode!r}")
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting must be one of {WEIGHTINGS}, not {weighting!r}")
    meshes = list(scene.meshes)
    positions, triangles, face_surface, vertex_surface, offset = _geometry(scene, meshes)
    s = ShadeInput(
        mode=mode, positions=positions, triangles=triangles,
        vertex_attrs=np.zeros((len(positions), 0)), face_rgb=None,
        face_surface=face_surface, vertex_surface=vertex_surface, vertex_offset=offset,
        surfaces=pack_surfaces([m.material for m in meshes], [not m.closed for m in meshes]),
        lights=pack_lights(scene.lights), ambient=pack_ambient(scene.ambient),
        eye=pack_eye(eye), halfway=scene.specular == "halfway",
        faces=(np.arange(len(triangles), dtype=np.int64) if faces is None
               else np.ascontiguousarray(faces, dtype=np.int64)))
    SHADERS[mode].prepare(s, scene, meshes, weighting)
    return s


def resolve(shading: ShadeInput, vis, clipped_triangles: np.ndarray, clipped_attrs: np.ndarray,
            source: np.ndarray, background, out: np.ndarray | None = None) -> np.ndarray:
    """The pixel step: a visibility buffer → ``(H, W, 3)`` uint8, row 0 at the top.

    ``vis`` has ``tri`` ``(H, W)`` (-1 empty, else an index into ``clipped_triangles``) and
    ``b1``, ``b2`` (the perspective-correct weights of vertices 1 and 2). ``clipped_attrs``
    are ``shading.vertex_attrs`` after clipping; ``source`` maps each clipped triangle to its
    row of ``shading.triangles``. Empty pixels get ``background`` (RGB in [0, 1]). Writes into
    ``out`` when given.
    """
    tri = np.ascontiguousarray(vis.tri, dtype=np.int32)
    height, width = tri.shape
    if out is None:
        out = np.empty((height, width, 3), dtype=np.uint8)
    background8 = to_uint8(background).reshape(3)
    triangles = np.ascontiguousarray(clipped_triangles, dtype=np.int64).reshape(-1, 3)
    source = np.ascontiguousarray(source, dtype=np.int64).reshape(-1)
    attrs = np.ascontiguousarray(clipped_attrs, dtype=np.float64)
    k = SHADERS[shading.mode].attribute_count
    if attrs.ndim != 2 or attrs.shape[1] != k:
        raise ValueError(f"{shading.mode} shading carries {k} attributes per vertex, "
                         f"the clipper gave an array of shape {attrs.shape}")
    # The kernels index without bounds checks: refuse indices that point nowhere.
    if tri.size and tri.max() >= len(triangles):
        raise ValueError(f"the visibility buffer names triangle {tri.max()}, "
                         f"but only {len(triangles)} were clipped")
    if len(source) != len(triangles) or (source.size and not
                                         0 <= source.min() <= source.max() < len(shading.triangles)):
        raise ValueError("source must give, for each clipped triangle, its row of "
                         f"shading.triangles (0..{len(shading.triangles) - 1})")
    if k and triangles.size and not 0 <= triangles.min() <= triangles.max() < len(attrs):
        raise ValueError(f"clipped triangles index {len(attrs)} attribute rows out of range")
    if shading.mode == "flat":
        _resolve_flat(tri, source, np.ascontiguousarray(shading.face_rgb, dtype=np.float64),
                      background8, out)
    elif shading.mode == "gouraud":
        _resolve_gouraud(tri, np.ascontiguousarray(vis.b1, dtype=np.float64),
                         np.ascontiguousarray(vis.b2, dtype=np.float64), triangles, attrs,
                         background8, out)
    else:
        _resolve_phong(tri, np.ascontiguousarray(vis.b1, dtype=np.float64),
                       np.ascontiguousarray(vis.b2, dtype=np.float64), triangles, attrs, source,
                       shading.face_surface, shading.surfaces, shading.lights, shading.ambient,
                       shading.eye, shading.halfway, background8, out)
    return out
