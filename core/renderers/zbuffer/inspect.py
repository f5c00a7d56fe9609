"""The z-buffer's pixel record, for the pixel inspector: why one pixel has its colour.

:func:`inspect_pixel` draws the frame once with :func:`core.renderers.zbuffer.draw.draw`, keeping
what each stage produced (the clipped triangles and their attributes, the device points, the
visibility buffer, the flat colours), and then reads the pixel's story out of those arrays:
the visible mesh and triangle, the barycentric weights the z-buffer stored
(perspective-correct; screen-linear for the scan-line rasterizer) and the other kind
recomputed from the device points, the depth (canonical and world), the normal, and the
lighting model's terms (:func:`core.shading.models.dispatch.lighting_terms`) — at the face centroid (flat), at the
three vertices (Gouraud, then the interpolation), or at the pixel (Phong, textured: with
(u, v), the MIP level and the texels the filter read).

The record's ``color`` is computed from those numbers with the kernels' own per-pixel
functions and expressions (the same IEEE operations in the same order), so it is the pixel
the frame shows; the tests hold it against ``render`` on thousands of random pixels.

A capture is kept in the caller's :class:`~core.context.RenderContext` (one per scene, the
last view and settings asked), so inspecting many pixels of one frame draws it once.
Supersampled frames (a regular grid) are inspected sample by sample.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import SimpleNamespace
from typing import Callable, NamedTuple

import numpy as np

from core.arrays import rgb_picture
from core.camera.film import grid_side, sample_viewport, to_rgb8
from core.camera.view import eye_from_view, n_par_factors, n_per_factors, vrc_basis
from core.context import DEFAULT_CONTEXT, RenderContext
from core.pipeline import project
from core.renderers.zbuffer.draw import draw, draw_lines
from core.shading.illumination import quantize
from core.shading.models.dispatch import lighting_terms

KEY = "pixel inspector: z-buffer"


class Stages(NamedTuple):
    """The drawing a record follows: the z-buffer's own (:data:`ZBUFFER`), or a renderer that
    runs the z-buffer's pipeline with a stage of its own (the scan-line renderer's)."""

    draw: Callable
    draw_lines: Callable
    sample_viewport: Callable


ZBUFFER = Stages(draw, draw_lines, sample_viewport)


class _Recorder:
    """A Timer that keeps every stage's arrays (the last one of each name)."""

    keeps_arrays = True

    def __init__(self) -> None:
        self.arrays: dict = {}

    def lap(self, stage: str, **arrays) -> None:
        self.arrays.update(arrays)


@dataclass
class Capture:
    """One drawn frame and what its stages left behind (copies: the context reuses them)."""

    settings: object
    view: object
    side: int                       # samples per pixel along x and y (1: the pixel centre)
    width: int                      # of the drawn buffer (side x the frame's)
    height: int
    color: np.ndarray               # (h, w, 3) uint8 as drawn
    n: np.ndarray
    z_min: float
    vp: tuple
    mode: str                       # the shading mode that ran ("textured" for mapped Phong)
    lines: np.ndarray | None        # (h, w) bool: pixels the line pass drew over
    line_rgb: list
    background: list
    mesh_names: list = field(default_factory=list)
    arrays: dict = field(default_factory=dict)
    shade: object = None            # a ShadeInput: surfaces, lights, eye, normals, maps
    device_h: np.ndarray | None = None
    matrices: dict = field(default_factory=dict)
    n_inverse: np.ndarray | None = None
    vrc: tuple = ()                 # u, v, n of the view, and the eye point (or None)


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The record of image pixel ``(x, y)``: what the z-buffer's stages made of it (the
    registered inspector of ``zbuffer``)."""
    return pixel_record(scene, view, settings, x, y, context, ZBUFFER)


def buffers(scene, view, settings, context=None, names=()) -> dict:
    """The buffer views of this frame (render passes): depth, normal, triangle id, barycentrics,
    (u, v), MIP level, overdraw, as named in ``names``."""
    return buffer_views(scene, view, settings, context, ZBUFFER, names)


def pixel_record(scene, view, settings, x: int, y: int, context, stages: Stages) -> dict:
    """The record of image pixel ``(x, y)`` (x right, y down, row 0 at the top) of the frame
    ``stages`` draw."""
    cap = capture(scene, view, settings, context, stages)
    side = cap.side
    if side == 1:
        record = _sample(cap, x, y)
    else:
        samples = [_sample(cap, x * side + i, y * side + j)
                   for j in range(side) for i in range(side)]
        mean = np.mean([s["color"] for s in samples], axis=0)
        record = {"samples per pixel": side * side, "samples": samples,
                  "color": [int(c) for c in np.floor(mean + 0.5)]}
    return {"renderer": "zbuffer", "pixel": [int(x), int(y)], **record,
            "shading": cap.mode, "rasterizer": settings.rasterizer,
            "projection": settings.projection, "matrices": cap.matrices}


def capture(scene, view, settings, context, stages: Stages) -> Capture:
    """The frame of ``view`` drawn once with every stage's arrays kept (cached per scene)."""
    cache = (context or DEFAULT_CONTEXT).cache(scene)
    held = cache.get(KEY)
    try:
        if held is not None and held[0] == (view, settings):
            return held[1]
    except (TypeError, ValueError):       # a view of arrays: compare nothing, draw again
        pass
    cap = _capture(scene, view, settings, stages)
    cache[KEY] = ((view, settings), cap)
    return cap


