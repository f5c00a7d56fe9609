"""Motion blur in the ray tracer as distributed ray tracing: a time per primary ray.

Each pixel traces ``J × S`` primary rays: its J film samples (the settings' pattern) each at
S times, one in each of S equal strata of the shutter interval (stratified, so a pixel's S
times cover the shutter evenly whatever the motion). The times come from B = S·m time
buckets: stratum k holds buckets ``k·m … k·m + m − 1``, bucket b at ``(b + u_b) / B`` of
the shutter with ``u_b`` a seeded jitter in [0, 1), and each ray picks its bucket within
its stratum by a seeded per-pixel, per-sample draw. So neighbouring pixels see different
times (B of them across the picture, not S): what accumulated sub-frames, every pixel at
the same S times, show as S sharp copies of a fast object becomes noise instead.

The choice: one scene, one BVH, per time bucket (``animation.scene_at(t_b)``: keyed
objects, the keyed camera, rigid bodies, linkages and actors at t_b), not a ray
transformed into each object's space at its own time — the kernel and its BVH stay as
they are, and every mover is blurred, not only rigid keyed ones. Each ray sees the scene
exactly at its own time; the times are B values per frame rather than a continuum (B is at
least 4·S and at least 64). Particles are drawn over the opaque picture, not traced:
a frame with particles is blurred by accumulation (the frame's stats say so).

Deterministic: the jitters and picks come from ``numpy.random.default_rng`` seeded with the
settings' seed and the frame's time, so a frame is the same bytes on every run.
"""

from __future__ import annotations

import numpy as np

from core.renderers import get_renderer

MIN_BUCKETS = 64        # time buckets a frame at least (the distinct times a picture sees)
BUCKETS_PER_STRATUM = 4
MAX_BUCKETS = 4096


