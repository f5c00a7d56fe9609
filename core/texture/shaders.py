"""The ``textured`` shader: Phong with a material's maps, and the course's bump demo material.

Registered in :mod:`core.shading.registry` as ``"textured"``; the z-buffer also uses it for
``phong`` whenever a mesh's material has maps (:func:`shading_for`), so a scene asks for Phong
shading and gets its textures. Flat and Gouraud shading draw textured materials untextured:
a texture, a bump map and a normal map all need a value per pixel, which those modes do not
compute (the plan says so).

Vertex step (world coordinates, kept with the scene): the varyings of
:mod:`core.texture.surface` — normal, position, (u, v) times the material's ``uv_scale``, and
the tangent frame ∂P/∂u, ∂P/∂v (:func:`core.texture.material.tangent_frames`; zero where no
map needs it). Meshes without (u, v) (``.tri`` files, OBJ without ``vt``) get (0, 0) and are
drawn with the material's colour.

Pixel step: (u, v) derivatives come from the clipped triangles' device coordinates, which
the z-buffer hands over as ``ShadeInput.device`` (the tutorial's plane constants,
:func:`core.texture.tutorial.plane_constants`, made when a scan line enters a triangle, so
only visible triangles pay for them); the filter and the bump switch come from
``RenderSettings.texture_filter`` and ``.bump`` (``ShadeInput.settings``).
"""

from __future__ import annotations

import numpy as np

from core.arrays import read_only
from core.jit import call_compiled, compiled_at, njit, prange
from core.shading.illumination import OD, quantize
from core.shading.registry import Shader, register_shader
from core.shading.shade import ShadeInput, all_vertex_normals, cached, scene_arrays
from core.texture.bump_demo import DEMO_LIGHT, demo_pixel, java_color_byte
from core.texture.material import TEXTURED_MODE, maps_of, tangent_frames
from core.texture.sample import FILTERS, TRILINEAR
from core.texture.surface import UV, VARYING_COLUMNS, pack_maps, textured_pixel
from core.texture.tutorial import plane_constants

NAME = "textured"
# Columns of a packed demo row: kind (1 = the bump demo), map, bump on, viewpoint (3).
DEMO_COLUMNS = 6


def shading_for(scene, shading: str) -> str:
    """``"textured"`` for Phong shading of a scene with any mapped or demo material."""
    if shading == TEXTURED_MODE and any(maps_of(m.material) is not None for m in scene.meshes):
        return NAME
    return shading


def mesh_varyings(mesh) -> np.ndarray:
    """``(V, 8)``: (u, v) scaled, ∂P/∂u, ∂P/∂v of one mesh (zeros where it has no (u, v))."""
    out = np.zeros((len(mesh.positions), 8))
    maps = maps_of(mesh.material)
    if mesh.uv is None or maps is None:
        return out
    uv = mesh.uv * np.asarray(maps.uv_scale)
    out[:, :2] = uv
    if maps.needs_tangents and len(mesh.triangles):
        out[:, 2:] = tangent_frames(mesh.positions, mesh.triangles, uv)
    return out


def _demo_rows(meshes) -> np.ndarray:
    rows = np.zeros((len(meshes), DEMO_COLUMNS))
    for s, mesh in enumerate(meshes):
        maps = maps_of(mesh.material)
        if maps is not None and maps.demo is not None:
            rows[s] = (1.0, maps.demo.bump_map, float(maps.demo.bump), *maps.demo.viewpoint)
    return rows