def _capture(scene, view, settings, zbuffer: Stages) -> Capture:
    from core.texture.shaders import shading_for
    side = grid_side(settings.samples)
    if settings.samples > 1 and (settings.sample_pattern != "regular"
                                 or side * side != settings.samples):
        raise ValueError("the inspector follows a regular grid of samples (1, 4, 9, ...); "
                         f"{settings.samples} {settings.sample_pattern} samples are drawn "
                         "one pass at a time and are not kept")
    width, height = settings.size[0] * side, settings.size[1] * side
    drawn = settings.replace(samples=1, size=(width, height))
    context = RenderContext()                 # private: nothing else reuses its buffers
    frame = SimpleNamespace(color=rgb_picture(height, width), depth=None,
                            stats={"computed": [], "allocated": []}, message=None)
    recorder = _Recorder()
    zbuffer.draw(scene, view, drawn, frame, context, recorder)
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = zbuffer.sample_viewport(project.viewport(view.window, width, height,
                                                   settings.keep_aspect), drawn.pixel_offset)
    mode = shading_for(scene, settings.shading)
    cap = Capture(settings=settings, view=view, side=side, width=width, height=height,
                  color=frame.color.copy(), n=np.array(n), z_min=float(z_min), vp=vp, mode=mode,
                  lines=None, line_rgb=to_rgb8(scene.line_color).tolist(),
                  background=to_rgb8(scene.background).tolist(),
                  mesh_names=[getattr(m, "name", None) for m in scene.meshes])
    cap.matrices = _matrices(cap)
    cap.n_inverse = np.linalg.inv(cap.n)
    cap.vrc = (*vrc_basis(view), eye_from_view(view, settings.projection).point)
    if "tri" in recorder.arrays:
        vis = context.buffer("visibility", (width, height), lambda: None)
        covered = np.zeros((height, width), bool)
        for row in range(height):
            covered[row, vis.span[row, 0]:vis.span[row, 1] + 1] = True
        cap.arrays = {k: np.array(v) for k, v in recorder.arrays.items()
                      if isinstance(v, np.ndarray)}
        cap.arrays["tri"] = np.where(covered, cap.arrays["tri"], -1)
        cap.shade = _shade_input(scene, view, settings, mode)
        points, inv_w = cap.arrays["device_points"], cap.arrays["inv_w"]
        w = np.divide(1.0, inv_w, out=np.zeros_like(inv_w), where=inv_w > 0)
        cap.device_h = np.column_stack([points * w[:, None], w])
    line_meshes = [m for m in scene.meshes if settings.shading == "wireframe"
                   or not len(m.triangles)]
    if line_meshes:                           # the line pass, alone, onto a blank picture
        mask = np.zeros((height, width, 3), np.uint8)
        zbuffer.draw_lines(mask, line_meshes, settings.projection, n, z_min, vp, (1, 1, 1),
                           context, _Recorder(), {"computed": []})
        cap.lines = mask.any(axis=2)
    return cap