def buckets_per_stratum(samples: int) -> int:
    """m: buckets in each of the S strata (B = S·m >= MIN_BUCKETS, >= 4·S, <= MAX_BUCKETS)."""
    m = max(BUCKETS_PER_STRATUM, -(-MIN_BUCKETS // samples))
    return max(1, min(m, MAX_BUCKETS // samples))


def time_plan(shape: tuple, samples: int, seed: int, t: float):
    """``(fractions (B,), picks (S, J, H, W))``: the buckets' times as fractions of the
    shutter in [0, 1), and each ray's bucket (stratum k's rays pick within stratum k)."""
    fractions, bands = _plan(shape, samples, seed, t, shape[1])
    return fractions, next(bands)[1]


def _plan(shape: tuple, samples: int, seed: int, t: float, rows: int):
    """The buckets' fractions, and an iterator of ``(row0, picks)`` for bands of ``rows``
    rows (drawn band after band from one generator: the same plan for the same size)."""
    m = buckets_per_stratum(samples)
    frame_key = int(round(abs(t) * 1e6)) % (1 << 32)
    rng = np.random.default_rng([int(seed) % (1 << 32), frame_key])
    count = samples * m
    fractions = (np.arange(count) + rng.random(count)) / count
    films, height, width = shape
    first = (np.arange(samples, dtype=np.uint16) * m).reshape(samples, 1, 1, 1)

    def bands():
        for row0 in range(0, height, rows):
            band = (samples, films, min(rows, height - row0), width)
            yield row0, rng.integers(0, m, size=band, dtype=np.uint16) + first
    return fractions, bands()


MAX_BAND_RAYS = 1 << 23     # rays a band: its picks sorted at a time (int64 indices, 64 MB)


def usable(animation, t: float, settings) -> str | None:
    """None when the frame can be blurred per ray, else why not (it is then accumulated)."""
    if not get_renderer(settings.renderer).blur_per_ray:
        return "per-ray times are the ray tracer's"
    if animation.sprites_at(t) is not None:
        return "particles are drawn over the picture, not traced"
    if settings.sample_pattern == "adaptive":
        return "adaptive supersampling chooses its own samples"
    if settings.pixel_filter != "box" or settings.filter_radius not in (None, 0.5):
        return "per-ray blur box-filters its samples"
    if settings.depth_cue:
        return "depth cueing needs one depth a pixel"
    return None


def render_per_ray(animation, t: float, settings, view_index: int, shutter, context=None):
    """The frame at ``t`` blurred per ray (the module's text), or None when a bucket's scene
    cannot be ray traced (the caller's accumulated path then says why). The buckets go in
    time order, each scene made once (a simulation only steps on)."""
    from core.camera.film import sample_offsets
    from core.renderers.raytrace.draw import TraceOptions
    from core.shading.illumination import to_uint8
    width, height = settings.size
    offsets = (sample_offsets(settings.samples, settings.sample_pattern, settings.seed)
               if settings.samples > 1 else np.array([settings.pixel_offset], np.float64))
    per_pixel = len(offsets) * shutter.samples
    rows = max(1, MAX_BAND_RAYS // (per_pixel * max(1, width)))
    fractions, bands = _plan((len(offsets), height, width), shutter.samples, settings.seed,
                             t, rows)
    times = t + (shutter.open + fractions * (shutter.close - shutter.open)) / animation.fps
    plans = [_sorted(row0, picks, len(times)) for row0, picks in bands]
    total = np.zeros((height, width, 3))
    options = TraceOptions.from_settings(settings)
    counts, scene = None, None
    for b, when in enumerate(times):
        if all(bounds[b] == bounds[b + 1] for _, _, _, bounds in plans):
            continue
        setup, scene = _setup_at(animation, when, settings, view_index, options, context)
        if setup is None:
            return None
        for row0, shape, order, bounds in plans:
            _, j, y, x = np.unravel_index(order[bounds[b]:bounds[b + 1]], shape)
            y = y + row0
            points = np.stack([x + offsets[j, 0], y + offsets[j, 1]], axis=1)
            _trace_into(total, setup, points, y, x)
        counts = setup.counts if counts is None else counts + setup.counts
    return _frame(scene, settings, to_uint8(total / per_pixel), counts, len(times), per_pixel)


def _sorted(row0, picks, buckets):
    """A band's rays bucket by bucket: ``(row0, shape, order, bounds)``, bucket b's rays
    being ``order[bounds[b]:bounds[b + 1]]`` (flat indices into ``shape``; 4 bytes a ray)."""
    flat = picks.ravel()
    order = np.argsort(flat, kind="stable").astype(np.int32)
    return row0, picks.shape, order, np.searchsorted(flat[order], np.arange(buckets + 1))


def _trace_into(total, setup, points, y, x) -> None:
    """Adds the colours of the primary rays through ``points`` to their pixels."""
    from core.renderers.raytrace.draw import trace_points
    step = 1 << 18                                   # rays a call, to bound the memory
    for s in range(0, len(points), step):
        colours = trace_points(setup, points[s:s + step])
        np.add.at(total, (y[s:s + step], x[s:s + step]), colours)


def _setup_at(animation, when, settings, view_index, options, context):
    from core.camera.view import pick_view
    from core.renderers.raytrace.draw import prepare
    from core.render import DEFAULT_CONTEXT, lit_as_asked
    scene = animation.scene_at(when)
    if not scene.views:
        return None, scene
    scene = lit_as_asked(scene, settings, context or DEFAULT_CONTEXT)
    view = pick_view(scene.views, view_index)
    try:
        return prepare(scene, view, settings.projection, settings.size, options, None,
                       settings.keep_aspect), scene
    except ValueError:                           # the accumulated path words the message
        return None, scene


def _frame(scene, settings, color, counts, buckets, per_pixel):
    """The frame of the mean colours (its plan from the last bucket's scene: the same
    meshes and materials at every time, and no simulation stepped back to re-ask)."""
    from core.raytrace import whitted
    from core.render import Frame, plan
    height, width = color.shape[:2]
    stages = plan(scene, settings.projection, settings.shading,
                  settings.keep_aspect, settings.rasterizer, settings.texture_filter,
                  settings.renderer, settings.transparency)    # what the window lists
    frame = Frame(rgbx=np.empty((height, width, 4), np.uint8), plan=stages,
                  stats={"allocated": ["color"], "computed": ["ray tracing"],
                         "renderer": settings.renderer, "projection": settings.projection,
                         "shading": settings.shading})
    frame.color[:] = color
    frame.stats["rays"] = {n: int(c) for n, c in zip(whitted.COUNTERS, counts)}
    frame.stats["samples per pixel"] = per_pixel
    frame.stats["motion blur"] = f"per ray, {buckets} time buckets"
    return frame
