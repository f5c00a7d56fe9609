"""What every shading mode shares (FvDFH 16.2.3–16.2.5; Assignment #3), on a visibility buffer.

The modes themselves are :mod:`core.shading.flat`, :mod:`~core.shading.gouraud` and
:mod:`~core.shading.phong`, found through :mod:`core.shading.registry`.

The z-buffer pass (``core.pipeline.raster``) leaves, per pixel, the index of the visible (post-clip)
triangle and the perspective-correct barycentric weights of its vertices. Shading is then two
small steps per mode, a "vertex" step before clipping and a "pixel" step after rasterizing
(tinyrenderer's shader split; the z-buffer knows nothing about light):

=========  ==========================================  =======================================
mode       before clipping (world coordinates)         per pixel (resolve)
=========  ==========================================  =======================================
flat       face normals; the model once per planar     the face's colour: ``face_rgb[source]``
           polygon at its centroid → ``face_rgb (T, 3)``
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

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from core.camera.film import fill_bytes
from core.context import DEFAULT_CONTEXT, RenderContext
from core.arrays import read_only, rgb_picture
from core.jit import njit, prange
from core.shading.illumination import (Eye, eye_from_view, pack_ambient, pack_eye, pack_lights,
                                        pack_surfaces, to_uint8)
from core.scene.normals import WEIGHTINGS, face_normals, vertex_normals
from core.shading.registry import get_shader
from core.shading.wide import float32_is_exact_enough

__all__ = ["ShadeInput", "Eye", "eye_from_view", "prepare", "resolve"]


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
    context: RenderContext = field(default_factory=RenderContext, repr=False)
    computed: list[str] = field(default_factory=list)
    # Deferred lighting (prepare(..., lazy=True), the z-buffer's way): flat and Gouraud light
    # no face or vertex in the vertex step; the pixel step lights only those a visible pixel
    # uses (at 1M triangles on 500 x 500 pixels, a fifth of the front faces), and the clipper
    # asks ``before_clip(vertices)`` for the few it interpolates. ``lit`` flags what is done.
    lazy: bool = False
    lit: np.ndarray | None = None
    float32_safe: bool | None = None     # wide_shading's answer on the materials and lights
    normals: np.ndarray | None = None
    before_clip: Callable | None = None
    # The frame's RenderSettings (given to prepare: both steps read it), and, set by the
    # renderer before the pixel step for the textured shaders, (device points, 1/W) of the
    # clipped vertices.
    settings: object = None
    device: tuple | None = None
    # Flat shading: each face's planar polygon (-1 alone) and the polygons' centroids; for the
    # float32 passes, every face's lighting point and normal (the scene's, kept between frames).
    polygon: np.ndarray | None = None
    polygon_point: np.ndarray | None = None
    face_points: tuple | None = None
    face_bytes: np.ndarray | None = None     # (T, 3) uint8: face_rgb rounded, for the pixels


# --------------------------------------------------------------------------------------------
# Work that does not depend on the view, kept in the render context while the mesh (or the
# scene) lives: face and vertex normals per mesh; the concatenated arrays per scene. Cached
# arrays are read-only.


def _read_only(value):
    for a in value if isinstance(value, tuple) else (value,):
        if isinstance(a, np.ndarray):
            a.flags.writeable = False
    return value


def cached(context: RenderContext, owner, arrays: tuple, key: str,
           compute: Callable[[], object]):
    """``compute()`` once per ``owner``, again whenever one of ``arrays`` is replaced.

    The entry holds the arrays it was computed from (so their ids cannot be reused while it
    lives) and is dropped with the owner. Arrays changed in place are not noticed: a scene is
    data that the stages never change (core.scene).
    """
    cache = context.cache(owner)
    entry = cache.get("shading")
    if entry is None or len(entry[0]) != len(arrays) or any(
            a is not b for a, b in zip(entry[0], arrays)):
        entry = (arrays, {})
        cache["shading"] = entry
    if key not in entry[1]:
        entry[1][key] = _read_only(compute())
    return entry[1][key]


def _mesh_arrays(mesh) -> tuple:
    return (mesh.positions, mesh.triangles, mesh.normals)


def scene_arrays(meshes) -> tuple:
    return tuple(meshes) + tuple(a for m in meshes for a in _mesh_arrays(m))


def _mesh_face_normals(context, mesh) -> np.ndarray:
    return cached(context, mesh, _mesh_arrays(mesh), "face normals",
                  lambda: face_normals(mesh.positions, mesh.triangles)[0])


def _mesh_vertex_normals(context, mesh, weighting: str) -> np.ndarray:
    return cached(context, mesh, _mesh_arrays(mesh), f"vertex normals {weighting}",
                  lambda: vertex_normals(mesh, weighting))


def concatenated(context, scene, meshes, key: str, parts: Callable, width: int,
                 dtype=np.float64):
    """The per-mesh arrays ``parts(mesh)`` of all meshes, one after another (cached)."""
    def join():
        arrays = [parts(m) for m in meshes]
        return np.concatenate(arrays) if arrays else np.zeros((0, width), dtype)
    return cached(context, scene, scene_arrays(meshes), key, join)


def all_face_normals(s: "ShadeInput", scene, meshes) -> np.ndarray:
    """Every mesh's unit face normals, scene order ``(T, 3)``."""
    return concatenated(s.context, scene, meshes, "face normals",
                        lambda m: _mesh_face_normals(s.context, m), 3)


