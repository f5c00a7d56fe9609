"""Gouraud shading (FvDFH 16.2.4): the illumination model at each vertex with its vertex normal;
the colours are interpolated. Varyings: ``rgb`` (3)."""

from __future__ import annotations

import numpy as np

from core.arrays import read_only
from core.jit import call_compiled, compiled_at, njit, prange
from core.shading.illumination import quantize
from core.shading.models.dispatch import light_point
from core.shading.registry import Shader, register_shader
from core.shading.shade import (PARALLEL_ITEMS, RUN, ShadeInput, all_vertex_normals, cached,
                                 covered_spans, scene_arrays, unlit, visible_items,
                                 wide_shading)
from core.prefetch import prefetch
from core.shading.wide import AHEAD, illuminate_wide


def _prepare_gouraud(s: ShadeInput, scene, meshes, weighting) -> None:
    """The model at each vertex; the clipper and the resolve interpolate RGB (FvDFH 16.2.4).

    Lazy (the z-buffer's way): no vertex is lit here; the clipper lights the vertices of the
    triangles it cuts (``before_clip``) and the pixel step those of the visible triangles."""
    normals = all_vertex_normals(s, scene, meshes, weighting)
    # vertices no face uses stay unlit (black); kept in the context: no fresh 12 MB a frame
    s.vertex_attrs = s.context.scratch("gouraud rgb", (len(s.positions), 3), zero=True)
    s.computed.append("illuminate vertices")
    if s.lazy:
        s.normals = normals
        s.lit = np.zeros(len(s.positions), np.uint8)
        s.before_clip = lambda vertices: _light(s, unlit(vertices, s.lit), s.vertex_attrs)
        return
    s.normals = normals
    _light(s, _drawn_vertices(s, scene, meshes), s.vertex_attrs)


def _drawn_vertices(s: ShadeInput, scene, meshes) -> np.ndarray:
    """The vertices of the faces drawn: when no face is culled (a mesh not declared closed,
    such as a scan), those of every face, the same for every view (kept with the scene: a
    pass over the bunny's 69,451 faces, 0.17 ms a frame)."""
    if len(s.faces) == len(s.triangles):     # every face (``faces`` are distinct indices)
        return cached(s.context, scene, scene_arrays(meshes), "vertices of the faces",
                      lambda: _used_vertices(s.triangles, s.faces, len(s.positions)))
    return _used_vertices(s.triangles, s.faces, len(s.positions))


def _light(s: ShadeInput, vertices, out) -> None:
    """The model at ``vertices`` into the rows of ``out`` (their first rows are the mesh's)."""
    if wide_shading(s):
        illuminate_wide(s.positions, s.normals, s.vertex_surface, vertices, out, vertices,
                        s.surfaces, s.lights, s.ambient, s.eye, s.halfway,
                        len(vertices) >= PARALLEL_ITEMS)
        return
    given = (s.positions, s.normals, vertices, s.vertex_surface, s.surfaces, s.lights,
             s.ambient, s.eye, s.halfway, out, 0, len(vertices))
    if len(vertices) < PARALLEL_ITEMS:
        _phong_vertices(*given)
    else:
        _phong_vertices_parallel(*given[:-2], compiled_at(_phong_vertices, given))


@njit(cache=True)
def _used_vertices(triangles, faces, vertex_count):
    """Indices of the vertices that the faces ``faces`` use, each once, in vertex order."""
    used = np.zeros(vertex_count, dtype=np.bool_)
    for k in range(faces.shape[0]):
        for c in range(3):
            used[triangles[faces[k], c]] = True
    return np.flatnonzero(used)


@njit(cache=True, inline="always")   # no call, no reference counts per point
def _phong_vertex(positions, normals, i, vertex_surface, surfaces, lights, ambient, eye, halfway,
                  out):
    """The model at vertex ``i`` with its vertex normal (FvDFH 16.2.4)."""
    r, g, b = light_point(positions[i, 0], positions[i, 1], positions[i, 2],
                          normals[i, 0], normals[i, 1], normals[i, 2], vertex_surface[i],
                          surfaces, lights, ambient, eye, halfway)
    out[i, 0], out[i, 1], out[i, 2] = r, g, b


