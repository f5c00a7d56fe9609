"""Shading modes by name: a shader is a vertex step and a pixel step (tinyrenderer's split).

A :class:`Shader` says which per-vertex values (*varyings*) it needs carried through the
clipper, does its per-face or per-vertex work in world coordinates (``vertex``), and turns the
visibility buffer into colours (``pixel``). The z-buffer knows nothing about light; a new way
of shading (textured, bump-mapped) is one new module that registers one more shader.

``register_shader(shader)`` adds one; ``get_shader(name)`` finds one (a ``ValueError`` names
the modes there are); ``shader_names()`` lists them. A mode's module registers its shader the
first time the mode is looked up: :func:`core.registry.register_shading` names the module
(the built-in ones: :mod:`core.shading.modes`). The shaders are a
:class:`core.registries.Registry` (the one shape of every registry) whose loader imports
those modules; a shader's functions are its own, as its module is imported lazily.
"""

from __future__ import annotations

import importlib
from typing import Callable, NamedTuple

from core.registries import Registry


class Shader(NamedTuple):
    """``vertex(s, scene, meshes, weighting, context)`` fills the :class:`ShadeInput` ``s``
    (``s.vertex_attrs`` ``(V, width)`` for the clipper, or ``s.face_rgb``);
    ``pixel(s, vis, triangles, attrs, source, background8, out)`` writes ``out`` ``(H, W, 3)``
    uint8 for every pixel, the background where ``vis.tri`` is -1."""

    name: str
    vertex: Callable
    pixel: Callable
    varyings: tuple[str, ...] = ()      # what the clipper carries, in column order
    width: int = 0                      # columns of vertex_attrs (sum of the varyings' sizes)
    description: str = ""
    # True: the pixel step reads vis.planes (core.pipeline.derivatives), the barycentrics'
    # screen derivatives (texture footprints, bump offsets); set up only for such shaders.
    needs_derivatives: bool = False
    # False: the pixel step reads only vis.tri, so the rasterizer may skip the barycentrics
    # (flat shading: a quarter of the rast's time on a real scan at 1580 x 1080).
    barycentrics: bool = True
    # How many items (faces, vertices) the vertex step lights when it lights them all, for a
    # scene: the z-buffer weighs it against the picture's pixels to decide whether to light
    # only the visible ones (core.shading.shade.defers_lighting); None: it lights per pixel.
    lit_items: Callable | None = None
    label: str = ""                     # its words in listings ("": its name)


def _load(name: str | None) -> None:
    """Import the module of shading mode ``name`` (None: of every mode), which registers its
    shader, on the first lookup: a scene can be read and a wireframe drawn without numba."""
    from core.registry import shading_modes
    for mode in shading_modes():
        if mode.module and (name is None or mode.name == name):
            importlib.import_module(mode.module)


SHADERS = Registry("shading", _load)


def register_shader(shader: Shader) -> None:
    SHADERS.register(shader if shader.label else shader._replace(label=shader.name))


def unregister_shader(name: str) -> None:
    SHADERS.unregister(name)


def get_shader(name: str) -> Shader:
    return SHADERS.get(name)


def shader_names() -> tuple[str, ...]:
    return SHADERS.names()
