"""How to draw: the projection, shading, size, samples and renderer of one frame.

The names of the projections are listed here once (:class:`Projection`); the shading modes a
user may choose are the registered ones (:func:`core.registry.shading_names`, the built-in
ones in :mod:`core.shading.modes`), which the reader, the plan, the CLI and the window offer.
:class:`Shading` names the built-in modes. Both are ``str`` enums, so ``Shading.PHONG ==
"phong"`` and scene files keep their words.

:class:`RenderSettings` is a frozen value: a variant is ``settings.replace(…)``. Each
renderer's own settings are its registered options class's (``settings.options_of(name)``).
A system that needs a setting of its own adds a field here with a default that keeps every
existing picture unchanged.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from enum import Enum

from core.registry import get_renderer, option_owner, shading_modes, shading_names


class Projection(str, Enum):
    PERSPECTIVE = "perspective"
    PARALLEL = "parallel"

    def __str__(self) -> str:
        return self.value


PROJECTIONS = tuple(p.value for p in Projection)
# The shading modes, for the sweeps and tests that go through them: the registry's
# (core.registry, core.shading.modes), read here once; SOLID_SHADINGS are those that light
# filled triangles (depth shading fills them unlit: it is left out of the sweeps that compare
# lighting against the exact images).
SHADINGS = shading_names()
SOLID_SHADINGS = tuple(mode.name for mode in shading_modes() if mode.lights)
SAMPLE_PATTERNS = ("regular", "jittered", "adaptive")   # adaptive: the ray tracer's
FRESNEL_FORMS = ("schlick", "exact")
SPECULAR_FORMS = ("reflect", "halfway")     # (R·V)^n, or the halfway vector's (N·H)^n
SHADING_PRECISIONS = ("float32", "float64")    # core.shading.phong_wide, core.shading.phong
# Radiosity's form factors and solvers (core.radiosity.solve).
FORM_FACTOR_METHODS = ("hemicube", "raycast")
SOLVERS = ("progressive", "gauss-seidel")
# The ray tracer's shadow rays (core.raytrace.whitted): the notes' options.
SHADOW_MODES = ("off", "background", "object", "transmit")
PIXEL_FILTERS = ("box", "tent", "gaussian", "mitchell")     # core.camera.filters
FILTER_RADIUS = {"box": 0.5, "tent": 1.0, "gaussian": 1.5, "mitchell": 2.0}   # their defaults
MAX_FILTER_RADIUS = 8.0
CLIPPERS = ("cohen-sutherland", "liang-barsky", "homogeneous")   # core.pipeline.clip.CLIPPERS
RASTERIZERS = ("edge", "scanline")     # core.pipeline.raster, core.pipeline.raster_scanline
BSP_ROOTS = ("first", "random", "fewest-splits")   # core.visibility.bsp.ROOT_RULES
# The transparency kinds (core.effects.transparency) and their names in the window's menu:
# the one list the settings, the scene reader, the command line and the menu read.
TRANSPARENCIES = {"off": "Opaque (k_t ignored)",
                  "interpolated": "Interpolated",
                  "interpolated-specular": "Interpolated, the near one's specular added",
                  "screen-door": "Screen door"}
MAX_SAMPLES = 256          # samples per pixel any input may ask for


def require_one_of(what: str, value, choices) -> None:
    """ValueError "<what> must be one of a, b, c, not 'x'" unless ``value`` is a choice."""
    if value not in choices:
        raise ValueError(f"{what} must be one of {', '.join(choices)}, not {value!r}")


@dataclass(frozen=True)
class RenderSettings:
    """Everything about a frame that is not the scene or the view.

    ``samples`` per pixel are placed by :class:`core.camera.film.Film` (a regular √s x √s grid,
    or jittered within its cells with ``seed``) and box-filtered; 1 sample is the pixel centre,
    the course's sample point. ``renderer`` names an entry of :mod:`core.renderers`.
    """

    projection: str = "perspective"
    shading: str = "flat"
    size: tuple[int, int] = (500, 500)        # width, height in pixels
    samples: int = 1
    sample_pattern: str = "regular"
    renderer: str = "zbuffer"
    seed: int = 0
    rasterizer: str = "edge"                  # "edge" (fast) | "scanline" (the course's ET/AET, screen-linear)
    keep_aspect: bool = False                 # letterbox the window; False: stretch it over the viewport (the course)
    # Where in its pixel a one-sample frame samples (x right, y down, pixel units): the centre,
    # as the course's scan conversion does; the film moves it for each of several samples.
    pixel_offset: tuple[float, float] = (0.5, 0.5)
    # Texture filter (core.texture.sample.FILTERS): nearest | bilinear | trilinear | anisotropic.
    texture_filter: str = "trilinear"
    # Bump and normal maps perturb the normal (False: the demo's "Phong" mode, maps ignored).
    bump: bool = True
    # Each renderer's own settings (the ray tracer's depth limit and shadows, radiosity's
    # solver, the painters' BSP root, …): one frozen options object per class a renderer
    # registered (core.registry), read with options_of(name); those left at their defaults
    # are not stored, so two settings that draw alike compare equal.
    options: tuple = ()
    # Depth cueing (core.effects.depth_cue) on any renderer, with the scene's
    # [depth_cue] parameters (on by default for a scene that has the table).
    depth_cue: bool = False
    # Depth shading's scalar (core.shading.depth.MODES): "height" (world y) | "view" (eye distance).
    depth_shading: str = "height"
    # Transparency of materials with k_t > 0 in the z-buffer family (core.effects.transparency):
    # "off" (drawn opaque, as before) | "interpolated" | "interpolated-specular" |
    # "screen-door" (TRANSPARENCIES).
    transparency: str = "off"
    # The clipper of lines (core.pipeline.clip) and polygons (core.pipeline.clip_polygon):
    # "cohen-sutherland" (the course's outcodes and Sutherland–Hodgman, in the canonical
    # volume) | "liang-barsky" (parametric tests) | "homogeneous" (in clip space, before the
    # divide). The same picture.
    clipper: str = "cohen-sutherland"
    # The reconstruction filter of a supersampled frame (core.camera.filters): "box" (the
    # mean of each pixel's samples, as before) | "tent" | "gaussian" | "mitchell", and its
    # radius in pixels (None: the filter's own default).
    pixel_filter: str = "box"
    # The wireframe's lines: False the midpoint line (the course's), True Wu's antialiased
    # line (core.pipeline.raster_lines.draw_lines_wu), each pixel weighted by its coverage.
    antialias_lines: bool = False
    filter_radius: float | None = None
    # Phong's pixel step (core.shading.phong_wide): "float32", the model over each row in
    # 8-wide float32 passes (within 1/255 of float64; extreme inputs fall back per pixel), or
    # "float64", the textbook kernel, one pixel at a time.
    shading_precision: str = "float32"
    # A lighting model (core.shading.models) for every material, over what each material's
    # ``model`` key chose: the command line's --lighting-model, the window's menu. None: the
    # materials' own (Phong unless a material names another).
    lighting_model: str | None = None

    def __post_init__(self) -> None:
        require_one_of("projection", self.projection, PROJECTIONS)
        require_one_of("shading", str(self.shading), shading_names())
        if not (isinstance(self.samples, int) and 1 <= self.samples <= MAX_SAMPLES):
            raise ValueError(f"samples per pixel must be a whole number from 1 to {MAX_SAMPLES}, "
                             f"not {self.samples!r}")
        require_one_of("shading_precision", self.shading_precision, SHADING_PRECISIONS)
        require_one_of("rasterizer", self.rasterizer, RASTERIZERS)
        require_one_of("sample pattern", self.sample_pattern, SAMPLE_PATTERNS)
        side = math.isqrt(self.samples)
        if self.sample_pattern == "regular" and side * side != self.samples:
            # the film's regular grid is s x s; refused here, not as a traceback in the film
            raise ValueError(f"samples per pixel: {self.samples} is not a square; the regular "
                             f"grid takes 1, 4, 9, 16, … (the nearest are {side * side} and "
                             f"{(side + 1) ** 2})")
        if self.sample_pattern == "adaptive" and self.samples not in (1, 4, 16, 64, 256):
            raise ValueError(f"adaptive supersampling splits a pixel in four at each level: "
                             f"its most samples must be 4, 16, 64 or 256, not {self.samples}")
        check_filter(self.pixel_filter, self.filter_radius)
        require_one_of("clipper", self.clipper, CLIPPERS)
        require_one_of("transparency", self.transparency, TRANSPARENCIES)
        object.__setattr__(self, "projection", str(self.projection))
        object.__setattr__(self, "shading", str(self.shading))
        object.__setattr__(self, "size", (int(self.size[0]), int(self.size[1])))
        object.__setattr__(self, "pixel_offset", (float(self.pixel_offset[0]),
                                                  float(self.pixel_offset[1])))

    @classmethod
    def for_scene(cls, scene, **overrides) -> "RenderSettings":
        """The scene's own defaults (projection, shading, size), then ``overrides``; an
        override of ``None`` keeps the scene's value."""
        values = {"projection": scene.projection, "shading": scene.shading, "size": scene.size,
                  "rasterizer": scene.rasterizer, "keep_aspect": scene.keep_aspect,
                  "renderer": scene.renderer,
                  "depth_cue": getattr(scene, "depth_cue", None) is not None,
                  "transparency": getattr(scene, "transparency", None)
                  or needed_transparency(scene)}
        values.update({k: v for k, v in overrides.items() if v is not None})
        return cls().replace(**values)

    def replace(self, **changes) -> "RenderSettings":
        """A variant; a change to a field of a renderer's options (``max_depth=3``) goes to
        that renderer's options object (TypeError for a name that is neither)."""
        own = {k: v for k, v in changes.items() if k in RenderSettings.__dataclass_fields__}
        options = {type(o): o for o in own.pop("options", self.options)}   # whole objects too
        for name, value in changes.items():
            if name in RenderSettings.__dataclass_fields__:
                continue
            cls = option_owner(name)
            if cls is None:
                raise TypeError(f"RenderSettings has no setting {name!r}, and no renderer's "
                                f"options have one")
            options[cls] = dataclasses.replace(options.get(cls) or cls(), **{name: value})
        kept = tuple(sorted((o for cls, o in options.items() if o != cls()),
                            key=lambda o: type(o).__name__))
        return dataclasses.replace(self, **own, options=kept)

    def options_of(self, renderer: str):
        """Renderer ``renderer``'s options object (its defaults when none was set), or None
        for a renderer that registered none."""
        cls = get_renderer(renderer).options_class()
        if cls is None:
            return None
        return next((o for o in self.options if type(o) is cls), None) or cls()


def needed_transparency(scene) -> str:
    """What a scene that names no ``transparency`` gets: "interpolated" where any material has
    k_t > 0 (the scene needs it: drawn opaque, a glass pane would hide what is behind it; the
    ray tracers refract instead, as before), else "off". ``--transparency off`` still draws
    it opaque."""
    meshes = getattr(scene, "meshes", ())
    return "interpolated" if any(m.material.kt > 0 for m in meshes) else "off"


def check_filter(name: str, radius: float | None) -> float:
    """The radius a pixel filter uses (its default for None); ValueError with a message for an
    unknown filter or a radius outside (0, 8] pixels."""
    if name not in PIXEL_FILTERS:
        raise ValueError(f"the pixel filter must be one of {', '.join(PIXEL_FILTERS)}, "
                         f"not {name!r}")
    if radius is None:
        return FILTER_RADIUS[name]
    r = float(radius)
    if not (0.0 < r <= MAX_FILTER_RADIUS):
        raise ValueError(f"the filter radius must be above 0 and at most "
                         f"{MAX_FILTER_RADIUS:g} pixels, not {radius!r}")
    return r
