"""The registered renderers by name, and what each can do (read by everything that chooses one).

A renderer is one package (its drawing, its pixel inspector, its plan stages) and one
:func:`register_renderer` call (in :mod:`core.renderers`, or in the module that brings it).
Its entry names its functions and says what it can do, so that the front door, the plan, the
pixel inspector, the scene reader, the command line, the window's menus and the warm-up read
the registry instead of lists of names. The functions, each ``"package.module:function"``:

- ``target``: ``draw(scene, view, settings, frame, context, timer)``, the renderer;
- ``inspector``: ``inspect_pixel(scene, view, settings, x, y, context)``, the record of one
  pixel (:mod:`core.inspect`); its module may define ``buffers(scene, view, settings,
  context, names)``, the buffer views (:mod:`core.inspect.buffers`); None: not inspectable;
- ``plan_stages``: ``add_stages(stages, triangle_stage, scene)``, which puts the renderer's
  own stages in place in the z-buffer's list, or replaces it (:func:`core.plan.plan`); None:
  the z-buffer's;
- ``painting``: ``painting(scene, view, settings, context, timer, n, z_min, vp)``, the
  painter's order of the triangles (:mod:`core.visibility.paint`: the BSP tree's walk or
  Newell's sort); set, it is a painter: the pixel inspector and the command line's plan
  report ask it for its order, and transparency lays the clear triangles in it (None: not a
  painter; transparency then lays them in the depth sort's order).

What it can do:

- ``samples_itself``: it places the film's samples (the front door does not run it per sample);
- ``emitters``: it takes light from area emitters (global illumination);
- ``recursive``: it follows reflected and refracted rays (``k_r``, ``k_t``);
- ``caustics``: the light its paths carry reaches diffuse surfaces off mirrors and through
  glass (the path tracer; the two-pass method's radiosity pass carries none);
- ``transparency``: it lays ``k_t > 0`` over its opaque picture when asked;
- ``shaders``: it shades through the registered shading modes (depth shading among them);
- ``textures``: it draws a material's texture maps;
- ``progressive``: the window shows its picture coarse first, then refining: drawn by its
  ``progressive_drawer`` (``"package.module:function"``, :mod:`core.progressive`'s contract:
  the ray tracer tile by tile, radiosity shot by shot, the path tracer pass by pass), or,
  without one, by :func:`core.progressive.coarse_then_full`;
- ``samples_at_rest``: the samples per pixel the window draws it with when the user has not
  chosen a number (the path tracer's passes add up to it while the camera rests); None: the
  scene's;
- ``analytic``: it intersects ``scene.primitives`` exactly (spheres that the reader left
  untessellated, past the triangle budget, are drawn only by these);
- ``volumes``: it draws a scene's emission–absorption and MIP volumes (every renderer draws an
  isosurface, which is a mesh);
- ``ray_depth``: its frame keeps no depth buffer, and what each film sample shows is the first
  hit of its primary ray: depth cueing casts those rays for the depths
  (:mod:`core.effects.depth_cue`), and draws no line edges again cued (it draws none);
- ``blur_per_ray``: motion blur may give each primary ray a time of its own
  (:mod:`core.animation.ray_blur`, which traces with the Whitted tracer's kernels: set it only
  for a renderer whose picture is the ray tracer's); the others accumulate whole frames;
- ``rasterizes``: it scan-converts triangles, so a 16-sample frame costs about 16 of its frames
  (the window draws the aliasing view only for these; the others cast rays per sample);
- ``triangle_ids``: its buffer views keep the visible triangle at each pixel at the cost of
  one z-buffer pass, which the window's status line draws again for every frame;
- ``drawn_by``: the render log's words for what drew a frame, a :meth:`str.format` template
  over ``settings`` and ``options`` (its options object); empty: its name;
- ``status``: the window's status line's words for it (default "drawn by NAME"; empty: none,
  as for the z-buffer, the default renderer);
- ``label``: its name in the window's Render menu;
- ``key``: its key in the window (and its Render menu item's): the key steps through the
  renderers registered with it (``r``: the z-buffer and the ray tracer);
- ``title``: the window title's words for it (empty: none, as for the z-buffer);
- ``in_menu``: whether the Render menu lists it (the exact ray caster draws only analytic
  primitives, so it is chosen from the command line, not offered for every scene);
- ``options``: its own settings, a frozen dataclass (``"package.module:Class"``) whose
  ``__post_init__`` validates them and whose ``add_arguments(parser)`` / ``overrides(args)``
  are its command-line flags; :class:`core.settings.RenderSettings` carries one per class
  (``settings.options_of(name)``), and ``settings.replace(field=...)`` reaches it by the
  field's name (:func:`option_owner`). Two renderers may share one class (the painters').
  :meth:`Renderer.has_option` says whether its options have a field (the window's draw-order
  slider is for the renderers whose options have ``paint_first``).
- ``bench``: the bench's family that times it (``python -m app bench --renderer``):
  ``"zbuffer"``, ``"raytrace"``, ``"volume"`` (each alone), ``"gi"`` (a list of them) or
  ``"painters"`` (a list of them with the z-buffer); empty: not benched;
- ``warm_up``: the kernel warm-up's frames of its own, each ``(label, scene, settings)``:
  ``scene`` one of the warm-up's small scenes (``"closed"``, ``"small"``: a closed sphere,
  ``"box"``: a cube) and ``settings`` a dict of :class:`core.settings.RenderSettings` fields;
- ``quick``: the settings (a dict) that cut its work to a token amount when the warm-up draws
  a scene with it (the same kernels compile, only for less time).

The entries are data and the targets strings (``"package.module:function"``), imported when
first drawn, inspected or planned (:func:`load`), so this module sits at the bottom of the
core: the scene reader checks a file's ``renderer`` key against :func:`renderer_names`
without importing a renderer, and the plan (below the renderers) reaches their stages.

The renderers and the shading modes are each a :class:`core.registries.Registry`, the one
shape of every registry; the functions here are its wrappers.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from core.registries import Registry, load


@dataclass(frozen=True)
class Renderer:
    name: str
    target: str | Callable          # "package.module:function", or the function itself
    samples_itself: bool = False
    description: str = ""
    label: str = ""
    emitters: bool = False
    recursive: bool = False
    caustics: bool = False
    transparency: bool = False
    shaders: bool = False
    textures: bool = True
    progressive: bool = False
    progressive_drawer: str | None = None   # "package.module:function" (core.progressive)
    samples_at_rest: int | None = None      # the window's samples per pixel unless chosen
    analytic: bool = False                  # draws scene.primitives exactly
    volumes: bool = False
    in_menu: bool = True
    inspector: str | None = None    # "package.module:function": inspect_pixel
    plan_stages: str | None = None  # "package.module:function": add_stages
    options: str | type | None = None
    painting: str | Callable | None = None   # "package.module:function": the painter's order
    ray_depth: bool = False
    blur_per_ray: bool = False
    rasterizes: bool = False
    triangle_ids: bool = False
    drawn_by: str = ""
    status: str | None = None       # None: "drawn by NAME" (register_renderer fills it in)
    key: str = ""                   # the window's key for it ("R")
    title: str = ""                 # the window title's words for it
    bench: str = ""                 # the bench's family that times it
    warm_up: tuple = ()             # (label, scene, settings) frames of the warm-up
    quick: dict | None = None       # its settings cut to a token amount (the warm-up)

    def function(self) -> Callable:
        return load(self.target)

    def drawer(self) -> Callable:
        """How the window draws it with pictures on the way (:mod:`core.progressive`)."""
        return load(self.progressive_drawer or "core.progressive:coarse_then_full")

    def options_class(self) -> type | None:
        """Its options' dataclass (imported on first use), or None."""
        return load(self.options) if self.options is not None else None

    def has_option(self, field: str) -> bool:
        """Whether its options have a field named ``field`` (imports them)."""
        cls = self.options_class()
        return cls is not None and field in cls.__dataclass_fields__

    def words(self, settings) -> str:
        """What drew a frame of ``settings``, in the render log's words (``drawn_by``)."""
        if not self.drawn_by:
            return self.name
        return self.drawn_by.format(settings=settings, options=settings.options_of(self.name))