# numpy's error model, as the parallel loop's body that it was
@njit(cache=True, nogil=True, error_model="numpy")
def _phong_vertices(positions, normals, vertices, vertex_surface, surfaces, lights, ambient,
                    eye, halfway, out, start, end):
    """:func:`_phong_vertex` for ``vertices[start:end]``."""
    for k in range(start, end):
        _phong_vertex(positions, normals, vertices[k], vertex_surface, surfaces, lights, ambient,
                      eye, halfway, out)


@njit(cache=True, parallel=True, nogil=True)
def _phong_vertices_parallel(positions, normals, vertices, vertex_surface, surfaces, lights,
                             ambient, eye, halfway, out, at):
    """:func:`_phong_vertices` on runs of :data:`RUN` vertices, in parallel, called by its
    address ``at``: the lighting models' code is not optimised again inside this loop."""
    n = vertices.shape[0]
    for j in prange((n + RUN - 1) // RUN):
        start = np.int64(j) * RUN
        call_compiled(at, _phong_vertices, positions, normals, vertices, vertex_surface,
                      surfaces, lights, ambient, eye, halfway, out, start, min(n, start + RUN))


@njit(cache=True, parallel=True, nogil=True)
def resolve_gouraud(tri, b1, b2, span, triangles, rgb, out):
    """Interpolate the vertex colours over each row's covered span (the rest is background).
    A triangle's pixels come in runs along a row: its corner colours are read once a run."""
    for row in prange(tri.shape[0]):
        last = -1
        r0 = g0 = b0 = r1 = g1 = b1_ = r2 = g2 = b2_ = 0.0
        end = span[row, 1]
        for col_ in range(span[row, 0], end + 1):
            col = np.uint64(col_)      # unsigned: no wraparound select (core.pipeline.raster)
            prefetch(triangles, max(tri[row, np.uint64(min(col_ + AHEAD, end))], 0))  # as Phong's
            t = tri[row, col]
            if t < 0:
                continue                # background, filled before
            if t != last:
                last = t
                u = np.uint64(t)
                i0, i1, i2 = (np.uint64(triangles[u, 0]), np.uint64(triangles[u, 1]),
                              np.uint64(triangles[u, 2]))
                r0, g0, b0 = rgb[i0, 0], rgb[i0, 1], rgb[i0, 2]
                r1, g1, b1_ = rgb[i1, 0], rgb[i1, 1], rgb[i1, 2]
                r2, g2, b2_ = rgb[i2, 0], rgb[i2, 1], rgb[i2, 2]
            w1, w2 = b1[row, col], b2[row, col]
            w0 = 1.0 - w1 - w2
            out[row, col, 0] = quantize(w0 * r0 + w1 * r1 + w2 * r2)
            out[row, col, 1] = quantize(w0 * g0 + w1 * g1 + w2 * g2)
            out[row, col, 2] = quantize(w0 * b0 + w1 * b1_ + w2 * b2_)


def _pixel(s: ShadeInput, vis, triangles, attrs, source, background8, out) -> None:
    if s.lazy:      # light the mesh vertices that visible triangles use (new ones are done)
        _light(s, visible_items(vis, triangles, 3, s.lit), attrs)
    resolve_gouraud(np.ascontiguousarray(vis.tri, dtype=np.int32),
                     np.ascontiguousarray(vis.b1, dtype=np.float64),
                     np.ascontiguousarray(vis.b2, dtype=np.float64), covered_spans(vis),
                     triangles, read_only(attrs), out)


register_shader(Shader("gouraud", _prepare_gouraud, _pixel, varyings=("rgb",), width=3,
                       description="the model at the vertices, colours interpolated",
                       lit_items=lambda scene: sum(len(m.positions) for m in scene.meshes)))
