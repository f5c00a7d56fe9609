"""Phong shading (FvDFH 16.2.5): normals and world positions interpolated, the normal
renormalised and the illumination model evaluated at every pixel. Varyings: ``normal`` (3),
``position`` (3)."""

from __future__ import annotations

import numpy as np

from core.arrays import read_only
from core.jit import call_compiled, compiled_at, njit, prange
from core.shading.illumination import quantize, unit3
from core.shading.models.dispatch import light_point
from core.shading.wide import resolve_phong_wide
from core.shading.registry import Shader, register_shader
from core.shading.shade import (ShadeInput, all_vertex_normals, cached, covered_spans,
                                 scene_arrays, wide_shading)


def _prepare_phong(s: ShadeInput, scene, meshes, weighting) -> None:
    """Normals and world positions to interpolate; the model runs per pixel (FvDFH 16.2.5).

    Nothing here depends on the view, so the attribute array is kept with the scene."""
    normals = all_vertex_normals(s, scene, meshes, weighting)
    s.vertex_attrs = cached(s.context, scene, scene_arrays(meshes),
                             f"phong attributes {weighting}",
                             lambda: np.concatenate([normals, s.positions], axis=1))
    s.computed.append("illuminate pixels")


# numpy's error model, as the parallel loop's body that it was
@njit(cache=True, nogil=True, error_model="numpy")
def _phong_rows(tri, b1, b2, span, triangles, attrs, source, face_surface, surfaces, lights,
                ambient, eye, halfway, out, start, end):
    """The model at every covered pixel of the spans of rows ``start`` to ``end`` (the rest
    is background)."""
    for row in range(start, end):
        for col in range(span[row, 0], span[row, 1] + 1):
            t = tri[row, col]
            if t < 0:
                continue                # background, filled before
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
            r, g, b = light_point(px, py, pz, nx, ny, nz, face_surface[source[t]], surfaces,
                                  lights, ambient, eye, halfway)
            out[row, col, 0] = quantize(r)
            out[row, col, 1] = quantize(g)
            out[row, col, 2] = quantize(b)


ROWS = 4    # picture rows a call of the parallel loop


@njit(cache=True, parallel=True, nogil=True)
def _resolve_phong(tri, b1, b2, span, triangles, attrs, source, face_surface, surfaces, lights,
                   ambient, eye, halfway, out, at):
    """:func:`_phong_rows` on runs of :data:`ROWS` rows, in parallel, called by its address
    ``at`` (core.jit.call_compiled): every lighting model is typed and optimised once, in
    ``_phong_rows``, not again inside this loop."""
    n = tri.shape[0]
    for j in prange((n + ROWS - 1) // ROWS):
        start = np.int64(j) * ROWS
        call_compiled(at, _phong_rows, tri, b1, b2, span, triangles, attrs, source,
                      face_surface, surfaces, lights, ambient, eye, halfway, out, start,
                      min(n, start + ROWS))


def _pixel(s: ShadeInput, vis, triangles, attrs, source, background8, out) -> None:
    """float32 passes (core.shading.wide) unless the settings ask for the textbook
    kernel or an exponent is not a whole number up to 2^16 (then float64 throughout)."""
    given = (np.ascontiguousarray(vis.tri, dtype=np.int32),
             np.ascontiguousarray(vis.b1, dtype=np.float64),
             np.ascontiguousarray(vis.b2, dtype=np.float64), covered_spans(vis), triangles,
             read_only(attrs), source, s.face_surface, s.surfaces, s.lights, s.ambient, s.eye,
             s.halfway, out)
    if wide_shading(s):
        resolve_phong_wide(*given)
    else:
        _resolve_phong(*given, compiled_at(_phong_rows, given + (0, 0)))


register_shader(Shader("phong", _prepare_phong, _pixel, varyings=("normal", "position"), width=6,
                       description="normals interpolated, the model at every pixel"))
