"""Depth cueing (FvDFH 16.1.3; the notes' light-source-independent model: "reduce clarity of
a pixel as a function of depth"), applied to any renderer's frame.

Each visible point's colour I is blended towards the depth-cue colour I_dc::

    I' = s_o I + (1 - s_o) I_dc,
    s_o = s_b + (z_o - z_b)(s_f - s_b) / (z_f - z_b)   between the cue planes,
    s_o = s_f in front of z_f,  s_o = s_b behind z_b,

where z_o is the point's depth along the view-plane normal from the VRP (as the view's F and
B are measured: larger is nearer the viewer), z_f and z_b the front and back cue planes.
A scene's ``[depth_cue]`` table gives ``front``, ``back``, ``s_front``, ``s_back`` and
``color``; they default to the view's F and B, 1, 0 and the background, so that a point on the
back clipping plane fades fully into the background.

Where the depth comes from: the z-buffer and the painters leave ``frame.depth`` (device depth;
the device transformation is inverted at the pixel centre to get the world point); the ray
tracer and ray caster's primary hits give it directly (their registry entries'
``ray_depth``); wireframe lines are drawn again with each pixel's colour cued at its own
depth along the line (the same pixels as the midpoint line: perspective-correct depth between
the clipped endpoints).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.registry import get_renderer
from core.scene.formats.keys import register_scene_keys
from core.shading.illumination import to_uint8

KEYS = ("front", "back", "s_front", "s_back", "color")


@dataclass(frozen=True)
class DepthCue:
    """A scene's depth-cue parameters; ``None`` takes the view's F, B or the background."""

    front: float | None = None
    back: float | None = None
    s_front: float = 1.0
    s_back: float = 0.0
    color: tuple[float, float, float] | None = None

    def resolved(self, view, background) -> tuple[float, float, float, float, np.ndarray]:
        """``(z_f, z_b, s_f, s_b, I_dc)`` for ``view``."""
        z_f = view.front if self.front is None else self.front
        z_b = view.back if self.back is None else self.back
        color = background if self.color is None else self.color
        return z_f, z_b, self.s_front, self.s_back, np.asarray(color, dtype=np.float64)


def scale_factor(z, z_f, z_b, s_f, s_b) -> np.ndarray:
    """s_o at depths ``z`` (FvDFH eq. 16.11 with its two clamps)."""
    z = np.asarray(z, dtype=np.float64)
    if z_f == z_b:
        return np.where(z >= z_f, s_f, s_b)
    s = s_b + (z - z_b) * (s_f - s_b) / (z_f - z_b)
    return np.where(z >= z_f, s_f, np.where(z <= z_b, s_b, s))


def cue(color, z, view, background, params: DepthCue | None = None) -> np.ndarray:
    """``I'`` for colours ``color`` (..., 3) in [0, 1] at depths ``z`` (...)."""
    z_f, z_b, s_f, s_b, i_dc = (params or DepthCue()).resolved(view, background)
    s = scale_factor(z, z_f, z_b, s_f, s_b)[..., None]
    return s * np.asarray(color, dtype=np.float64) + (1.0 - s) * i_dc


def view_depth(points, view) -> np.ndarray:
    """Depth along the unit VPN from the VRP of world ``points`` (..., 3)."""
    n = np.asarray(view.vpn, dtype=np.float64)
    n = n / np.linalg.norm(n)
    return (np.asarray(points) - np.asarray(view.vrp, dtype=np.float64)) @ n


# ------------------------------------------------------------------------------ the frames

def depth_cued(draw):
    """``draw`` (a renderer) followed by depth cueing of what it drew (``settings.depth_cue``)."""
    def draw_cued(scene, view, settings, frame, context, timer):
        draw(scene, view, settings, frame, context, timer)
        if frame.message is None:
            apply(scene, view, settings, frame, context)
            timer.lap("depth cue")
    return draw_cued