def _packed_maps(s: ShadeInput, scene, meshes):
    """:func:`pack_maps` of the materials, kept while the same textures and numbers are used
    (packing copies every texel: tens of MB a frame for a few large textures). Kept in the
    context's cache of the scene under its own key, holding the textures it was made from."""
    all_maps = [maps_of(m.material) for m in meshes]
    textures = tuple(t for m in all_maps if m is not None
                     for t in (m.color, m.height, m.normal_map, m.environment) if t is not None)
    numbers = [(m.bump_scale, m.reflectivity, [t is None for t in (
        m.color, m.height, m.normal_map, m.environment)]) if m is not None else None
        for m in all_maps]
    cache = s.context.cache(scene)
    held = cache.get("texture maps")
    if (held is None or held[1] != numbers or len(held[0]) != len(textures)
            or any(a is not b for a, b in zip(held[0], textures))):
        held = cache["texture maps"] = (textures, numbers, pack_maps(all_maps))
    return held[2]


def _vertex(s: ShadeInput, scene, meshes, weighting) -> None:
    normals = all_vertex_normals(s, scene, meshes, weighting)
    # Maps are read from the materials each frame (a window may switch the demo's map); the
    # arrays that depend only on the geometry are kept with the scene.
    extra = cached(s.context, scene, scene_arrays(meshes), "texture varyings",
                   lambda: np.concatenate([mesh_varyings(m) for m in meshes]) if meshes
                   else np.zeros((0, 8)))
    s.vertex_attrs = cached(s.context, scene, scene_arrays(meshes),
                            f"textured attributes {weighting}",
                            lambda: np.concatenate([normals, s.positions, extra], axis=1))
    s.texture_maps = _packed_maps(s, scene, meshes)
    s.demo = _demo_rows(meshes)
    s.computed += ["illuminate pixels", "texture lookups"]


ROWS = 4    # picture rows a call of the parallel loop


