"""The headlight: one white light at the eye that follows the camera, in place of the scene's.

The course's lights are fixed in the world (so after an orbit the far side of a model is
dark); a viewer's headlight lights whatever the camera looks at. It is data, not a case in
any kernel: the frame is drawn from a twin of the scene (the same meshes, materials,
primitives and volumes) whose ``lights`` list holds one :class:`core.scene.model.Light` at
the eye of the frame's view (:func:`headlight`: the PRP in world coordinates in perspective;
a directional light towards the viewer in parallel), intensity 1 and no attenuation. Every
renderer that packs ``scene.lights`` per frame (the z-buffer family, the ray tracer and the
ray caster, the volume marcher) draws it with no change.

The twin keeps its identity from frame to frame, so the render context's caches kept with the
scene (the packed geometry, the BVH, the texture varyings) live on; its list is updated in
place (copies made from the twin, such as the lighting-model override's, share the list and so
see the new eye too). The global-illumination renderers solve or pack the light transport once
per scene (radiosity's solution, the path tracer's emitters and lights): a light that moves
with every camera would redo that each frame, so they keep the scene's lights
(:func:`headlight_refused` says why).
"""

from __future__ import annotations

import dataclasses

from core.camera.view import eye_from_view
from core.scene.model import Light


def headlight(view, projection: str) -> Light:
    """A white light at the eye of ``view``: a point light at the PRP (perspective) or a
    directional light towards the viewer (parallel), without attenuation."""
    eye = eye_from_view(view, projection)
    if eye.point is not None:
        return Light(position=tuple(float(c) for c in eye.point))
    return Light(direction=tuple(float(c) for c in eye.direction))


def headlight_refused(renderer) -> str:
    """"" when ``renderer`` (a registry entry) draws the headlight; else why not."""
    if renderer.emitters:
        return (f"the headlight is off for {renderer.label.lower()}: it solves the light once "
                f"per scene; the scene's lights are used")
    return ""


class Headlights:
    """The headlit twin of the scene shown: made once per scene (and again after the scene's
    meshes were edited in place), its lights set to the eye of each frame."""

    def __init__(self):
        self._of = None            # (scene, edits) the twin was made for
        self._twin = None

    def twin(self, scene, edits: int):
        """The twin of ``scene`` (``edits``: the scene's in-place edits so far)."""
        if self._of is None or self._of[0] is not scene or self._of[1] != edits:
            twin = dataclasses.replace(scene, lights=[])      # volumes too (Scene.systems)
            self._of, self._twin = (scene, edits), twin
        return self._twin

    def lit(self, scene, edits: int, view, projection: str):
        """The twin with its one light at ``view``'s eye (call on the thread that renders)."""
        twin = self.twin(scene, edits)
        twin.lights[:] = [headlight(view, projection)]    # in place: copies share the list
        return twin


class Lighting:
    """Which lights draw the frame: the scene's own, or the headlight in their place; and the
    scene as the frame shown was drawn (``state.lighting`` of
    :class:`app.session.state.ViewerState`, which holds the fields)."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here

    def set_headlight(self, on: bool) -> None:
        s = self.state
        if bool(on) != s.headlight:
            s.headlight, s.dirty = bool(on), True

    @property
    def note(self) -> str:
        """The status line's words for the headlight: "" when it is off."""
        s = self.state
        if not s.headlight:
            return ""
        if s.playback is not None:
            return "headlight off on animated scenes: the scene's keyed lights are used"
        return headlight_refused(s.choices.renderer_entry) or "headlight on: a light at the eye"

    def lights_for(self, view):
        """None when the scene's own lights draw the next frame; else ``lit(scene)`` giving
        the scene lit by the headlight at ``view``'s eye (called on the rendering thread)."""
        s = self.state
        if (not s.headlight or view is None or s.playback is not None
                or headlight_refused(s.choices.renderer_entry)):
            return None
        if s._headlights is None:
            s._headlights = Headlights()
        headlights, projection = s._headlights, s.projection
        return lambda scene: headlights.lit(scene, s.scene_edits, view, projection)

    def drawn_scene(self):
        """The scene as the frame shown was drawn, for work beside the renderer (the
        inspector's records and buffer views): the course's .tri rules applied, and under the
        headlight a copy of its own lit at the eye (not the renderer's twin, which the
        worker's next frame relights)."""
        s = self.state
        scene, view = s.scene, s.views.current
        if self.lights_for(view) is not None:
            scene = dataclasses.replace(scene, lights=[headlight(view, s.projection)])
        if s.course_tri and view is not None:
            from core.scene.course_tri import course_tri_scene
            scene = course_tri_scene(scene, view)
        return scene
