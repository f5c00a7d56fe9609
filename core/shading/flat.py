"""Flat shading (FvDFH 16.2.3): the illumination model once per polygon, at its centroid with
its normal; every pixel of the polygon gets that colour. Varyings: none.

The course's polygons arrive here as triangles: a planar quad is two. Faces that share an edge
and lie in one plane (:func:`core.scene.normals.planar_polygons`) are lit as one polygon, at
the area-weighted centroid of the whole polygon, so a flat quad has no diagonal seam. A face
alone in its plane is lit at its own centroid, exactly as before."""

from __future__ import annotations

import numpy as np

from core.jit import call_compiled, compiled_at, njit, prange
from core.shading.illumination import quantize
from core.shading.models.dispatch import light_point
from core.shading.registry import Shader, register_shader
from core.scene.normals import face_normals, planar_polygons
from core.shading.shade import (PARALLEL_ITEMS, RUN, ShadeInput, all_face_normals, cached,
                                 covered_spans, scene_arrays, visible_items, wide_shading)
from core.shading.wide import illuminate_wide


@njit(cache=True, inline="always")   # no call, no reference counts per face
def _face_point(positions, triangles, f, polygon, polygon_point):
    """Where face ``f`` is lit and whose normal it takes: its polygon's centroid and the
    polygon's row (the same numbers for every face of the polygon), or its own centroid and
    row when it is alone in its plane."""
    p = polygon[f]
    if p >= 0:
        return polygon_point[p, 0], polygon_point[p, 1], polygon_point[p, 2], p
    i0, i1, i2 = triangles[f, 0], triangles[f, 1], triangles[f, 2]
    cx = (positions[i0, 0] + positions[i1, 0] + positions[i2, 0]) / 3.0
    cy = (positions[i0, 1] + positions[i1, 1] + positions[i2, 1]) / 3.0
    cz = (positions[i0, 2] + positions[i1, 2] + positions[i2, 2]) / 3.0
    return cx, cy, cz, f


@njit(cache=True, inline="always")   # no call, no reference counts per face
def _phong_face(positions, triangles, f, normals, polygon, polygon_point, face_surface,
                surfaces, lights, ambient, eye, halfway, out):
    """The model once for face ``f`` (FvDFH 16.2.3), at :func:`_face_point`."""
    cx, cy, cz, p = _face_point(positions, triangles, f, polygon, polygon_point)
    r, g, b = light_point(cx, cy, cz, normals[p, 0], normals[p, 1], normals[p, 2],
                          face_surface[f], surfaces, lights, ambient, eye, halfway)
    out[f, 0], out[f, 1], out[f, 2] = r, g, b


@njit(cache=True, nogil=True)
def _face_points(positions, triangles, normals, polygon, polygon_point):
    """:func:`_face_point` of every face: the points and normals the float32 passes
    (core.shading.wide) light, made once per scene (:func:`face_points`)."""
    points, unit = np.empty((triangles.shape[0], 3)), np.empty((triangles.shape[0], 3))
    for f in range(triangles.shape[0]):
        cx, cy, cz, p = _face_point(positions, triangles, f, polygon, polygon_point)
        points[f, 0], points[f, 1], points[f, 2] = cx, cy, cz
        unit[f, 0], unit[f, 1], unit[f, 2] = normals[p, 0], normals[p, 1], normals[p, 2]
    return points, unit


# numpy's error model, as the parallel loop's body that it was
@njit(cache=True, nogil=True, error_model="numpy")
def _phong_faces(positions, triangles, faces, normals, polygon, polygon_point, face_surface,
                 surfaces, lights, ambient, eye, halfway, out, start, end):
    """:func:`_phong_face` for ``faces[start:end]``."""
    for k in range(start, end):
        _phong_face(positions, triangles, faces[k], normals, polygon, polygon_point,
                    face_surface, surfaces, lights, ambient, eye, halfway, out)


