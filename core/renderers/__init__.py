"""Renderers behind :func:`core.render.render`, found by name (``RenderSettings.renderer``).

A renderer is a function ``draw(scene, view, settings, frame, context)`` that fills
``frame.color`` (every pixel) for a view already checked to be valid, and records what it did
in ``frame.stats``. It may draw one sample per pixel only: the front door runs it once per film
sample when ``settings.samples > 1`` unless it says it samples pixels itself
(``samples_itself=True``, as a ray caster does).

Registered here by module path, so that choosing a renderer imports it (and its compiled
kernels) only when it is first used.

- ``zbuffer``: the FvDFH pipeline, lines and triangles (:mod:`core.renderers.zbuffer`);
- ``bsp``, ``depth-sort``: the painter's algorithms (:mod:`core.renderers.painters`);
- ``raycast``: the exact analytic surfaces of ``scene.primitives`` (:mod:`core.renderers.raycast`).
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Renderer:
    name: str
    target: str | Callable          # "package.module:function", or the function itself
    samples_itself: bool = False    # True: it places the film's samples itself
    description: str = ""

    def function(self) -> Callable:
        if callable(self.target):
            return self.target
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)


_RENDERERS: dict[str, Renderer] = {}


def register_renderer(name: str, target, samples_itself: bool = False,
                      description: str = "") -> None:
    """Make ``name`` a value of ``RenderSettings.renderer``."""
    _RENDERERS[name] = Renderer(name, target, samples_itself, description)


def get_renderer(name: str) -> Renderer:
    if name not in _RENDERERS:
        raise ValueError(f"renderer must be one of {', '.join(_RENDERERS)}, not {name!r}")
    return _RENDERERS[name]


def renderer_names() -> tuple[str, ...]:
    return tuple(_RENDERERS)


register_renderer("zbuffer", "core.renderers.zbuffer:draw",
                  description="the FvDFH viewing pipeline: clip, project, scan-line z-buffer")
register_renderer("raycast", "core.renderers.raycast:draw", samples_itself=True,
                  description="the analytic surfaces ray-cast exactly (the reference)")
register_renderer("raytrace", "core.raytrace.renderer:draw", samples_itself=True,
                  description="Whitted ray tracing: shadows, mirrors, glass (core.raytrace)")
register_renderer("radiosity", "core.radiosity.renderer:draw",
                  description="radiosity (hemicube or ray-cast form factors, progressive "
                              "refinement), drawn Gouraud by the z-buffer (core.radiosity)")
register_renderer("pathtrace", "core.pathtrace.renderer:draw", samples_itself=True,
                  description="Kajiya's rendering equation by path tracing on the BVH "
                              "(core.pathtrace)")
register_renderer("bsp", "core.renderers.painters:draw_bsp",
                  description="a BSP tree built once in world space, painted back to front")
register_renderer("depth-sort", "core.renderers.painters:draw_depth_sort",
                  description="Newell, Newell and Sancha's depth sort, painted back to front")
