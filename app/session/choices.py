"""The render settings the user chose: projection, shading, rasterizer, renderer and its options,
samples, texture filter, bump maps (and the bump demo's clicks), depth cueing, transparency,
the lighting model, depth shading and the painter's draw order, and the
:class:`core.settings.RenderSettings` they make.

:class:`RenderChoices` is the ``choices`` part of :class:`app.session.state.ViewerState`, which
holds the fields; a change that alters the picture sets the state's ``dirty``.
"""

from __future__ import annotations

from core.registry import get_renderer, shading_names
from core.settings import PROJECTIONS, RASTERIZERS


def bump_demos(scene) -> list:
    """The bump demo's materials on ``scene`` (empty elsewhere)."""
    from core.texture.demo_scene import demo_materials
    return demo_materials(scene)


class RenderChoices:
    """The settings of the next frame, each set through its method (``state.choices``)."""

    def __init__(self, state):
        self.state = state        # the ViewerState: the fields live there, not here

    @property
    def has_textures(self) -> bool:
        """Has a mesh of the scene a texture, bump, normal or environment map?"""
        from core.texture.material import maps_of
        return any(maps_of(m.material) is not None for m in self.state.scene.meshes)

    @property
    def is_bump_demo(self) -> bool:
        """Is this the bump demo's scene (J3DPanel's clicks apply)?"""
        return bool(bump_demos(self.state.scene))

    @property
    def bump_label(self) -> str | None:
        """The demo's text: ``"Bump: B(x,y) = …"`` or ``"Phong"`` (None elsewhere)."""
        if not self.is_bump_demo:
            return None
        from core.texture.demo_scene import label
        return f"Bump: {label(self.state.bump_map)}" if self.state.bump else "Phong"

    def settings(self):
        """The :class:`core.settings.RenderSettings` of the next frame."""
        from core.settings import RenderSettings
        s = self.state
        return RenderSettings.for_scene(s.scene, projection=s.projection, shading=s.shading,
                                        size=s.size, rasterizer=s.rasterizer,
                                        keep_aspect=bool(s.keep_aspect),
                                        renderer=s.renderer_name,
                                        samples=self.samples_wanted,
                                        texture_filter=s.texture_filter, bump=s.bump,
                                        depth_cue=s.depth_cue,
                                        transparency=s.transparency or None,
                                        lighting_model=s.lighting_model or None,
                                        depth_shading=s.depth_shading,
                                        paint_first=(s.paint_first if self.renderer_entry
                                                     .has_option("paint_first") else None),
                                        **s.option_values)

    @property
    def samples_wanted(self) -> int | None:
        """The next frame's samples per pixel: the user's, or the renderer's at rest."""
        samples = self.state.samples
        return samples if samples is not None else self.renderer_entry.samples_at_rest

    def set_samples(self, samples: int | None) -> bool:
        """Samples per pixel for the next frames (None: the default); a number the settings
        refuse keeps the last good one, with its message in the state's ``option_message``."""
        s = self.state
        if samples is not None:
            try:
                self.settings().replace(samples=samples)
            except (ValueError, TypeError) as error:
                s.option_message = f"{error}; samples per pixel stay {self.samples_wanted}"
                return False
        s.option_message = ""
        if samples != s.samples:
            s.samples, s.dirty = samples, True
        return True

    @property
    def has_triangles(self) -> bool:
        return self.state.scene.triangle_count > 0

    @property
    def renderer_entry(self):
        """The renderer's registry entry (:class:`core.registry.Renderer`: what it can do)."""
        return get_renderer(self.state.renderer_name or "zbuffer")

    def set_renderer(self, name: str) -> None:
        """``"zbuffer"`` or ``"raytrace"`` (any registered renderer)."""
        from core.renderers import renderer_names
        self._set("renderer_name", name, renderer_names())

    def next_texture_filter(self) -> str:
        """The texture filter after this one (nearest, bilinear, trilinear, anisotropic)."""
        from core.texture.modes import FILTERS
        names = tuple(FILTERS)
        here = names.index(self.state.texture_filter)
        self.set_texture_filter(names[(here + 1) % len(names)])
        return self.state.texture_filter

    def set_bump(self, on: bool) -> None:
        if bool(on) != self.state.bump:
            self.state.bump, self.state.dirty = bool(on), True

    def next_bump_map(self) -> int:
        """The demo's next height map (0 → 1 → 2 → 3 → 0), as its other mouse buttons do."""
        from core.texture.demo_scene import MAPS
        s = self.state
        s.bump_map, s.dirty = (s.bump_map + 1) % MAPS, True
        return s.bump_map

    def set_depth_cue(self, on: bool) -> None:
        if bool(on) != bool(self.settings().depth_cue):
            self.state.depth_cue, self.state.dirty = bool(on), True

    def set_transparency(self, mode: str) -> None:
        from core.settings import TRANSPARENCIES
        self._set("transparency", mode, TRANSPARENCIES)

    def renderer_options(self):
        """The current renderer's options object as the next frame uses it (None: it has
        none)."""
        return self.settings().options_of(self.state.renderer_name or "zbuffer")

    def set_option(self, name: str, value) -> bool:
        """Set the renderer's option ``name`` (a field of its options class). A value its class
        refuses keeps the last good one, with the class's message (the state's
        ``option_message``)."""
        try:
            self.settings().replace(**{name: value})      # the options class checks it
        except (ValueError, TypeError) as error:
            kept = getattr(self.renderer_options(), name, None)
            self.state.option_message = f"{error}; {name.replace('_', ' ')} stays {kept!r}"
            return False
        s = self.state
        s.option_message = ""
        if s.option_values.get(name, object()) != value:
            s.option_values = {**s.option_values, name: value}
            s.dirty = True
        return True

    def set_paint_first(self, count: int | None) -> None:
        """Paint only the first ``count`` triangles of the order (None: all of them)."""
        count = None if count is None else max(int(count), 0)
        if count != self.state.paint_first:
            self.state.paint_first, self.state.dirty = count, True

    @property
    def painted_total(self) -> int | None:
        """How many triangles the last painter's frame painted in all (the slider's end)."""
        stats = getattr(self.state.frame, "stats", None) or {}
        return stats.get("painted total", stats.get("painted"))

    def set_projection(self, projection: str) -> None:
        self._set("projection", projection, PROJECTIONS)

    def set_shading(self, shading: str) -> None:
        self._set("shading", shading, shading_names())

    def set_rasterizer(self, rasterizer: str) -> None:
        self._set("rasterizer", rasterizer, RASTERIZERS)

    def _set(self, name: str, value: str, allowed) -> None:
        if value not in allowed:
            raise ValueError(f"{name} must be one of {', '.join(allowed)}, not {value!r}")
        if value != getattr(self.state, name):
            setattr(self.state, name, value)
            self.state.dirty = True

    def set_depth_shading(self, mode: str) -> None:
        """Depth shading by the distance from the eye ("view") or by height ("height")."""
        from core.shading.depth import MODES
        self._set("depth_shading", mode, MODES)

    def set_lighting_model(self, name: str) -> None:
        """A registered lighting model for every material, or "" for each material's own."""
        from core.shading.models import lighting_model_names
        self._set("lighting_model", name, ("",) + lighting_model_names())

    def set_texture_filter(self, name: str) -> None:
        from core.texture.modes import FILTERS
        self._set("texture_filter", name, tuple(FILTERS))

    # -- the bump demo's mouse (J3DPanel): left click toggles bump/Phong, any other
    # button cycles the height maps. Only in a scene with the demo's material.
    def demo_click(self, left: bool) -> str | None:
        """The demo's click; returns its label, or None (the click keeps its usual meaning).
        The demo's material is set now and again by the next frame's job (on the worker's
        thread, so that a frame never sees it change half-way)."""
        if not self.is_bump_demo:
            return None
        if left:
            self.set_bump(not self.state.bump)
        else:
            self.next_bump_map()
        from core.texture.demo_scene import apply_demo_options
        return apply_demo_options(self.state.scene, self.state.bump_map, self.state.bump)

    def set_keep_aspect(self, keep: bool) -> None:
        if bool(keep) != self.state.keep_aspect:
            self.state.keep_aspect = bool(keep)
            self.state.dirty = True

    def set_course_tri(self, on: bool) -> None:
        if bool(on) != self.state.course_tri:
            self.state.course_tri = bool(on)
            self.state.dirty = True