def apply(scene, view, settings, frame, context) -> None:
    """Cue ``frame.color`` in place: the surfaces, then the lines drawn again cued."""
    params = getattr(scene, "depth_cue", None) or DepthCue()
    by_rays = get_renderer(settings.renderer).ray_depth     # no depth buffer: cast the rays
    height, width = frame.color.shape[:2]
    z_f, z_b, s_f, s_b, i_dc = params.resolved(view, scene.background)
    s = None
    if frame.depth is not None:
        z = _depth_from_device(frame.depth, view, settings, context, width, height)
        s = np.where(np.isfinite(z), scale_factor(z, z_f, z_b, s_f, s_b), np.nan)
    elif by_rays and settings.shading != "wireframe":
        z = _depth_from_rays(scene, view, settings, width, height)      # (samples, H, W)
        hit = np.isfinite(z)
        s_all = np.where(hit, scale_factor(z, z_f, z_b, s_f, s_b), 0.0)
        s = np.where(hit.any(0), s_all.sum(0) / np.maximum(hit.sum(0), 1), np.nan)
    if s is not None:
        covered = np.isfinite(s)
        lit = frame.color[covered].astype(np.float64) / 255.0
        so = s[covered][:, None]
        frame.color[covered] = to_uint8(so * lit + (1.0 - so) * i_dc)
    frame.stats.setdefault("computed", []).append("depth cue")
    line_meshes = [m for m in scene.meshes
                   if settings.shading == "wireframe" or not len(m.triangles)]
    if line_meshes and not by_rays:             # the ray casters draw no line edges
        draw_cued_lines(frame.color, line_meshes, view, settings, context, scene, params)


def _viewport(view, settings, width, height):
    """The viewport moved so that the frame's sample offset lands on the pixel centre (as the
    z-buffer's ``core.camera.film.sample_viewport`` does)."""
    from core.pipeline import project
    vp = project.viewport(view.window, width, height, settings.keep_aspect)
    dx, dy = 0.5 - settings.pixel_offset[0], settings.pixel_offset[1] - 0.5
    return vp[0] + dx, vp[1] + dx, vp[2] + dy, vp[3] + dy


def _depth_from_device(depth, view, settings, context, width, height) -> np.ndarray:
    """``(H, W)`` view depth of the surface at each pixel centre (NaN where none): the pixel
    centre and its device depth carried back through the inverse of M_vv3dv · M · N."""
    from core.pipeline import project
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = _viewport(view, settings, width, height)
    inverse = np.linalg.inv(project.triangle_matrix(settings.projection, z_min, vp) @ n)
    covered = np.isfinite(depth)
    rows, cols = np.nonzero(covered)
    device = np.stack([cols + 0.5, (height - 1 - rows) + 0.5, depth[covered],
                       np.ones(len(rows))], axis=1)
    world = device @ inverse.T
    z = np.full(depth.shape, np.nan)
    z[covered] = view_depth(world[:, :3] / world[:, 3:4], view)
    return z


def _depth_from_rays(scene, view, settings, width, height) -> np.ndarray:
    """``(samples, H, W)`` view depth of each primary ray's first hit (NaN: none)."""
    from core.camera.film import sample_offsets
    from core.raytrace import whitted
    from core.renderers.raytrace.draw import TraceOptions, prepare, primary
    offsets = (sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
               if settings.samples > 1 else np.array([settings.pixel_offset]))
    setup = prepare(scene, view, settings.projection, (width, height), TraceOptions(), offsets,
                    settings.keep_aspect)
    o, d, lo, hi = primary(setup, 0, height, 0, width)
    live = np.isfinite(lo)
    kind = np.full(int(live.sum()), whitted.NOTHING, np.int64)
    index, t = np.empty(len(kind), np.int64), np.full(len(kind), np.inf)
    whitted.visible_many(setup.packing.packed, np.ascontiguousarray(o[live]),
                         np.ascontiguousarray(d[live]), np.ascontiguousarray(lo[live]),
                         np.ascontiguousarray(hi[live]), kind, index, t)
    z = np.full(len(o), np.nan)
    hit = kind != whitted.NOTHING
    z_live = np.full(len(kind), np.nan)
    z_live[hit] = view_depth(o[live][hit] + t[hit, None] * d[live][hit], view)
    z[live] = z_live
    return z.reshape(len(offsets), height, width)


