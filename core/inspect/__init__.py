"""See inside every pixel: the pixel inspector's front door, above :mod:`core.render`.

- :func:`inspect_pixel` asks the renderer that draws ``settings.renderer`` for the record of
  one pixel: the ``inspect_pixel(scene, view, settings, x, y, context) -> dict`` its registry
  entry names (``inspector``, in the renderer's package; the record carries at least
  ``renderer``, ``pixel`` and ``color``, the pixel on 0–255 as ``render`` writes it). An
  inspector that shows the frame as the front door draws it (effects laid over) takes the
  front door as its keyword ``render``: the renderers sit below :mod:`core.render` and do not
  import it. Where the entry names none, :class:`NotInspectable` says so.
- :mod:`core.inspect.buffers`: the buffer views (render passes): depth, normal, triangle id,
  barycentrics, (u, v), MIP level, overdraw, ray-tree depth.
- :mod:`core.inspect.compare`: a picture held against the reference, pixel by pixel.

Nothing here runs unless asked: a frame drawn without the inspector pays nothing for it.
"""

from __future__ import annotations

from inspect import Parameter, signature

from core.camera.view import ViewError, problems
from core.context import DEFAULT_CONTEXT
from core.registry import load
from core.render import lit_as_asked, render
from core.renderers import get_renderer


class NotInspectable(ValueError):
    """The pixel cannot be inspected: the renderer has no inspector, the pixel is outside the
    frame, the view is invalid. The message says which."""


def inspector_of(name: str):
    """The ``inspect_pixel`` that renderer ``name``'s entry names, imported now (None: it
    names none)."""
    entry = get_renderer(name)
    return None if entry.inspector is None else load(entry.inspector)


def takes_render(inspect) -> bool:
    """Whether the inspector asks for the front door (a keyword-only ``render``)."""
    found = signature(inspect).parameters.get("render")
    return found is not None and found.kind is Parameter.KEYWORD_ONLY


def inspect_pixel(scene, view, settings, x: int, y: int, context=None) -> dict:
    """The record of image pixel ``(x, y)`` (x right, y down, row 0 at the top) of the frame
    ``render(scene, view, settings)`` draws. Raises :class:`NotInspectable` with a message."""
    try:
        inspect = inspector_of(settings.renderer)
    except ValueError as error:
        raise NotInspectable(str(error)) from None
    if inspect is None:
        raise NotInspectable(f"the {settings.renderer} renderer has no pixel inspector "
                             f"(its registry entry names none)")
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
        front_door = {"render": render} if takes_render(inspect) else {}
        return inspect(lit_as_asked(scene, settings, context), view, settings, int(x), int(y),
                       context, **front_door)
    except ValueError as error:            # what the renderer cannot inspect, in its words
        raise NotInspectable(f"{settings.renderer}: {error}") from None
