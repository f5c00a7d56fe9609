"""One frame of an animation: the opaque picture of ``scene_at(t)``, then the particle stage.

``render_at(animation, t, settings) -> Frame`` is what the movie writer and the window call.
The opaque picture comes from ``core.render`` (any registered renderer); the particles are
blended over it by :func:`core.animation.draw.draw_particles`, depth-tested against
``Frame.depth``.
"""

from __future__ import annotations

import dataclasses

from core.animation.draw import draw_particles


def settings_for(animation, **overrides):
    """The render settings of the animation's scene, with ``overrides`` (size, samples, …)."""
    from core import RenderSettings
    return RenderSettings.for_scene(animation.scene, **overrides)


def render_at(animation, t: float, settings):
    """The frame at time ``t``: the keyed view (or the scene's first view) of ``scene_at(t)``."""
    from core import render
    scene = animation.scene_at(t)
    if not scene.views:
        raise ValueError(f"{scene.name}: no view to render")
    view = scene.views[0]
    frame = render(scene, view, settings)
    sprites = animation.sprites_at(t)
    if sprites is not None and frame.message is None:
        draw_particles(frame, sprites, view, settings)
    return frame