@njit(cache=True, parallel=True, nogil=True)
def _phong_faces_parallel(positions, triangles, faces, normals, polygon, polygon_point,
                          face_surface, surfaces, lights, ambient, eye, halfway, out, at):
    """:func:`_phong_faces` on runs of :data:`RUN` faces, in parallel, called by its address
    ``at`` (core.jit.call_compiled): every lighting model is typed and optimised once, in
    ``_phong_faces``, not again inside this loop."""
    n = faces.shape[0]
    for j in prange((n + RUN - 1) // RUN):
        start = np.int64(j) * RUN
        call_compiled(at, _phong_faces, positions, triangles, faces, normals, polygon,
                      polygon_point, face_surface, surfaces, lights, ambient, eye, halfway, out,
                      start, min(n, start + RUN))


def _mesh_polygons(mesh) -> tuple[np.ndarray, np.ndarray]:
    """``(polygon (T,), point (T, 3))`` of one mesh: each face's polygon (its lowest face; -1
    for a face alone in its plane) and, at that lowest face's row, the polygon's area-weighted
    centroid."""
    normals, double_area = face_normals(mesh.positions, mesh.triangles)
    polygon = planar_polygons(mesh.positions, mesh.triangles, normals)
    count = len(polygon)
    size = np.bincount(polygon, minlength=count)
    centroid = mesh.positions[mesh.triangles].sum(axis=1) / 3.0
    area = np.bincount(polygon, weights=double_area, minlength=count)
    point = np.zeros((count, 3))
    for c in range(3):
        point[:, c] = np.bincount(polygon, weights=double_area * centroid[:, c], minlength=count)
    ok = area > 0.0
    point[ok] /= area[ok, None]
    return np.where(size[polygon] > 1, polygon, -1), point


def lighting_points(mesh) -> tuple[np.ndarray, np.ndarray]:
    """``(point (T, 3), normal (T, 3))``: where and with which normal flat shading evaluates
    the model for each face of ``mesh`` (the GL oracle draws flat with the same numbers)."""
    polygon, point = _mesh_polygons(mesh)
    normals = face_normals(mesh.positions, mesh.triangles)[0]
    alone = polygon < 0
    own = np.where(alone, np.arange(len(polygon)), polygon)
    where = np.where(alone[:, None], mesh.positions[mesh.triangles].sum(axis=1) / 3.0,
                     point[own])
    return where, normals[own]


def polygons(s: ShadeInput, scene, meshes) -> tuple[np.ndarray, np.ndarray]:
    """Every mesh's :func:`_mesh_polygons`, scene order, faces numbered across the scene."""
    def build():
        parts = [cached(s.context, m, (m.positions, m.triangles, m.normals), "flat polygons",
                        lambda m=m: _mesh_polygons(m)) for m in meshes]
        offsets = np.cumsum([0] + [len(p[0]) for p in parts])
        polygon = [np.where(p[0] >= 0, p[0] + offsets[i], -1) for i, p in enumerate(parts)]
        return ((np.concatenate(polygon) if parts else np.zeros(0, np.int64)),
                (np.concatenate([p[1] for p in parts]) if parts else np.zeros((0, 3))))
    return cached(s.context, scene, scene_arrays(meshes), "flat polygons", build)


def face_points(s: ShadeInput, scene, meshes) -> tuple[np.ndarray, np.ndarray]:
    """Where each face of the scene is lit and the normal it takes (:func:`_face_points`): the
    same for every camera, so made once per scene rather than for the lit faces of each frame
    (1.4 ms of one core a frame for the bunny's 69,451 faces)."""
    return cached(s.context, scene, scene_arrays(meshes), "flat face points",
                  lambda: _face_points(s.positions, s.triangles, s.normals, s.polygon,
                                       s.polygon_point))


def _prepare_flat(s: ShadeInput, scene, meshes, weighting) -> None:
    """One evaluation per polygon, at its centroid with its normal (FvDFH 16.2.3).

    Lazy (the z-buffer's way): no face is lit here; the pixel step lights the visible ones."""
    s.normals = all_face_normals(s, scene, meshes)
    s.polygon, s.polygon_point = polygons(s, scene, meshes)
    if wide_shading(s):
        s.face_points = face_points(s, scene, meshes)
    s.face_rgb = s.context.scratch("flat rgb", (len(s.triangles), 3), zero=True)  # unlit: black
    s.face_bytes = s.context.scratch("flat bytes", (len(s.triangles), 3), np.uint8, zero=True)
    s.computed += ["face normals", "illuminate faces"]
    if s.lazy:
        s.lit = np.zeros(len(s.triangles), np.uint8)
        return
    _light(s, s.faces)


def _light(s: ShadeInput, faces) -> None:
    """Light ``faces`` into ``s.face_rgb``, and round their colours to ``s.face_bytes``."""
    parallel = len(faces) >= PARALLEL_ITEMS
    if wide_shading(s):
        points, normals = s.face_points
        illuminate_wide(points, normals, s.face_surface, faces, s.face_rgb, faces, s.surfaces,
                        s.lights, s.ambient, s.eye, s.halfway, parallel)
    else:
        given = (s.positions, s.triangles, faces, s.normals, s.polygon, s.polygon_point,
                 s.face_surface, s.surfaces, s.lights, s.ambient, s.eye, s.halfway,
                 s.face_rgb, 0, len(faces))
        if len(faces) < PARALLEL_ITEMS:
            _phong_faces(*given)
        else:
            _phong_faces_parallel(*given[:-2], compiled_at(_phong_faces, given))
    (_face_bytes_parallel if parallel else _face_bytes)(s.face_rgb, faces, s.face_bytes)


@njit(cache=True, nogil=True)
def _face_bytes(face_rgb, faces, out):
    """Each face's colour rounded to bytes (:func:`quantize`), once a face, not once a run of
    its pixels."""
    for k in range(faces.shape[0]):
        f = faces[k]
        out[f, 0], out[f, 1], out[f, 2] = (quantize(face_rgb[f, 0]), quantize(face_rgb[f, 1]),
                                           quantize(face_rgb[f, 2]))


@njit(cache=True, parallel=True, nogil=True)
def _face_bytes_parallel(face_rgb, faces, out):
    """:func:`_face_bytes` on runs of :data:`RUN` faces, in parallel."""
    n = faces.shape[0]
    for j in prange((n + RUN - 1) // RUN):
        start = np.int64(j) * RUN
        _face_bytes(face_rgb, faces[start:min(n, start + RUN)], out)


@njit(cache=True, parallel=True, nogil=True)
def _resolve_flat(tri, span, source, face_bytes, out):
    """Each covered pixel of each row's span gets its face's bytes (the rest is background):
    loaded at every pixel, with no test for a new triangle (a branch that the bunny's runs of
    1.4 pixels mispredict: at 1580 x 1080 the runs' way took 1.1 ms, this 0.64)."""
    for row in prange(tri.shape[0]):
        for col_ in range(span[row, 0], span[row, 1] + 1):
            col = np.uint64(col_)      # unsigned: no wraparound select (core.pipeline.raster)
            t = tri[row, col]
            if t >= 0:
                f = np.uint64(source[np.uint64(t)])
                out[row, col, 0], out[row, col, 1], out[row, col, 2] = (
                    face_bytes[f, 0], face_bytes[f, 1], face_bytes[f, 2])


def _pixel(s: ShadeInput, vis, triangles, attrs, source, background8, out) -> None:
    if s.lazy:                          # light the faces that some pixel shows
        _light(s, visible_items(vis, source.reshape(-1, 1), 1, s.lit))
    _resolve_flat(np.ascontiguousarray(vis.tri, dtype=np.int32), covered_spans(vis), source,
                  s.face_bytes, out)


register_shader(Shader("flat", _prepare_flat, _pixel, description="one colour per polygon",
                       barycentrics=False, lit_items=lambda scene: scene.triangle_count))