def _shade_input(scene, view, settings, mode):
    """The shading inputs of ``mode`` (surfaces, lights, eye, normals, texture maps), made
    lazily in a context of their own: nothing is lit, nothing the capture holds is touched."""
    from core.shading import stages
    eye = stages.shade.eye_from_view(view, settings.projection)
    s = stages.shade.prepare(mode, scene, eye, context=RenderContext(), lazy=True,
                             settings=settings)
    return s


# --------------------------------------------------------------------------------------------
# One sample (one pixel of the drawn buffer)


def _sample(cap: Capture, x: int, y: int) -> dict:
    if cap.lines is not None and cap.lines[y, x]:
        return {"layer": "line", "color": list(cap.line_rgb),
                "note": "drawn by the line pass (midpoint line, after the triangles)"}
    tri = cap.arrays.get("tri")
    if tri is None or tri[y, x] < 0:
        return {"layer": "background", "color": list(cap.background)}
    return _triangle_pixel(cap, x, y, int(tri[y, x]))


def _triangle_pixel(cap: Capture, x: int, y: int, t: int) -> dict:
    a, s = cap.arrays, cap.shade
    i0, i1, i2 = (int(i) for i in a["clipped_triangles"][t])
    w1, w2 = float(a["b1"][y, x]), float(a["b2"][y, x])
    w0 = 1.0 - w1 - w2
    face = int(a["source"][t])
    mesh = int(s.face_surface[face])
    first_face = int(np.searchsorted(s.face_surface, mesh))
    canonical = w0 * a["clipped_points"][i0] + w1 * a["clipped_points"][i1] \
        + w2 * a["clipped_points"][i2]
    world = (cap.n_inverse @ np.append(canonical, 1.0))[:3]
    corners = (i0, i1, i2)
    vertex_count = len(s.positions)
    record = {
        "layer": "triangle",
        "mesh": mesh, "mesh name": cap.mesh_names[mesh],
        "triangle": face - first_face, "scene triangle": face, "clipped triangle": t,
        "made by the clipper": any(i >= vertex_count for i in corners)
        or not np.array_equal(s.triangles[face], corners),
        "weights": {"used": [w0, w1, w2],
                    "kind": ("screen-linear" if cap.settings.rasterizer == "scanline"
                             else "perspective-correct"),
                    **_both_weights(cap, x, y, corners)},
        "depth": _depth(cap, y, x, world, canonical),
    }
    shaded = _breakdown(cap.mode)
    if shaded is None:
        record["note"] = f"no breakdown for {cap.mode} shading"
        record["color"] = cap.color[y, x].tolist()
        return record
    record.update(shaded(cap, x, y, corners, (w0, w1, w2), face, mesh))
    return record


def _both_weights(cap: Capture, x, y, corners) -> dict:
    """Screen-linear weights at the pixel centre from the device points, and the
    perspective-correct ones they give with 1/W (what the edge rasterizer stores)."""
    d, inv_w = cap.arrays["device_points"], cap.arrays["inv_w"]
    px, py = x + 0.5, cap.height - y - 0.5            # device y runs up
    (x0, y0), (x1, y1), (x2, y2) = (d[i, :2] for i in corners)
    area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
    if area == 0.0:
        return {}
    l1 = ((px - x0) * (y2 - y0) - (x2 - x0) * (py - y0)) / area
    l2 = ((x1 - x0) * (py - y0) - (px - x0) * (y1 - y0)) / area
    screen = [1.0 - l1 - l2, l1, l2]
    p = [screen[k] * inv_w[i] for k, i in enumerate(corners)]
    total = sum(p)
    return {"screen-linear": [float(v) for v in screen],
            "perspective-correct": [float(v / total) for v in p]}


def _depth(cap: Capture, y, x, world, canonical) -> dict:
    u, v, n, eye = cap.vrc
    rel = world - np.asarray(cap.view.vrp, dtype=np.float64)
    out = {"npc": float(cap.arrays["depth"][y, x]),
           "canonical point": [float(c) for c in canonical],
           "world point": [float(c) for c in world],
           "vrc": [float(rel @ u), float(rel @ v), float(rel @ n)]}
    if eye is not None:
        out["distance from the eye"] = float(np.linalg.norm(world - eye))
    return out