RENDERERS = Registry("renderer")


def register_renderer(name: str, target, samples_itself: bool = False, description: str = "",
                      **capabilities) -> Renderer:
    """Make ``name`` a value of ``RenderSettings.renderer`` (and of a scene file's
    ``renderer`` key, the command line's ``--renderer`` and the Render menu)."""
    unknown = set(capabilities) - set(Renderer.__dataclass_fields__)
    if unknown:
        raise TypeError(f"unknown renderer capabilities: {', '.join(sorted(unknown))}")
    capabilities.setdefault("label", name)
    capabilities.setdefault("status", f"drawn by {name}")
    return RENDERERS.register(Renderer(name, target, samples_itself, description, **capabilities))


def unregister_renderer(name: str) -> None:
    """Remove ``name`` (a test's or a plug-in's renderer); the built-in ones stay registered."""
    RENDERERS.unregister(name)


def get_renderer(name: str) -> Renderer:
    return RENDERERS.get(name)


def renderer_names() -> tuple[str, ...]:
    return RENDERERS.names()


def renderers() -> tuple[Renderer, ...]:
    return RENDERERS.entries()


def names_that(capability: str) -> tuple[str, ...]:
    """The renderers that can do ``capability`` (a field of :class:`Renderer`), in order."""
    return RENDERERS.names_that(capability)


