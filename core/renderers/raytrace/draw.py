"""The ray tracer's front door: a scene, a view and settings → a picture, whole or by tiles.

- :func:`prepare` packs the scene (BVH, primitives, materials; kept while the scene lives), the
  lights, the eye and the options once per frame: a :class:`Setup`.
- :func:`trace_tile` traces the image rows ``[row0, row1)`` and columns ``[col0, col1)`` at every
  sample of the pixel and returns their box-filtered colour — what a progressive driver (the
  window) calls tile by tile, coarse first (:func:`tiles` gives an order).
- :func:`render_image` traces the whole frame; :func:`draw` is the renderer registered
  as ``"raytrace"`` (``fn(scene, view, settings, frame, context)``), filling ``frame``.

Options (:class:`TraceOptions`, read from :class:`core.settings.RenderSettings` where it has
them): ``max_depth`` (7, the notes), ``adaptive_epsilon`` (ε of the notes' adaptive depth
control), ``shadows`` (:data:`core.raytrace.whitted.SHADOW_MODES`, default ``"transmit"``),
``fresnel`` (Schlick, off), and ``medium`` (the index of the space between objects: air).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from core.camera.rays import camera_rays, primary_rays
from core.camera.view import View, check
from core.raytrace import adaptive, geometry, whitted
from core.raytrace.optics import AIR, index_of_refraction
from core.renderers.raytrace.options import (MAX_DEPTH_LIMIT,  # noqa: F401  (its limit)
                                             RaytraceOptions)
from core.camera.film import sample_offsets
from core.shading.illumination import (eye_from_view, pack_ambient, pack_eye, pack_lights,
                                       to_uint8)
from core.work import report



@dataclass(frozen=True)
class TraceOptions(RaytraceOptions):
    """The user's ray-tracing options (checked by :class:`RaytraceOptions`) and what else the
    kernel takes: the medium the eye is in and the frame's texture filter and bump switch."""

    medium: float = AIR
    texture_filter: str = "trilinear"      # the z-buffer's filters (core.texture.sample)
    bump: bool = True

    @property
    def fresnel_code(self) -> int:
        if not self.fresnel:
            return whitted.FRESNEL_OFF
        return (whitted.FRESNEL_EXACT if self.fresnel_form == "exact"
                else whitted.FRESNEL_SCHLICK)

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "medium", index_of_refraction(self.medium, "medium"))

    @classmethod
    def from_settings(cls, settings) -> "TraceOptions":
        own = settings.options_of("raytrace")
        return cls(**{name: getattr(own, name) for name in RaytraceOptions.__dataclass_fields__},
                   texture_filter=settings.texture_filter, bump=settings.bump)


@dataclass
class Setup:
    """One frame's inputs, ready for the kernel."""

    packing: geometry.Packing
    view: View
    projection: str
    width: int
    height: int
    offsets: np.ndarray          # (S, 2) sample offsets in the pixel, from its top-left corner
    lights: np.ndarray
    ambient: np.ndarray
    eye: np.ndarray
    halfway: bool
    background: np.ndarray
    options: TraceOptions
    counts: np.ndarray           # (7,) rays of each kind so far (whitted.COUNTERS)
    keep_aspect: bool = False    # letterbox the window (else stretch it: the course's mapping)
    not_drawn: tuple = ()        # what the scene has that the tracer leaves out, in words
    adaptive: tuple | None = None  # (levels, threshold, min_levels): adaptive.py


def prepare(scene, view: View, projection: str, size: tuple[int, int],
            options: TraceOptions = TraceOptions(), offsets=None,
            keep_aspect: bool = False) -> Setup:
    """Everything one frame needs. Raises ViewError for an invalid view and ValueError for a
    material or primitive the tracer cannot use."""
    check(view, projection)
    width, height = size
    packing = geometry.pack(scene)
    return Setup(packing=packing, view=view, projection=projection, width=int(width),
                 height=int(height),
                 offsets=(np.array([[0.5, 0.5]]) if offsets is None
                          else np.asarray(offsets, dtype=np.float64).reshape(-1, 2)),
                 lights=pack_lights(scene.lights), ambient=pack_ambient(scene.ambient),
                 eye=pack_eye(eye_from_view(view, projection)),
                 halfway=scene.specular == "halfway",
                 background=np.asarray(scene.background, dtype=np.float64).reshape(3),
                 options=options, counts=np.zeros(len(whitted.COUNTERS), dtype=np.int64),
                 keep_aspect=bool(keep_aspect), not_drawn=not_drawn(scene))