@njit(cache=True, parallel=True, nogil=True)
def _resolve(tri, b1, b2, triangles, attrs, device_h, source, face_surface, surfaces, maps,
             texels, levels, textures, demo, demo_light, filter_, bump, lights, ambient, eye,
             halfway, background8, out, at):
    """:func:`_textured_rows` on runs of :data:`ROWS` rows, in parallel, called by its
    address ``at`` (core.jit.call_compiled): the texture lookups and the lighting are
    optimised once, in ``_textured_rows``, not again inside this loop."""
    n = tri.shape[0]
    for j in prange((n + ROWS - 1) // ROWS):
        start = np.int64(j) * ROWS
        call_compiled(at, _textured_rows, tri, b1, b2, triangles, attrs, device_h, source,
                      face_surface, surfaces, maps, texels, levels, textures, demo, demo_light,
                      filter_, bump, lights, ambient, eye, halfway, background8, out, start,
                      min(n, start + ROWS), surfaces.copy(), np.zeros((1, 3, 3)))


# numpy's error model, as the parallel loop's body that it was; no reference counts (_nrt:
# it makes no array, and the counts of the views it takes cost 17 % of a textured frame)
@njit(cache=True, nogil=True, error_model="numpy", _nrt=False)
def _textured_rows(tri, b1, b2, triangles, attrs, device_h, source, face_surface, surfaces,
                   maps, texels, levels, textures, demo, demo_light, filter_, bump, lights,
                   ambient, eye, halfway, background8, out, start, end, surf, constants):
    """Every pixel of rows ``start`` to ``end``: the background, the bump demo's model, or
    the textured model. ``surf``: a copy of ``surfaces``, where a pixel writes its texture's
    O_d, then undoes it; ``constants`` (1, 3, 3): the visible triangle's plane constants,
    made when the scan line enters it (per visible triangle, not for every triangle)."""
    height, width = tri.shape
    for row in range(start, end):
        current = -1
        for col in range(width):
            t = tri[row, col]
            if t < 0:
                for c in range(3):
                    out[row, col, c] = background8[c]
                continue
            i0, i1, i2 = triangles[t, 0], triangles[t, 1], triangles[t, 2]
            w1, w2 = b1[row, col], b2[row, col]
            w0 = 1.0 - w1 - w2
            s = face_surface[source[t]]
            if demo[s, 0] > 0.5:                # the course's bump demo: its own model
                blue = demo_shade(attrs, i0, i1, i2, w0, w1, w2, demo, s, demo_light)
                out[row, col, 0] = 0
                out[row, col, 1] = 0
                out[row, col, 2] = java_color_byte(blue)
                continue
            if t != current:
                current = t
                for a in range(3):
                    for b in range(3):
                        constants[0, a, b] = 0.0
                if device_h.shape[0]:
                    plane_constants(device_h, i0, i1, i2, attrs[i0, UV], attrs[i0, UV + 1],
                                    attrs[i1, UV], attrs[i1, UV + 1], attrs[i2, UV],
                                    attrs[i2, UV + 1], float(height), constants, 0)
            r, g, b = textured_pixel(attrs, i0, i1, i2, w0, w1, w2, 0, col, row, constants,
                                     s, maps, texels, levels, textures, filter_, bump, surf,
                                     lights, ambient, eye, halfway)
            for c in range(3):
                surf[s, OD + c] = surfaces[s, OD + c]
            out[row, col, 0] = quantize(r)
            out[row, col, 1] = quantize(g)
            out[row, col, 2] = quantize(b)


@njit(cache=True)
def demo_shade(attrs, i0, i1, i2, w0, w1, w2, demo, s, light):
    """The demo's pixel step at the interpolated point and normal."""
    nx = w0 * attrs[i0, 0] + w1 * attrs[i1, 0] + w2 * attrs[i2, 0]    # the normal, then the
    ny = w0 * attrs[i0, 1] + w1 * attrs[i1, 1] + w2 * attrs[i2, 1]    # position: the first
    nz = w0 * attrs[i0, 2] + w1 * attrs[i1, 2] + w2 * attrs[i2, 2]    # six varyings
    x = w0 * attrs[i0, 3] + w1 * attrs[i1, 3] + w2 * attrs[i2, 3]
    y = w0 * attrs[i0, 4] + w1 * attrs[i1, 4] + w2 * attrs[i2, 4]
    z = w0 * attrs[i0, 5] + w1 * attrs[i1, 5] + w2 * attrs[i2, 5]
    return demo_pixel(x, y, z, nx, ny, nz, light, demo[s, 3:6], int(demo[s, 1]),
                      demo[s, 2] > 0.5)


def _pixel(s: ShadeInput, vis, triangles, attrs, source, background8, out) -> None:
    filter_ = FILTERS.get(s.settings.texture_filter if s.settings else "trilinear", TRILINEAR)
    bump = s.settings.bump if s.settings else True
    tri = np.ascontiguousarray(vis.tri, dtype=np.int32)
    device = s.device
    if device is not None:
        points, inv_w = device
        w = np.divide(1.0, inv_w, out=np.zeros_like(inv_w), where=inv_w > 0)
        device_h = np.column_stack([points * w[:, None], w])
    else:                                   # no device coordinates: no derivatives, level 0
        device_h = np.zeros((0, 4))
    texels, levels, textures, maps = s.texture_maps
    # the demo lights its panel with the scene's first light (J3DPanel's lightSource)
    demo_light = (s.lights[0, 1:4].copy() if len(s.lights) and s.lights[0, 0] == 0.0
                  else np.array(DEMO_LIGHT))
    given = (tri, np.ascontiguousarray(vis.b1, dtype=np.float64),
             np.ascontiguousarray(vis.b2, dtype=np.float64), triangles, read_only(attrs),
             device_h, source, s.face_surface, s.surfaces, maps, texels, levels, textures, s.demo,
             demo_light, filter_, bump, s.lights, s.ambient, s.eye, s.halfway, background8, out)
    _resolve(*given, compiled_at(_textured_rows, given + (0, 0, s.surfaces.copy(),
                                                        np.zeros((1, 3, 3)))))


register_shader(Shader(NAME, _vertex, _pixel,
                       varyings=("normal", "position", "uv", "dpdu", "dpdv"),
                       width=VARYING_COLUMNS,
                       description="Phong with the material's textures, bump/normal and "
                                   "environment maps (and the bump demo's material)"))
