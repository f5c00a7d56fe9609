"""See inside every pixel: the pixel inspector's front door, above :mod:`core.render`.

- :func:`inspect_pixel` asks the renderer that draws ``settings.renderer`` for the record of
  one pixel: its module's ``inspect_pixel(scene, view, settings, x, y, context) -> dict`` (the
  contract every renderer may meet; the record carries at least ``renderer``, ``pixel`` and
  ``color``, the pixel on 0–255 as ``render`` writes it). Where a renderer's module has none
  yet, a fallback of this package stands in (:data:`FALLBACKS`); where there is neither,
  :class:`NotInspectable` says so.
- :mod:`core.inspect.buffers`: the buffer views (render passes): depth, normal, triangle id,
  barycentrics, (u, v), MIP level, overdraw, ray-tree depth.
- :mod:`core.inspect.compare`: a picture held against the reference, pixel by pixel.

Nothing here runs unless asked: a frame drawn without the inspector pays nothing for it.
"""

from __future__ import annotations

import importlib

from core.camera.view import ViewError, problems
from core.context import DEFAULT_CONTEXT
from core.render import lit_as_asked
from core.renderers import get_renderer

# The inspectors that live here, for renderers whose module defines none: those that draw the
# frame through the front door (the painters', radiosity's) sit above core.render, and the
# records that follow a renderer's kernels from outside (raytrace, raycast). A renderer's
# own inspect_pixel wins.
FALLBACKS = {"raytrace": "core.inspect.raytrace:inspect_pixel",
             "raycast": "core.inspect.raycast:inspect_pixel",
             "bsp": "core.inspect.painters:inspect_pixel",
             "depth-sort": "core.inspect.painters:inspect_pixel",
             "radiosity": "core.inspect.radiosity:inspect_pixel"}


class NotInspectable(ValueError):
    """The pixel cannot be inspected: the renderer has no inspector, the pixel is outside the
    frame, the view is invalid. The message says which."""


def renderer_module(name: str):
    """The module of the registered renderer ``name`` (None for a bare function)."""
    target = get_renderer(name).target
    if callable(target):
        return importlib.import_module(target.__module__)
    return importlib.import_module(target.partition(":")[0])


def inspector_of(name: str):
    """The ``inspect_pixel`` of renderer ``name``: its module's, else a fallback, else None."""
    found = getattr(renderer_module(name), "inspect_pixel", None)
    if found is inspect_pixel:               # a module that imported this front door's
        found = None
    if found is None and name in FALLBACKS:
        module, _, function = FALLBACKS[name].partition(":")
        found = getattr(importlib.import_module(module), function)
    return found


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The record of image pixel ``(x, y)`` (x right, y down, row 0 at the top) of the frame
    ``render(scene, view, settings)`` draws. Raises :class:`NotInspectable` with a message."""
    try:
        inspect = inspector_of(settings.renderer)
    except ValueError as error:
        raise NotInspectable(str(error)) from None
    if inspect is None:
        raise NotInspectable(f"the {settings.renderer} renderer has no pixel inspector "
                             f"(its module defines no inspect_pixel)")
    width, height = settings.size
    if not (0 <= x < width and 0 <= y < height):
        raise NotInspectable(f"pixel ({x}, {y}) is outside the {width} x {height} frame "
                             f"(x from 0 to {width - 1}, y from 0 to {height - 1})")
    if view is None:
        raise NotInspectable(f"{scene.name}: no valid view to inspect")
    try:
        (context or DEFAULT_CONTEXT).normalizing_transform(view, settings.projection)
    except ViewError:
        raise NotInspectable(f"{view.label}: invalid for {settings.projection} projection: "
                             + "; ".join(problems(view, settings.projection))) from None
    try:
        context = context or DEFAULT_CONTEXT
        return inspect(lit_as_asked(scene, settings, context), view, settings, int(x), int(y),
                       context)
    except ValueError as error:            # what the renderer cannot inspect, in its words
        raise NotInspectable(f"{settings.renderer}: {error}") from None