def _geometry(context, scene, meshes):
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
    return cached(context, scene, scene_arrays(meshes), "geometry", build)


# --------------------------------------------------------------------------------------------
# The vertex step of each mode


# Below this many faces or vertices one core is quicker: waking the second costs ~0.1 ms.
PARALLEL_ITEMS = 4_096
# Items a call in the float64 lighting kernels' parallel loops (core.jit.call_compiled): a call
# through a pointer costs about a microsecond, a face or a vertex about a tenth of one.
RUN = 1_024
# Below this many triangles the z-buffer lights every front face (flat) or its vertices
# (Gouraud) in the vertex step, as the painters do, instead of deferring to the visible ones:
# finding those is a pass over the covered pixels, which costs more than lighting them all.
# Measured (1k triangles, 500 x 500, 50k covered pixels): the pass 0.12-0.21 ms before the
# visible ones are lit; lighting all 434 front faces 0.10 ms (Gouraud: their 310 vertices, 0.08).
LIGHT_ALL_BELOW = 8_192
# Past that, the pass costs about as much per covered pixel as lighting one face or vertex
# does: the z-buffer defers only when the items outnumber a fifth of the picture's pixels.
# Measured on the bunny (69,451 faces, 36,218 vertices), the vertex and pixel steps with
# deferred lighting against all lit: at 1580 x 1080 Gouraud 7.03 against 5.68 ms, flat 5.83
# against 5.10; at 500 x 500 Gouraud 2.12 against 1.91, flat 2.43 against 2.69 (deferred
# wins: 0.28 faces a pixel); the bunny subdivided to 1.1M faces defers at any size here.
LAZY_ITEMS_PER_PIXEL = 0.2


def defers_lighting(shader, scene, pixels: int) -> bool:
    """Should the z-buffer light only the faces or vertices that some pixel shows (found by a
    pass over the covered pixels) rather than all of them in the vertex step?"""
    if shader.lit_items is None or scene.triangle_count < LIGHT_ALL_BELOW:
        return False
    return shader.lit_items(scene) > LAZY_ITEMS_PER_PIXEL * pixels


def all_vertex_normals(s: ShadeInput, scene, meshes, weighting) -> np.ndarray:
    """Every mesh's vertex normals (given, or averaged with ``weighting``), scene order."""
    if any(m.normals is None and len(m.triangles) for m in meshes):
        s.computed.append("vertex normals")
    return concatenated(s.context, scene, meshes, f"vertex normals {weighting}",
                        lambda m: _mesh_vertex_normals(s.context, m, weighting), 3)


# --------------------------------------------------------------------------------------------
# What the renderer calls


def geometry(scene, context: RenderContext = DEFAULT_CONTEXT) -> tuple[np.ndarray, np.ndarray]:
    """``(positions (V, 3), triangles (T, 3))``: all meshes over one vertex array, scene order
    (cached with the scene; the same arrays :func:`prepare` puts in its ShadeInput)."""
    positions, triangles, *_ = _geometry(context, scene, list(scene.meshes))
    return positions, triangles