def not_drawn(scene) -> tuple:
    """What of ``scene`` the tracer cannot draw, one sentence each (shown with the frame's
    stats and in the window's panel, never silently dropped)."""
    from core.renderers import line_edges_note
    notes = [note for note in (line_edges_note(scene),) if note]
    from core.texture.material import maps_of
    demo = [m.name for m in scene.meshes if getattr(maps_of(m.material), "demo", None)]
    if demo:
        notes.append(f"the bump demo's material ({', '.join(demo)}): drawn by the z-buffer only")
    mapped = sorted({m.name for m in scene.meshes if m.tessellates is not None
                     and maps_of(m.material) is not None})
    if mapped:
        notes.append(f"texture maps on analytic primitives ({', '.join(mapped)}): the traced "
                     f"sphere or plane has no (u, v)")
    return tuple(notes)


def nothing_to_trace(scene) -> str:
    """Why the tracer has nothing to draw in a scene with no triangle, sphere or plane: what
    the scene holds instead, and which renderer draws that."""
    from core.renderers import held_instead
    held = held_instead(scene)
    return (f"{scene.name}: nothing to ray trace: no triangles, spheres or planes"
            + (f"; {'; '.join(held)}" if held else ""))


def trace_rays(setup: Setup, origins, directions, t_min, t_max,
               differentials=None) -> np.ndarray:
    """Colours ``(N, 3)`` (unclamped) of primary rays; adds their ray counts to ``setup``.

    ``differentials`` ``(N, 12)``: ∂O/∂x, ∂D/∂x, ∂O/∂y, ∂D/∂y per pixel of each ray, for the
    texture footprint (None: a point sample, the finest level)."""
    from core.texture.sample import FILTERS
    o = setup.options
    n = len(origins)
    textured = setup.packing.textured
    if differentials is None:
        differentials = np.zeros((n if textured else 0, 12))
    raw = np.empty((n, 3))
    counts = np.zeros(((n + whitted.CHUNK - 1) // whitted.CHUNK, len(whitted.COUNTERS)),
                      dtype=np.int64)
    offset = 1e-9 * setup.packing.scale
    args = (setup.packing.packed, np.ascontiguousarray(origins), np.ascontiguousarray(directions),
            np.ascontiguousarray(t_min), np.ascontiguousarray(t_max), setup.eye, setup.lights,
            setup.ambient, setup.halfway, setup.background,
            whitted.SHADOW_MODES.index(o.shadows), o.max_depth, float(o.adaptive_epsilon),
            o.fresnel_code, o.medium, offset, raw, counts, setup.packing.texturing, textured,
            FILTERS[o.texture_filter], bool(o.bump),
            np.ascontiguousarray(differentials, dtype=np.float64),
            np.array(o.secondary_attenuation, dtype=np.float64),
            whitted.colour_at(setup.packing.packed, setup.lights, setup.ambient, setup.halfway,
                              setup.packing.texturing, textured, FILTERS[o.texture_filter],
                              bool(o.bump)))
    whitted.trace_many(*args, whitted.trace_at(*args))
    setup.counts += counts.sum(axis=0)
    return raw


def primary(setup: Setup, row0: int, row1: int, col0: int, col1: int, offsets=None):
    """Primary rays of a tile, sample-major then row-major, and their [F, B] intervals
    (``offsets``: the samples in each pixel, default the setup's)."""
    return camera_rays(setup.view, setup.projection, setup.width, setup.height,
                       setup.offsets if offsets is None else offsets, setup.keep_aspect,
                       (row0, row1), (col0, col1))


def differentials(setup: Setup, row0: int, row1: int, col0: int, col1: int,
                  offsets=None) -> np.ndarray:
    """``(N, 12)`` the primary rays' differentials per pixel, by the rays one pixel right
    and one pixel down (in the order of :func:`primary`)."""
    offsets = setup.offsets if offsets is None else offsets

    def rays(shift):
        o, d, _ = primary_rays(setup.view, setup.projection, setup.width, setup.height,
                               offsets + shift, setup.keep_aspect, (row0, row1), (col0, col1))
        return o, d
    o, d = rays(np.zeros(2))
    ox, dx = rays(np.array([1.0, 0.0]))
    oy, dy = rays(np.array([0.0, 1.0]))
    return np.concatenate([ox - o, dx - d, oy - o, dy - d], axis=1)


def trace_tile(setup: Setup, row0: int, row1: int, col0: int, col1: int) -> np.ndarray:
    """The box-filtered, unclamped colour ``(row1 − row0, col1 − col0, 3)`` of a tile."""
    origins, directions, t_min, t_max = primary(setup, row0, row1, col0, col1)
    diffs = (differentials(setup, row0, row1, col0, col1) if setup.packing.textured else None)
    raw = trace_rays(setup, origins, directions, t_min, t_max, diffs)
    return raw.reshape(len(setup.offsets), row1 - row0, col1 - col0, 3).mean(axis=0)


def render_filtered(setup: Setup, name: str, radius: float) -> np.ndarray:
    """The whole frame as :func:`render_raw`, each pixel reconstructed from the samples around
    it with the pixel filter ``name`` of ``radius`` (core.camera.filters), not their mean."""
    from core.camera.filters import reconstruct
    rows = band_rows(setup.width, len(setup.offsets))
    bands = []
    for r in range(0, setup.height, rows):
        end = min(r + rows, setup.height)
        origins, directions, t_min, t_max = primary(setup, r, end, 0, setup.width)
        diffs = (differentials(setup, r, end, 0, setup.width) if setup.packing.textured
                 else None)
        raw = trace_rays(setup, origins, directions, t_min, t_max, diffs)
        bands.append(raw.reshape(len(setup.offsets), end - r, setup.width, 3))
        report("ray tracing", end, setup.height, "row")
    samples = np.concatenate(bands, axis=1)
    # unclamped, as the box's mean is; on 0-255 for the filter, back to the tracer's 0-1
    return reconstruct(samples * 255.0, setup.offsets, name, radius) / 255.0


def tiles(width: int, height: int, tile: int = 32) -> list[tuple[int, int, int, int]]:
    """``(row0, row1, col0, col1)`` tiles covering the image, centre first (what the viewer
    looks at), spiralling out by distance — the order a progressive display fills in."""
    boxes = [(r, min(r + tile, height), c, min(c + tile, width))
             for r in range(0, height, tile) for c in range(0, width, tile)]
    cy, cx = height / 2, width / 2
    return sorted(boxes, key=lambda b: ((b[0] + b[1]) / 2 - cy) ** 2 + ((b[2] + b[3]) / 2 - cx) ** 2)


def render_raw(setup: Setup) -> np.ndarray:
    """The whole frame, ``(H, W, 3)`` unclamped float colours, row 0 at the top."""
    if setup.adaptive is not None:
        levels, threshold, min_levels = setup.adaptive
        return adaptive.render_adaptive(lambda points: trace_points(setup, points),
                                        setup.width, setup.height, levels, threshold,
                                        min(levels, min_levels))
    rows = band_rows(setup.width, len(setup.offsets))
    bands = []
    for r in range(0, setup.height, rows):
        bands.append(trace_tile(setup, r, min(r + rows, setup.height), 0, setup.width))
        report("ray tracing", min(r + rows, setup.height), setup.height, "row")
    return np.concatenate(bands)


RAYS_PER_BAND = 1 << 20


def band_rows(width: int, samples: int) -> int:
    """Rows a band of the whole frame holds: about RAYS_PER_BAND primary rays. All of
    ``render scenes/whitted.toml --samples 64`` in one band held 1.7 GB of rays and colours,
    fresh pages the system had to zero (4.3-5.5 s of its CPU time, 11.6-14.9 s wall); bands of
    2^20 rays: 0.3 GB, 0.4-0.6 s, 9.9-10.1 s (2^18 cost more user time, 2^21-2^22 no less).
    A pixel's colour depends on its own rays only, so the bands give the same picture."""
    return max(1, RAYS_PER_BAND // max(1, width * samples))


def trace_points(setup: Setup, points: np.ndarray) -> np.ndarray:
    """Colours ``(N, 3)`` of the primary rays through ``points`` (pixels from the picture's
    top-left corner, x right, y down)."""
    origins, directions, t_min, t_max = primary(setup, 0, 1, 0, 1, points)
    diffs = differentials(setup, 0, 1, 0, 1, points) if setup.packing.textured else None
    return trace_rays(setup, origins, directions, t_min, t_max, diffs)


def stats_of(setup: Setup, seconds: float) -> dict:
    b = setup.packing.build
    rays = {name: int(c) for name, c in zip(whitted.COUNTERS, setup.counts)}
    return {"rays": rays, "bvh": {"triangles": b.triangles, "nodes": b.nodes, "depth": b.depth,
                                  "build ms": b.seconds * 1e3, "bytes": b.bytes},
            "trace ms": seconds * 1e3, "renderer": "raytrace",
            "not drawn": list(setup.not_drawn)}


def render_image(scene, view: View, projection: str, size: tuple[int, int],
                 options: TraceOptions = TraceOptions(), samples: int = 1,
                 pattern: str = "regular", seed: int = 0, keep_aspect: bool = False,
                 threshold: float = 0.1, min_levels: int = adaptive.MIN_LEVELS
                 ) -> tuple[np.ndarray, np.ndarray, dict]:
    """``(uint8 image (H, W, 3), raw float image, stats)`` of ``view`` of ``scene``
    (``pattern = "adaptive"``: up to ``samples`` a pixel where corners differ by more than
    ``threshold``)."""
    offsets = sample_offsets(samples, pattern, seed)
    setup = prepare(scene, view, projection, size, options, offsets, keep_aspect)
    if pattern == "adaptive":
        setup.adaptive = (adaptive.levels_for(samples), threshold, min_levels)
    start = time.perf_counter()
    raw = render_raw(setup)
    return to_uint8(raw), raw, stats_of(setup, time.perf_counter() - start)


def draw(scene, view: View, settings, frame, context=None, timer=None) -> None:
    """The ``"raytrace"`` renderer (:mod:`core.renderers`): fills ``frame.color`` and
    ``frame.stats`` for ``settings``, placing the film's samples itself."""
    try:
        options = TraceOptions.from_settings(settings)
        offsets = (sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
                   if settings.samples > 1 else np.array([settings.pixel_offset], dtype=np.float64))
        setup = prepare(scene, view, settings.projection, settings.size, options, offsets,
                        settings.keep_aspect)
        if settings.sample_pattern == "adaptive":
            setup.adaptive = (adaptive.levels_for(settings.samples), settings.options_of("raytrace").adaptive_threshold,
                              adaptive.MIN_LEVELS)
    except ValueError as error:              # a setting or a material the tracer cannot use
        frame.color[...] = to_uint8(scene.background)
        frame.message = f"{scene.name}: cannot ray trace: {error}"
        return
    if setup.packing.build.triangles == 0 and not (len(setup.packing.packed.spheres)
                                                   or len(setup.packing.packed.planes)):
        frame.message = nothing_to_trace(scene)
    if timer is not None:
        timer.lap("pack scene, build BVH")
    start = time.perf_counter()
    if setup.adaptive is None and (settings.pixel_filter != "box"
                                   or settings.filter_radius not in (None, 0.5)):
        from core.settings import check_filter
        radius = check_filter(settings.pixel_filter, settings.filter_radius)
        frame.color[...] = to_uint8(render_filtered(setup, settings.pixel_filter, radius))
        frame.stats["pixel filter"] = f"{settings.pixel_filter}, radius {radius:g}"
    else:
        frame.color[...] = to_uint8(render_raw(setup))
    frame.stats.update(stats_of(setup, time.perf_counter() - start))
    frame.stats["samples per pixel"] = (
        setup.counts[whitted.PRIMARY] / (setup.width * setup.height) if setup.adaptive
        else len(offsets))
    frame.stats["computed"].append("ray tracing")
    if timer is not None:
        timer.lap("ray trace")


def frame_offsets(settings) -> np.ndarray:
    """The sample offsets ``draw`` uses for ``settings``."""
    if settings.samples > 1:
        return sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
    return np.array([settings.pixel_offset], dtype=np.float64)