def _matrices(cap: Capture) -> dict:
    view, projection = cap.view, cap.settings.projection
    factors = (n_per_factors if projection == "perspective" else n_par_factors)(view)
    out = {name: (float(m) if m.ndim == 0 else m.tolist()) for name, m in factors.items()}
    if projection == "perspective":
        out["M"] = project.perspective_to_parallel(cap.z_min).tolist()
    out["viewport"] = list(cap.vp)
    out["M_vv3dv"] = project.m_vv3dv(*cap.vp).tolist()
    return out


def _terms(s, p, n, surface, surfaces=None) -> dict:
    return lighting_terms(p, n, surface, s.surfaces if surfaces is None else surfaces,
                          s.lights, s.ambient, s.eye, s.halfway)


def _bytes(rgb) -> list:
    return [int(quantize(c)) for c in rgb]


def _lit_where(mode: str) -> tuple[str | None, tuple[str, ...]]:
    """Where shading ``mode`` lights (its registry entry's ``lights``; the textured shader,
    which stands in for Phong, at pixels) and the varyings its shader carries."""
    from core.registry import get_shading, shading_names
    from core.shading.registry import get_shader, shader_names
    varyings = get_shader(mode).varyings if mode in shader_names() else ()
    if mode not in shading_names():
        return ("pixels" if mode == "textured" else None), varyings
    return get_shading(mode).lights, varyings


def _breakdown(mode: str) -> Callable | None:
    """The record of how ``mode`` made a pixel's colour, chosen by where it lights and what
    its shader carries (None: a mode this inspector cannot take apart)."""
    if mode == "textured":
        return _textured
    lights, varyings = _lit_where(mode)
    if lights == "faces":
        return _flat
    if lights == "vertices" and varyings == ("rgb",):
        return _gouraud
    if lights == "pixels" and varyings[:2] == ("normal", "position"):
        return _phong
    return None


def _flat(cap, x, y, corners, weights, face, mesh) -> dict:
    """Flat: the model once per polygon (FvDFH 16.2.3): at the face's centroid with its face
    normal, or, for faces that make one planar polygon, at the polygon's centroid with the
    normal of its lowest face (core.shading.flat.polygons)."""
    s = cap.shade
    polygon = getattr(s, "polygon", None)
    own = int(polygon[face]) if polygon is not None and polygon[face] >= 0 else -1
    if own < 0:
        p = s.positions[s.triangles[face]]
        point, where = [(p[0, c] + p[1, c] + p[2, c]) / 3.0 for c in range(3)], "the face centroid"
    else:
        point, where = list(s.polygon_point[own]), f"the centroid of polygon {own} (planar faces)"
    normal = s.normals[face if own < 0 else own]
    terms = _terms(s, point, normal, mesh)
    rgb = cap.arrays["face_rgb"][face]
    return {"normal": normal.tolist(), "evaluated at": where,
            "phong": terms, "face colour": rgb.tolist(), "color": _bytes(rgb)}


def _gouraud(cap, x, y, corners, weights, face, mesh) -> dict:
    """Gouraud: the model at each vertex, the colours interpolated (FvDFH 16.2.4)."""
    s, rgb = cap.shade, cap.arrays["clipped_attrs"]
    w0, w1, w2 = weights
    i0, i1, i2 = corners
    vertices = []
    for i in corners:
        entry = {"vertex": i, "colour": rgb[i].tolist()}
        if i < len(s.positions):
            entry["phong"] = _terms(s, s.positions[i], s.normals[i], int(s.vertex_surface[i]))
        else:
            entry["note"] = "made by the clipper: its colour interpolated along the cut edge"
        vertices.append(entry)
    colour = [w0 * rgb[i0, c] + w1 * rgb[i1, c] + w2 * rgb[i2, c] for c in range(3)]
    record = {"vertices": vertices, "interpolated colour": [float(c) for c in colour],
              "color": _bytes(colour)}
    if max(corners) < len(s.normals):       # shown only: Gouraud lights the vertices
        record["interpolated normal"] = [float(w0 * s.normals[i0, c] + w1 * s.normals[i1, c]
                                               + w2 * s.normals[i2, c]) for c in range(3)]
    return record


