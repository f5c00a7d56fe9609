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
- ``plan_stages``: ``add_stages(stages, triangle_stage)``, which puts the renderer's own
  stages in place in the z-buffer's list (:func:`core.plan.plan`); None: the z-buffer's.

What it can do:

- ``samples_itself``: it places the film's samples (the front door does not run it per sample);
- ``emitters``: it takes light from area emitters (global illumination);
- ``recursive``: it follows reflected and refracted rays (``k_r``, ``k_t``);
- ``transparency``: it lays ``k_t > 0`` over its opaque picture when asked;
- ``shaders``: it shades through the registered shading modes (depth shading among them);
- ``textures``: it draws a material's texture maps;
- ``progressive``: the window shows its picture coarse first, then refining;
- ``volumes``: it draws a scene's emission–absorption and MIP volumes (every renderer draws an
  isosurface, which is a mesh);
- ``label``: its name in the window's Render menu;
- ``in_menu``: whether the Render menu lists it (the exact ray caster draws only analytic
  primitives, so it is chosen from the command line, not offered for every scene);
- ``options``: its own settings, a frozen dataclass (``"package.module:Class"``) whose
  ``__post_init__`` validates them and whose ``add_arguments(parser)`` / ``overrides(args)``
  are its command-line flags; :class:`core.settings.RenderSettings` carries one per class
  (``settings.options_of(name)``), and ``settings.replace(field=...)`` reaches it by the
  field's name (:func:`option_owner`). Two renderers may share one class (the painters').

The entries are data and the targets strings (``"package.module:function"``), imported when
first drawn, inspected or planned (:func:`load`), so this module sits at the bottom of the
core: the scene reader checks a file's ``renderer`` key against :func:`renderer_names`
without importing a renderer, and the plan (below the renderers) reaches their stages.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Renderer:
    name: str
    target: str | Callable          # "package.module:function", or the function itself
    samples_itself: bool = False
    description: str = ""
    label: str = ""
    emitters: bool = False
    recursive: bool = False
    transparency: bool = False
    shaders: bool = False
    textures: bool = True
    progressive: bool = False
    volumes: bool = False
    in_menu: bool = True
    inspector: str | None = None    # "package.module:function": inspect_pixel
    plan_stages: str | None = None  # "package.module:function": add_stages
    options: str | type | None = None

    def function(self) -> Callable:
        return load(self.target)

    def options_class(self) -> type | None:
        """Its options' dataclass (imported on first use), or None."""
        return load(self.options) if self.options is not None else None


def load(target: str | Callable) -> Callable:
    """The function ``"package.module:function"`` names, its module imported now (a function
    is its own target)."""
    if callable(target):
        return target
    module, _, name = target.partition(":")
    return getattr(importlib.import_module(module), name)


_RENDERERS: dict[str, Renderer] = {}


def register_renderer(name: str, target, samples_itself: bool = False, description: str = "",
                      **capabilities) -> Renderer:
    """Make ``name`` a value of ``RenderSettings.renderer`` (and of a scene file's
    ``renderer`` key, the command line's ``--renderer`` and the Render menu)."""
    unknown = set(capabilities) - set(Renderer.__dataclass_fields__)
    if unknown:
        raise TypeError(f"unknown renderer capabilities: {', '.join(sorted(unknown))}")
    capabilities.setdefault("label", name)
    entry = Renderer(name, target, samples_itself, description, **capabilities)
    _RENDERERS[name] = entry
    return entry


def unregister_renderer(name: str) -> None:
    """Remove ``name`` (a test's or a plug-in's renderer); the built-in ones stay registered."""
    _RENDERERS.pop(name, None)


def get_renderer(name: str) -> Renderer:
    if name not in _RENDERERS:
        raise ValueError(f"renderer must be one of {', '.join(_RENDERERS)}, not {name!r}")
    return _RENDERERS[name]


def renderer_names() -> tuple[str, ...]:
    return tuple(_RENDERERS)


def renderers() -> tuple[Renderer, ...]:
    return tuple(_RENDERERS.values())


def names_that(capability: str) -> tuple[str, ...]:
    """The renderers that can do ``capability`` (a field of :class:`Renderer`), in order."""
    return tuple(r.name for r in _RENDERERS.values() if getattr(r, capability))


def option_classes() -> tuple[type, ...]:
    """The renderers' options classes, each once, in registration order."""
    found = []
    for entry in _RENDERERS.values():
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