def draw_cued_lines(color, meshes, view, settings, context, scene, params) -> None:
    """The line edges again, each pixel cued at its depth along its segment."""
    from core.pipeline import clip, project
    from core.pipeline.raster_lines import line_pixels
    from core.transforms import apply as transform
    height, width = color.shape[:2]
    n, z_min = context.normalizing_transform(view, settings.projection)
    vp = _viewport(view, settings, width, height)
    n_inverse = np.linalg.inv(n)
    line8 = np.asarray(scene.line_color, dtype=np.float64)
    for mesh in meshes:
        edges = mesh.all_edges()
        if len(edges) == 0:
            continue
        points = transform(n, mesh.positions)[:, :3]
        q0, q1 = clip.clip_lines(points[edges[:, 0]], points[edges[:, 1]], settings.projection,
                                 z_min)
        if len(q0) == 0:
            continue
        d0 = project.project_lines(q0, settings.projection, vp)
        d1 = project.project_lines(q1, settings.projection, vp)
        x0, y0 = _pixel(d0, width, height)
        x1, y1 = _pixel(d1, width, height)
        x, y = line_pixels(x0, y0, x1, y1)
        counts = np.maximum(np.abs(x1 - x0), np.abs(y1 - y0)) + 1
        k = np.repeat(np.arange(len(x0)), counts)
        # t along the segment on the screen, then the world parameter (1/W is screen-linear)
        a, b = d0[k, :2], d1[k, :2]
        ab = b - a
        length2 = (ab * ab).sum(1)
        centre = np.stack([x + 0.5, y + 0.5], 1)
        t = np.clip(np.where(length2 > 0, ((centre - a) * ab).sum(1) / np.where(
            length2 > 0, length2, 1.0), 0.0), 0.0, 1.0)
        if settings.projection == "perspective":
            w0, w1 = -q0[k, 2], -q1[k, 2]          # M_per (d = -1) divides by -z
            s = t * w0 / ((1.0 - t) * w1 + t * w0)
        else:
            s = t
        z0 = view_depth(transform(n_inverse, q0)[:, :3], view)
        z1 = view_depth(transform(n_inverse, q1)[:, :3], view)
        z = (1.0 - s) * z0[k] + s * z1[k]
        color[height - 1 - y, x] = to_uint8(cue(np.broadcast_to(line8, (len(z), 3)), z, view,
                                                scene.background, params))


def _pixel(p, width, height):
    col = np.clip(np.floor(p[:, 0]), 0, width - 1).astype(np.int64)
    row = np.clip(np.floor(p[:, 1]), 0, height - 1).astype(np.int64)
    return col, row


# --------------------------------------------------------------------------- the scene key

def read_table(reader, value, path) -> DepthCue:
    """The ``[depth_cue]`` table of a scene file (``reader``: the scene reader's checks)."""
    table = reader.table(value, path, KEYS)
    get = lambda key, read: read(table[key], path + (key,)) if key in table else None  # noqa
    number = lambda v, p: reader.number(v, p)                                         # noqa
    unit = lambda v, p: reader.number(v, p, 0.0, 1.0)                                 # noqa
    front, back = get("front", number), get("back", number)
    if front is not None and back is not None and back >= front:
        raise reader.fail(path + ("back",), f"the back cue plane ({back}) must lie behind the "
                                            f"front one ({front}): back < front")
    s_front = get("s_front", unit)
    s_back = get("s_back", unit)
    color = get("color", lambda v, p: reader.vector(v, p, 3, 0.0, 1.0))
    return DepthCue(front, back, 1.0 if s_front is None else s_front,
                    0.0 if s_back is None else s_back,
                    None if color is None else tuple(float(c) for c in color))


def read_scene_keys(reader, doc: dict, scene) -> None:
    if "depth_cue" in doc:
        scene.depth_cue = read_table(reader, doc["depth_cue"], ("depth_cue",))


register_scene_keys("depth cue", ("depth_cue",), read_scene_keys)
