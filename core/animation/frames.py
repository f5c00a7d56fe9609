"""One frame of an animation: the opaque picture of ``scene_at(t)``, then the particle stage.

``render_at(animation, t, settings) -> Frame`` is what the movie writer and the window call.
The opaque picture comes from ``core.render`` (any registered renderer); the particles are
blended over it by :func:`core.animation.draw.draw_particles`, depth-tested against
``Frame.depth``.
"""

from __future__ import annotations

import math

import numpy as np

from core.animation.draw import draw_particles


def render_at(animation, t: float, settings, context=None, view_index: int = 0,
              paths: bool = False):
    """The frame at time ``t`` of ``scene_at(t)``, seen through its view ``view_index`` (0: the
    keyed view, or the scene's first view when none is keyed; then the file's views). With
    ``paths`` the keyed paths are drawn over it (:mod:`core.animation.paths`).
    """
    scene = animation.scene_at(t)
    if not scene.views:
        raise ValueError(f"{scene.name}: no view to render")
    view = scene.views[view_index % len(scene.views)]
    frame = _with_particles(animation, t, scene, view, settings, context)
    if paths and frame.message is None:
        from core.animation.paths import draw_paths, paths_of
        draw_paths(frame, paths_of(animation), view, settings)
    return frame


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