def prepare(mode: str, scene, eye: Eye, weighting: str = "mean",
            faces: np.ndarray | None = None,
            context: RenderContext = DEFAULT_CONTEXT, lazy: bool = False,
            settings=None) -> ShadeInput:
    """The vertex step of ``mode`` for every mesh of ``scene`` seen from ``eye``.

    ``eye`` is :func:`eye_from_view`'s answer. ``weighting`` picks the vertex-normal average
    (:data:`core.scene.normals.WEIGHTINGS`; the notes' ``"mean"`` by default). ``faces``, when given,
    are the indices (into :func:`geometry`'s triangles) of the only faces that will be drawn,
    e.g. those back-face culling kept: flat lights only those faces and Gouraud only their
    vertices. ``lazy``: light nothing yet, :func:`resolve` lights only what is visible (the
    results are the same numbers; ``face_rgb`` and ``vertex_attrs`` are filled in as needed).
    ``settings``: the frame's :class:`~core.settings.RenderSettings`, which both steps read
    (the lighting's precision, the texture filter, the bump switch, depth shading's scalar).
    Raises ValueError for an unknown mode or weighting.
    """
    shader = get_shader(mode)
    if weighting not in WEIGHTINGS:
        raise ValueError(f"weighting must be one of {WEIGHTINGS}, not {weighting!r}")
    meshes = list(scene.meshes)
    positions, triangles, face_surface, vertex_surface, offset = _geometry(context, scene, meshes)
    s = ShadeInput(
        mode=mode, positions=positions, triangles=triangles,
        vertex_attrs=np.zeros((len(positions), 0)), face_rgb=None,
        face_surface=face_surface, vertex_surface=vertex_surface, vertex_offset=offset,
        surfaces=pack_surfaces([m.material for m in meshes], [not m.closed for m in meshes]),
        lights=pack_lights(scene.lights), ambient=pack_ambient(scene.ambient),
        eye=pack_eye(eye), halfway=scene.specular == "halfway",
        faces=(cached(context, scene, scene_arrays(meshes), "every face",
                      lambda: np.arange(len(triangles), dtype=np.int64)) if faces is None
               else np.ascontiguousarray(faces, dtype=np.int64)), context=context, lazy=lazy,
        settings=settings)
    shader.vertex(s, scene, meshes, weighting)
    return s


def resolve(shading: ShadeInput, vis, clipped_triangles: np.ndarray, clipped_attrs: np.ndarray,
            source: np.ndarray, background, out: np.ndarray | None = None,
            trusted: bool = False) -> np.ndarray:
    """The pixel step: a visibility buffer → ``(H, W, 3)`` uint8, row 0 at the top.

    ``vis`` has ``tri`` ``(H, W)`` (-1 empty, else an index into ``clipped_triangles``) and
    ``b1``, ``b2`` (the perspective-correct weights of vertices 1 and 2). ``clipped_attrs``
    are ``shading.vertex_attrs`` after clipping; ``source`` maps each clipped triangle to its
    row of ``shading.triangles``. Empty pixels get ``background`` (RGB in [0, 1]). Writes into
    ``out`` when given. ``trusted``: the arrays come straight from our own clipper and
    rasterizer, whose indices are in range by construction, so the range checks (five passes
    over arrays of up to 24 MB at a million triangles, ~2 ms a frame) are skipped.
    """
    tri = np.ascontiguousarray(vis.tri, dtype=np.int32)
    height, width = tri.shape
    if out is None:
        out = rgb_picture(height, width)
    background8 = to_uint8(background).reshape(3)
    # read-only whether cached or fresh: each pixel kernel compiles for one type (core/arrays)
    triangles = read_only(np.ascontiguousarray(clipped_triangles, dtype=np.int64).reshape(-1, 3))
    source = read_only(np.ascontiguousarray(source, dtype=np.int64).reshape(-1))
    attrs = np.ascontiguousarray(clipped_attrs, dtype=np.float64)
    shader = get_shader(shading.mode)
    k = shader.width
    if attrs.ndim != 2 or attrs.shape[1] != k:
        raise ValueError(f"{shading.mode} shading carries {k} attributes per vertex, "
                         f"the clipper gave an array of shape {attrs.shape}")
    # The kernels index without bounds checks: refuse indices that point nowhere.
    if not trusted:
        _check_indices(shading, tri, triangles, source, attrs)
    fill_bytes(out, background8)        # one memset; the pixel steps shade covered spans only
    shader.pixel(shading, vis, triangles, attrs, source, background8, out)
    return out


def _check_indices(shading: ShadeInput, tri, triangles, source, attrs) -> None:
    """Refuse a visibility buffer, clipped triangles or sources that index out of range."""
    if tri.size and tri.max() >= len(triangles):
        raise ValueError(f"the visibility buffer names triangle {tri.max()}, "
                         f"but only {len(triangles)} were clipped")
    if len(source) != len(triangles) or (source.size and not
                                         0 <= source.min() <= source.max() < len(shading.triangles)):
        raise ValueError("source must give, for each clipped triangle, its row of "
                         f"shading.triangles (0..{len(shading.triangles) - 1})")
    if attrs.shape[1] and triangles.size and not (0 <= triangles.min()
                                                  <= triangles.max() < len(attrs)):
        raise ValueError(f"clipped triangles index {len(attrs)} attribute rows out of range")


@njit(cache=True, parallel=True, nogil=True)
def _mark_shown(tri, span, shown):
    """``shown[t + 1] = 1`` for each triangle ``t`` that a covered pixel of a row's span shows
    (``shown[0]`` takes the empty pixels' -1). A store a pixel and no test: no branch to
    mispredict at each new triangle along a row. Threads may write the same 1 at once."""
    for row in prange(tri.shape[0]):
        for col in range(span[row, 0], span[row, 1] + 1):
            shown[np.uint64(tri[row, np.uint64(col)] + 1)] = 1     # unsigned: no wraparound


