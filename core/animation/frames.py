"""One frame of an animation: the opaque picture of ``scene_at(t)``, then the particle stage.

``render_at(animation, t, settings) -> Frame`` is what the movie writer and the window call.
The opaque picture comes from ``core.render`` (any registered renderer); the particles are
blended over it by :func:`core.animation.draw.draw_particles`, depth-tested against
``Frame.depth``.

Motion blur (temporal antialiasing): with a :class:`Shutter` of S samples the frame is the
box filter over the shutter interval, estimated as the accumulation buffer does it — S whole
frames at the midpoints of S equal parts of ``[t + open/fps, t + close/fps]``, averaged in
floating point and rounded once. Keyed objects, the keyed camera, rigid bodies, linkages
and particles are all taken at each sample's time. That is every renderer's way with
``method = "accumulate"``, and the z-buffer's by default.

The ray tracer by default (``method = "auto"`` or ``"per-ray"``) blurs as distributed ray
tracing, a time per primary ray (:mod:`core.animation.ray_blur`): S rays a film sample, at
stratified times with a per-pixel jitter, each seeing the scene at its own time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from core.animation.draw import draw_particles
from core.camera.view import pick_view
from core.renderers import get_renderer


@dataclass(frozen=True)
class Shutter:
    """S samples over the shutter interval ``[open, close]`` (fractions of a frame's time
    after the frame's instant). The default, -0.25 to 0.25, is a 180° shutter centred on the
    frame's time (the blurred frame is where the sharp one is)."""

    samples: int = 1
    open: float = -0.25
    close: float = 0.25
    method: str = "auto"        # BLUR_METHODS: auto is per-ray for the ray tracer, else accumulate

    def __post_init__(self) -> None:
        if self.method not in BLUR_METHODS:
            raise ValueError(f"the motion blur's method is one of {', '.join(BLUR_METHODS)}, "
                             f"not {self.method!r}")
        if not 1 <= self.samples <= MAX_BLUR_SAMPLES:
            raise ValueError(f"motion blur takes 1 to {MAX_BLUR_SAMPLES} samples, not {self.samples}")
        if not (math.isfinite(self.open) and math.isfinite(self.close)
                and -1.0 <= self.open <= self.close <= 1.0):
            raise ValueError(f"the shutter opens and closes within a frame either side of the "
                             f"frame's time, open <= close (-1 to 1), not {self.open:g} to "
                             f"{self.close:g}")

    def times(self, t: float, fps: float) -> list[float]:
        """The sample times of the frame at time t: the midpoints of S equal parts."""
        if self.samples == 1:
            return [t]
        span = self.close - self.open
        return [t + (self.open + (i + 0.5) / self.samples * span) / fps
                for i in range(self.samples)]

    def opens(self, t: float, fps: float) -> float:
        """The earliest time a sample of the frame at t takes: the shutter's opening (a ray's
        time may lie anywhere in its part; the accumulated samples start later, at the
        first part's midpoint). What a simulation restored for the frame starts from."""
        return t if self.samples == 1 else t + self.open / fps


MAX_BLUR_SAMPLES = 1024
BLUR_METHODS = ("auto", "accumulate", "per-ray")
SHARP = Shutter(1)


def render_at(animation, t: float, settings, context=None, view_index: int = 0,
              paths: bool = False, shutter: Shutter | None = None):
    """The frame at time ``t`` of ``scene_at(t)``, seen through its view ``view_index`` (0: the
    keyed view, or the scene's first view when none is keyed; then the file's views), or
    through ``view_index`` itself when it is a View (:func:`core.camera.view.pick_view`). With
    ``paths`` the keyed paths are drawn over it (:mod:`core.animation.paths`). With a
    ``shutter`` of more than one sample (default: the scene file's, ``animation.shutter``),
    the motion-blurred frame (the module's text); ``Shutter(1)`` is sharp.
    """
    if shutter is None:
        shutter = getattr(animation, "shutter", None)
    if shutter is not None and shutter.samples > 1:
        frame, why = _per_ray(animation, t, settings, context, view_index, shutter)
        if frame is None:
            frame = _blurred(animation, t, settings, context, view_index, paths, shutter)
            frame.stats["motion blur"] = f"accumulated ({why})" if why else "accumulated"
            return frame
        if paths:          # the view at t alone: scene_at(t) would step simulations back
            from core.animation.paths import draw_paths, paths_of
            keyed = animation.view_at(animation.local_time(t))
            views = ([keyed] if keyed is not None else []) + list(animation.scene.views)
            draw_paths(frame, paths_of(animation), pick_view(views, view_index), settings)
        return frame
    scene = animation.scene_at(t)
    if not scene.views:
        raise ValueError(f"{scene.name}: no view to render")
    view = pick_view(scene.views, view_index)
    frame = _with_particles(animation, t, scene, view, settings, context)
    if paths and frame.message is None:
        from core.animation.paths import draw_paths, paths_of
        draw_paths(frame, paths_of(animation), view, settings)
    return frame


def _per_ray(animation, t, settings, context, view_index, shutter):
    """``(frame, why not)``: the frame blurred a time per ray, or None where it is
    accumulated instead — the z-buffer's renderers, ``method = "accumulate"``, or what the
    per-ray path cannot take (``ray_blur.usable``: the reason goes in the frame's stats)."""
    per_ray = get_renderer(settings.renderer).blur_per_ray      # the ray tracer's
    if shutter.method == "accumulate" or (shutter.method == "auto" and not per_ray):
        return None, None
    from core.animation import ray_blur
    why = ray_blur.usable(animation, t, settings)
    if why:
        return None, why
    frame = ray_blur.render_per_ray(animation, t, settings, view_index, shutter, context)
    return frame, (None if frame is not None else "a time's scene cannot be ray traced")


def _blurred(animation, t, settings, context, view_index, paths, shutter):
    """The mean of the shutter's sample frames, rounded once (a still scene: the sharp frame
    exactly, the mean of equal bytes being those bytes)."""
    total, first = None, None
    for s in shutter.times(t, animation.fps):
        frame = render_at(animation, s, settings, context, view_index, paths, SHARP)
        if frame.message is not None:
            return frame
        if total is None:
            total, first = frame.color.astype(np.float64), frame
        else:
            total += frame.color
    first.color[:] = np.floor(total / shutter.samples + 0.5).astype(np.uint8)
    first.stats["motion blur samples"] = shutter.samples
    return first


def _with_particles(animation, t, scene, view, settings, context):
    """The opaque frame, then the particle stage.

    With more than one sample a pixel, the opaque picture is drawn once at ``side`` times the
    size (side = sqrt(samples), the regular grid), the particles are blended into that big
    picture against its depth, and the result is box-filtered: each sample sees the particles
    with its own depth test (the front door's supersampled frames keep no depth).
    """
    from core import render
    from core.camera.film import box_filter
    sprites = animation.sprites_at(t)
    if sprites is None or settings.samples == 1:
        frame = render(scene, view, settings, context)
        if sprites is not None and frame.message is None:
            draw_particles(frame, sprites, view, settings)
            _count_unborn(frame, animation)
        return frame
    side = max(1, math.isqrt(settings.samples - 1) + 1)       # the smallest grid that holds them
    width, height = settings.size
    big = render(scene, view, settings.replace(samples=1, size=(width * side, height * side)),
                 context)
    if big.message is None:
        draw_particles(big, sprites, view, settings)
    small = np.floor(box_filter(big.color, side) + 0.5).astype(np.uint8)
    out = type(big)(rgbx=np.empty((height, width, 4), np.uint8), plan=big.plan,
                    message=big.message, stats={**big.stats, "samples per pixel": side * side})
    out.color[:] = small
    out.sample_color = big.color
    _count_unborn(out, animation)
    return out


def _count_unborn(frame, animation) -> None:
    """Particles the MAX_PARTICLES cap kept from being born go in the frame's stats (the
    command line warns of them): the cap is never silent."""
    unborn = animation.particle_system.unborn
    if unborn:
        from core.animation.particles import MAX_PARTICLES
        frame.stats["particles not born"] = unborn
        frame.stats["particle cap"] = MAX_PARTICLES