def _lerp(attrs, c, corners, weights):
    (i0, i1, i2), (w0, w1, w2) = corners, weights
    return w0 * attrs[i0, c] + w1 * attrs[i1, c] + w2 * attrs[i2, c]


def _phong(cap, x, y, corners, weights, face, mesh) -> dict:
    """Phong: normal and position interpolated, the normal renormalised, the model at the
    pixel (FvDFH 16.2.5) — the kernel's expressions, in its order."""
    from core.shading.illumination import unit3
    attrs = cap.arrays["clipped_attrs"]
    raw = [_lerp(attrs, c, corners, weights) for c in range(3)]
    p = [_lerp(attrs, 3 + c, corners, weights) for c in range(3)]
    nx, ny, nz, _ = unit3(*raw)
    terms = _terms(cap.shade, p, (nx, ny, nz), mesh)
    return {"normal": [nx, ny, nz], "interpolated normal": [float(c) for c in raw],
            "phong": terms, "color": _bytes(terms["clamped"])}


def _textured(cap, x, y, corners, weights, face, mesh) -> dict:
    from core.renderers.zbuffer.texture import textured_record
    return textured_record(cap, x, y, corners, weights, face, mesh)


# --------------------------------------------------------------------------------------------
# Buffer views: the same capture, every pixel at once


def buffer_views(scene, view, settings, context, stages: Stages, names) -> dict:
    """``{name: array}`` for the buffer views in ``names`` this frame has (see
    :data:`core.inspect.buffers.BUFFERS`), at the drawn size (``side`` x the frame's when
    supersampled). Empty pixels are NaN (-1 for the triangle id, 0 for overdraw)."""
    cap = capture(scene, view, settings, context, stages)
    a = cap.arrays
    if "tri" not in a:
        return {}                           # wireframe: no triangle was filled
    h, w = cap.height, cap.width
    tri = a["tri"]
    covered = tri >= 0
    t = tri[covered]
    w1, w2 = a["b1"][covered], a["b2"][covered]
    weights = np.stack([1.0 - w1 - w2, w1, w2], axis=1)
    corners = a["clipped_triangles"][t]
    source = a["source"][t]
    out = {}

    def image(values, fill, k=None):
        shape = (h, w) if k is None else (h, w, k)
        full = np.full(shape, fill, dtype=np.float64 if fill != -1 else np.int64)
        full[covered] = values
        return full

    if "depth" in names:
        out["depth"] = image(a["depth"][covered], np.nan)
    if "triangle" in names:
        out["triangle"] = image(source, -1)
    if "barycentrics" in names:
        out["barycentrics"] = image(weights, np.nan, 3)
    if "normal" in names:
        out["normal"] = image(_normals(cap, corners, weights, source), np.nan, 3)
    if ("uv" in names or "mip" in names) and cap.mode == "textured":
        attrs = a["clipped_attrs"]
        lerped = sum(weights[:, k, None] * attrs[corners[:, k], 6:8] for k in range(3))
        uv, lam = _texture_reads(cap, t, covered, lerped)
        out["uv"] = image(uv, np.nan, 2)
        out["mip"] = image(lam, np.nan)
    if "overdraw" in names:
        from core.pipeline.raster import count_fragments
        out["overdraw"] = count_fragments(a["device_points"], a["inv_w"],
                                          a["clipped_triangles"], w, h).astype(np.int64)
    return out


