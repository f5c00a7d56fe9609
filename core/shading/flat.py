"""Flat shading (FvDFH 16.2.3): the illumination model once per face, at its centroid with its
face normal; every pixel of the face gets that colour. Varyings: none."""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from core.shading.illumination import phong_point, quantize
from core.shading.registry import Shader, register_shader
from core.shading.shade import (PARALLEL_ITEMS, ShadeInput, all_face_normals, covered_spans,
                                 visible_items)


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


@njit(cache=True, parallel=True, nogil=True)
def _phong_faces_parallel(positions, triangles, faces, normals, face_surface, surfaces, lights,
                          ambient, eye, halfway, out):
    for k in prange(faces.shape[0]):
        _phong_face(positions, triangles, faces[k], normals, face_surface, surfaces, lights,
                    ambient, eye, halfway, out)


@njit(cache=True, nogil=True)
def _phong_faces_serial(positions, triangles, faces, normals, face_surface, surfaces, lights,
                        ambient, eye, halfway, out):
    for k in range(faces.shape[0]):
        _phong_face(positions, triangles, faces[k], normals, face_surface, surfaces, lights,
                    ambient, eye, halfway, out)


def _prepare_flat(s: ShadeInput, scene, meshes, weighting) -> None:
    """One evaluation per face, at its centroid with its face normal (FvDFH 16.2.3).

    Lazy (the z-buffer's way): no face is lit here; the pixel step lights the visible ones."""
    s.normals = all_face_normals(s, scene, meshes)
    s.face_rgb = s.context.scratch("flat rgb", (len(s.triangles), 3), zero=True)  # unlit: black
    s.computed += ["face normals", "illuminate faces"]
    if s.lazy:
        s.lit = np.zeros(len(s.triangles), np.uint8)
        return
    _light(s, s.faces)


def _light(s: ShadeInput, faces) -> None:
    kernel = _phong_faces_parallel if len(faces) >= PARALLEL_ITEMS else _phong_faces_serial
    kernel(s.positions, s.triangles, faces, s.normals, s.face_surface, s.surfaces, s.lights,
           s.ambient, s.eye, s.halfway, s.face_rgb)


@njit(cache=True, parallel=True, nogil=True)
def _resolve_flat(tri, span, source, face_rgb, out):
    """Each covered pixel of each row's span gets its face's colour (the rest is background)."""
    for row in prange(tri.shape[0]):
        for col in range(span[row, 0], span[row, 1] + 1):
            t = tri[row, col]
            if t >= 0:
                f = source[t]
                for c in range(3):
                    out[row, col, c] = quantize(face_rgb[f, c])



def _pixel(s: ShadeInput, vis, triangles, attrs, source, background8, out) -> None:
    if s.lazy:                          # light the faces that some pixel shows
        _light(s, visible_items(vis, source.reshape(-1, 1), 1, s.lit))
    _resolve_flat(np.ascontiguousarray(vis.tri, dtype=np.int32), covered_spans(vis), source,
                  np.ascontiguousarray(s.face_rgb, dtype=np.float64), out)


register_shader(Shader("flat", _prepare_flat, _pixel, description="one colour per face"))