def option_classes() -> tuple[type, ...]:
    """The renderers' options classes, each once, in registration order."""
    found = []
    for entry in RENDERERS.entries():
        cls = entry.options_class()
        if cls is not None and cls not in found:
            found.append(cls)
    return tuple(found)


def option_owner(field: str) -> type | None:
    """The options class that has a field named ``field`` (None: no renderer's)."""
    for cls in option_classes():
        if field in cls.__dataclass_fields__:
            return cls
    return None


# -- shading modes --------------------------------------------------------------------------
@dataclass(frozen=True)
class ShadingMode:
    """A shading mode a user may choose (a scene's ``shading``, ``--shading``, the Shading menu).

    ``module`` registers its :class:`core.shading.registry.Shader` when imported (None: the
    pipeline's own line drawing, wireframe); ``normals`` is what the plan computes for it
    before lighting (``"face"``, ``"vertex"`` or None) and ``lights`` where it evaluates the
    illumination model (``"faces"``, ``"vertices"``, ``"pixels"`` or None: unlit);
    ``label`` and ``key`` are its Shading menu item."""

    name: str
    module: str | None
    label: str = ""
    key: str = ""
    normals: str | None = None
    lights: str | None = None
    description: str = ""


# The built-in modes register themselves (core.shading.modes, data only, like the renderers'
# registrations), imported by the core package before anything can look one up: this
# module, at the bottom of the core, names nothing above it.
SHADINGS = Registry("shading")


def register_shading(name: str, module: str | None, **fields) -> ShadingMode:
    """Make ``name`` a shading mode everything that chooses one offers (the built-in ones:
    :mod:`core.shading.modes`)."""
    fields.setdefault("label", name)
    mode = ShadingMode(name, module, **fields)
    if mode.normals not in (None, "face", "vertex"):
        raise ValueError(f"normals must be 'face', 'vertex' or None, not {mode.normals!r}")
    if mode.lights not in (None, "faces", "vertices", "pixels"):
        raise ValueError(f"lights must be 'faces', 'vertices', 'pixels' or None, "
                         f"not {mode.lights!r}")
    return SHADINGS.register(mode)


def unregister_shading(name: str) -> None:
    SHADINGS.unregister(name)


def shading_names() -> tuple[str, ...]:
    return SHADINGS.names()


def shading_modes() -> tuple[ShadingMode, ...]:
    return SHADINGS.entries()


def get_shading(name: str) -> ShadingMode:
    return SHADINGS.get(name)
