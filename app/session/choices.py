"""The render settings the user chose: projection, shading, rasterizer, renderer and its options,
samples, texture filter, bump maps (and the bump demo's clicks), depth cueing, transparency,
the lighting model, depth shading and the painter's draw order, and the
:class:`core.settings.RenderSettings` they make.

A part of :class:`app.session.state.ViewerState`, which holds the fields; a change that alters
the picture sets ``dirty``.
"""

from __future__ import annotations

from core.registry import get_renderer, shading_names
from core.settings import PROJECTIONS, RASTERIZERS


def bump_demos(scene) -> list:
    """The bump demo's materials on ``scene`` (empty elsewhere)."""
    from core.texture.demo_scene import demo_materials
    return demo_materials(scene)


class RenderChoices:
    """The settings of the next frame, each set through its method."""

    @property
    def has_textures(self) -> bool:
        """Has a mesh of the scene a texture, bump, normal or environment map?"""
        from core.texture.material import maps_of
        return any(maps_of(m.material) is not None for m in self.scene.meshes)

    @property
    def is_bump_demo(self) -> bool:
        """Is this the bump demo's scene (J3DPanel's clicks apply)?"""
        return bool(bump_demos(self.scene))

    @property
    def bump_label(self) -> str | None:
        """The demo's text: ``"Bump: B(x,y) = …"`` or ``"Phong"`` (None elsewhere)."""
        if not self.is_bump_demo:
            return None
        from core.texture.demo_scene import label
        return f"Bump: {label(self.bump_map)}" if self.bump else "Phong"

    def settings(self):
        """The :class:`core.settings.RenderSettings` of the next frame."""
        from core.settings import RenderSettings
        return RenderSettings.for_scene(self.scene, projection=self.projection,
                                        shading=self.shading, size=self.size,
                                        rasterizer=self.rasterizer,
                                        keep_aspect=bool(self.keep_aspect),
                                        renderer=self.renderer_name,
                                        samples=self.samples_wanted,
                                        texture_filter=self.texture_filter, bump=self.bump,
                                        depth_cue=self.depth_cue,
                                        transparency=self.transparency or None,
                                        lighting_model=self.lighting_model or None,
                                        depth_shading=self.depth_shading,
                                        paint_first=(self.paint_first if self.renderer_entry
                                                     .has_option("paint_first") else None),
                                        **self.option_values)

    @property
    def samples_wanted(self) -> int | None:
        """The next frame's samples per pixel: the user's, or the renderer's at rest."""
        return self.samples if self.samples is not None else self.renderer_entry.samples_at_rest

    def set_samples(self, samples: int | None) -> bool:
        """Samples per pixel for the next frames (None: the default); a number the settings
        refuse keeps the last good one, with its message in :attr:`option_message`."""
        if samples is not None:
            try:
                self.settings().replace(samples=samples)
            except (ValueError, TypeError) as error:
                self.option_message = f"{error}; samples per pixel stay {self.samples_wanted}"
                return False
        self.option_message = ""
        if samples != self.samples:
            self.samples, self.dirty = samples, True
        return True

    @property
    def has_triangles(self) -> bool:
        return self.scene.triangle_count > 0

    @property
    def renderer_entry(self):
        """The renderer's registry entry (:class:`core.registry.Renderer`: what it can do)."""
        return get_renderer(self.renderer_name or "zbuffer")

    def set_renderer(self, name: str) -> None:
        """``"zbuffer"`` or ``"raytrace"`` (any registered renderer)."""
        from core.renderers import renderer_names
        self._set("renderer_name", name, renderer_names())

    def next_texture_filter(self) -> str:
        """The texture filter after this one (nearest, bilinear, trilinear, anisotropic)."""
        from core.texture.modes import FILTERS
        names = tuple(FILTERS)
        self.set_texture_filter(names[(names.index(self.texture_filter) + 1) % len(names)])
        return self.texture_filter

    def set_bump(self, on: bool) -> None:
        if bool(on) != self.bump:
            self.bump, self.dirty = bool(on), True

    def next_bump_map(self) -> int:
        """The demo's next height map (0 → 1 → 2 → 3 → 0), as its other mouse buttons do."""
        from core.texture.demo_scene import MAPS
        self.bump_map, self.dirty = (self.bump_map + 1) % MAPS, True
        return self.bump_map

    def set_depth_cue(self, on: bool) -> None:
        if bool(on) != bool(self.settings().depth_cue):
            self.depth_cue, self.dirty = bool(on), True

    def set_transparency(self, mode: str) -> None:
        from core.settings import TRANSPARENCIES
        self._set("transparency", mode, TRANSPARENCIES)

    def renderer_options(self):
        """The current renderer's options object as the next frame uses it (None: it has
        none)."""
        return self.settings().options_of(self.renderer_name or "zbuffer")

    def set_option(self, name: str, value) -> bool:
        """Set the renderer's option ``name`` (a field of its options class). A value its class
        refuses keeps the last good one, with the class's message (:attr:`option_message`)."""
        try:
            self.settings().replace(**{name: value})      # the options class checks it
        except (ValueError, TypeError) as error:
            kept = getattr(self.renderer_options(), name, None)
            self.option_message = f"{error}; {name.replace('_', ' ')} stays {kept!r}"
            return False
        self.option_message = ""
        if self.option_values.get(name, object()) != value:
            self.option_values = {**self.option_values, name: value}
            self.dirty = True
        return True

    def set_paint_first(self, count: int | None) -> None:
        """Paint only the first ``count`` triangles of the order (None: all of them)."""
        count = None if count is None else max(int(count), 0)
        if count != self.paint_first:
            self.paint_first, self.dirty = count, True

    @property
    def painted_total(self) -> int | None:
        """How many triangles the last painter's frame painted in all (the slider's end)."""
        stats = getattr(self.frame, "stats", None) or {}
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
        if value != getattr(self, name):
            setattr(self, name, value)
            self.dirty = True

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
            self.set_bump(not self.bump)
        else:
            self.next_bump_map()
        from core.texture.demo_scene import apply_demo_options
        return apply_demo_options(self.scene, self.bump_map, self.bump)

    def set_keep_aspect(self, keep: bool) -> None:
        if bool(keep) != self.keep_aspect:
            self.keep_aspect = bool(keep)
            self.dirty = True

    def set_course_tri(self, on: bool) -> None:
        if bool(on) != self.course_tri:
            self.course_tri = bool(on)
            self.dirty = True