@njit(cache=True)
def _take_shown(shown, items, corners, limit, lit):
    """The items ``i < limit`` of the shown triangles (:func:`_mark_shown`) not lit yet, each
    once, in the triangles' order, now marked lit: their vertices (``corners`` 3, ``items``
    the triangles) or their source faces (``corners`` 1, ``items`` (T, 1))."""
    out = np.empty(lit.shape[0], np.int64)
    k = 0
    for t in range(items.shape[0]):
        if shown[t + 1]:
            for c in range(corners):
                i = items[t, c]
                if i < limit and lit[i] == 0:
                    lit[i] = 1
                    out[k] = i
                    k += 1
    return out[:k]


@njit(cache=True)
def _take_unlit(candidates, lit):
    """The candidates not lit yet, each once, now marked lit."""
    out = np.empty(candidates.shape[0], np.int64)
    k = 0
    for j in range(candidates.shape[0]):
        i = candidates[j]
        if lit[i] == 0:
            lit[i] = 1
            out[k] = i
            k += 1
    return out[:k]


def visible_items(vis, items: np.ndarray, corners: int, lit: np.ndarray) -> np.ndarray:
    """Indices (below ``len(lit)``) that a covered pixel of ``vis`` uses and that are not lit
    yet, marked lit now: vertices (``items`` the clipped triangles, ``corners`` 3) or faces
    (``items`` the source face of each clipped triangle as (T, 1), ``corners`` 1).

    Two passes: which triangles the pixels show, then their items (on the bunny's 72,702
    pixels at 500 x 500, 0.45 → 0.26 ms against a pass that looked each triangle's items up
    as it met it along a row, and then found the marked ones)."""
    shown = np.zeros(len(items) + 1, np.uint8)
    _mark_shown(np.ascontiguousarray(vis.tri, dtype=np.int32), covered_spans(vis), shown)
    return _take_shown(shown, items, corners, lit.shape[0], lit)


def unlit(candidates: np.ndarray, lit: np.ndarray) -> np.ndarray:
    """The ``candidates`` not lit yet (each once), marked lit now."""
    return _take_unlit(np.ascontiguousarray(candidates, dtype=np.int64), lit)


def wide_shading(s: ShadeInput) -> bool:
    """Light in float32 passes (core.shading.wide)? Unless the settings ask for the textbook
    float64 kernels, an exponent is not a whole number up to 2^16, or a light's terms would
    not fit in float32."""
    if getattr(s.settings, "shading_precision", "float32") != "float32":
        return False
    if s.float32_safe is None:          # asked up to three times a frame; ~35 µs to answer,
        s.float32_safe = s.context.remembered(      # so kept while the numbers stay the same
            "float32 holds", (s.surfaces.tobytes(), s.lights.tobytes(),
                              np.asarray(s.ambient, np.float64).tobytes()),
            lambda: (float32_is_exact_enough(s.surfaces)
                     and float32_holds_the_terms(s.surfaces, s.lights, s.ambient)))
    return s.float32_safe


# The float32 passes multiply each light's intensity by the material's terms in float32 (and
# the ambient's): a product past this would overflow to inf, and inf x 0 is NaN wherever the
# light does not reach. Such scenes (the stability suite's lights of 1e308) are lit in float64.
FLOAT32_TERMS = 1e30


def float32_holds_the_terms(surfaces: np.ndarray, lights: np.ndarray, ambient) -> bool:
    """Every intensity x k x O product of every light and surface, the ambient's, and every
    attenuation coefficient, finite and at most ``FLOAT32_TERMS`` in size."""
    ambient = np.asarray(ambient, np.float64).reshape(1, 3)
    intensity, attenuation = lights[:, None, 4:7], lights[:, 7:10]
    terms = [intensity * surfaces[None, :, 1:2] * surfaces[None, :, 4:7],
             intensity * surfaces[None, :, 2:3] * surfaces[None, :, 7:10],
             ambient * surfaces[:, 0:1] * surfaces[:, 4:7], attenuation]
    with np.errstate(over="ignore", invalid="ignore"):
        return all(bool(np.all(np.abs(t) <= FLOAT32_TERMS)) for t in terms)


def covered_spans(vis) -> np.ndarray:
    """``(H, 2)`` int32: per row, the first and last column a pixel step must look at (the
    rasterizer's spans when it kept them, else whole rows); the rest is background."""
    if getattr(vis, "spans_known", False) and vis.span is not None:   # any object with tri, b1, b2 will do
        return vis.span
    height, width = vis.tri.shape
    spans = np.empty((height, 2), np.int32)
    spans[:, 0] = 0
    spans[:, 1] = width - 1
    return spans