def _normals(cap, corners, weights, source) -> np.ndarray:
    """The normal shading used: carried by its shader and interpolated (Phong, textured), the
    face's (a mode lit at faces: flat), or the vertex normals interpolated at the world point
    (Gouraud, which keeps colours instead, and a mode that lights nothing)."""
    a, s = cap.arrays, cap.shade
    lights, varyings = _lit_where(cap.mode)
    if varyings[:1] == ("normal",):             # carried through the clipper
        attrs = a["clipped_attrs"]
        n = sum(weights[:, k, None] * attrs[corners[:, k], 0:3] for k in range(3))
    elif lights == "faces":
        n = s.normals[source]
    else:
        points = a["clipped_points"]
        canonical = sum(weights[:, k, None] * points[corners[:, k]] for k in range(3))
        world = canonical @ cap.n_inverse[:3, :3].T + cap.n_inverse[:3, 3]
        tri = s.triangles[source]
        lam = _barycentric(world, s.positions[tri[:, 0]], s.positions[tri[:, 1]],
                           s.positions[tri[:, 2]])
        n = sum(lam[:, k, None] * s.normals[tri[:, k]] for k in range(3))
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def _barycentric(p, a, b, c) -> np.ndarray:
    v0, v1, v2 = b - a, c - a, p - a
    d00, d01, d11 = (v0 * v0).sum(1), (v0 * v1).sum(1), (v1 * v1).sum(1)
    d20, d21 = (v2 * v0).sum(1), (v2 * v1).sum(1)
    den = d00 * d11 - d01 * d01
    den = np.where(den == 0.0, 1.0, den)
    l1 = (d11 * d20 - d01 * d21) / den
    l2 = (d00 * d21 - d01 * d20) / den
    return np.stack([1.0 - l1 - l2, l1, l2], axis=1)


def _texture_reads(cap, t, covered, lerped) -> tuple[np.ndarray, np.ndarray]:
    """Where the textures are read: ``(u, v)`` from the triangle's plane constants at the
    pixel centre (the interpolated ``lerped`` where they are degenerate, as the kernel does),
    and the colour map's MIP level (λ clamped to its levels, as trilinear does; NaN where the
    material has no colour map)."""
    from core.texture.surface import COLOR, UV
    from core.texture.tutorial import plane_constants
    s, attrs = cap.shade, cap.arrays["clipped_attrs"]
    texels, levels, textures, maps = s.texture_maps
    unique, slot = np.unique(t, return_inverse=True)
    constants = np.zeros((len(unique), 3, 3))
    first = cap.arrays["clipped_triangles"][unique]
    for k, (i0, i1, i2) in enumerate(first):
        plane_constants(cap.device_h, i0, i1, i2, attrs[i0, UV], attrs[i0, UV + 1],
                        attrs[i1, UV], attrs[i1, UV + 1], attrs[i2, UV], attrs[i2, UV + 1],
                        float(cap.height), constants, k)
    rows, cols = np.nonzero(covered)
    c = constants[slot]
    a_ = c[:, 0, 0] + c[:, 1, 0] * cols + c[:, 2, 0] * rows
    b_ = c[:, 0, 1] + c[:, 1, 1] * cols + c[:, 2, 1] * rows
    cc = c[:, 0, 2] + c[:, 1, 2] * cols + c[:, 2, 2] * rows
    with np.errstate(divide="ignore", invalid="ignore"):
        u, v = a_ / cc, b_ / cc
        dudx, dvdx = (c[:, 1, 0] - u * c[:, 1, 2]) / cc, (c[:, 1, 1] - v * c[:, 1, 2]) / cc
        dudy, dvdy = (c[:, 2, 0] - u * c[:, 2, 2]) / cc, (c[:, 2, 1] - v * c[:, 2, 2]) / cc
        mesh = s.face_surface[cap.arrays["source"][t]]
        k = maps[mesh, COLOR].astype(np.int64)
        base = textures[np.maximum(k, 0), 0]
        count = textures[np.maximum(k, 0), 1]
        tw, th = levels[base, 1], levels[base, 2]
        rho = np.maximum(np.hypot(dudx * tw, dvdx * th), np.hypot(dudy * tw, dvdy * th))
        lam = np.log2(rho)
    finite = np.isfinite(u) & np.isfinite(v)
    uv = np.where(finite[:, None], np.stack([u, v], axis=1), lerped)
    lam = np.where(finite, lam, -np.inf)          # no derivatives: level 0
    lam = np.clip(np.nan_to_num(lam, nan=0.0, posinf=1e9, neginf=0.0), 0.0, count - 1)
    return uv, np.where(k >= 0, lam, np.nan)
