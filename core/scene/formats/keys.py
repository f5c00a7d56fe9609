"""Scene-file keys that the systems above the reader bring: each system registers what it reads.

The scene reader (``scenefile.py``) knows the keys of the scene itself — geometry, views,
lights, materials' Phong and Whitted terms, the default settings. A system that adds keys
(animation's ``[animation]``, ``[[key]]`` and ``[[emitter]]``; the depth cue's table; the
textures of a material; the bump demo's panel view) registers a reader for them here when its
module is imported, and the reader only routes the keys to whoever registered them — as
Mitsuba's loader routes a table to the plugin that registered its type name. So nothing in
``core/scene`` imports a package above it; ``core/systems.py`` imports the systems once.

- :func:`register_scene_keys`: top-level keys (``arrays``: those written ``[[name]]``) and
  ``read(reader, doc, scene)``, called once per file after the scene's own keys are read,
  whether or not the file has the keys (a reader may add to every scene: the demo's panel).
- :func:`register_material_keys`: keys inside a ``material`` table and
  ``read(reader, table, path, material) -> material``, called for every material.

A reader gets the scene reader itself: its checks (``fail``, ``number``, ``vector``,
``string``, ``choice``, ``table``, ``tables``, ``boolean``), ``file`` and ``folder``, a
``notes`` list whose lines become the scene's messages, and ``state``, a dict for what one
file's readers share (the textures' texel budget). A reader is the function itself or
``"package.module:function"``, imported when first called.

The scene keys, the material keys and the scene contents are each a
:class:`core.registries.Registry` (the one shape of every registry), by the name each system
registers under.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from core.registries import Registry, load


@dataclass(frozen=True)
class SceneKeys:
    name: str                    # the system that reads them ("animation")
    keys: tuple[str, ...]
    arrays: tuple[str, ...]
    target: str | Callable       # read(reader, doc, scene)
    label: str = ""
    description: str = ""

    def read(self, reader, doc, scene) -> None:
        load(self.target)(reader, doc, scene)


@dataclass(frozen=True)
class MaterialKeys:
    name: str
    keys: tuple[str, ...]
    target: str | Callable       # read(reader, table, path, material) -> material
    label: str = ""
    description: str = ""

    def read(self, reader, table, path, material):
        return load(self.target)(reader, table, path, material)


@dataclass(frozen=True)
class SceneContents:
    name: str                    # the top-level table array ("volume")
    bounds: Callable             # bounds(scene) -> (n, 3) world points
    label: str = ""
    description: str = ""


SCENE_KEYS = Registry("scene keys")
MATERIAL_KEYS = Registry("material keys")
CONTENTS = Registry("scene contents")


def _taken(registry: Registry, name: str, own: tuple[str, ...]) -> set[str]:
    """The keys read already: the reader's own and those of every other entry."""
    return set(own) | {k for entry in registry.entries() if entry.name != name
                       for k in entry.keys}


def register_scene_keys(name: str, keys: tuple[str, ...], read: str | Callable,
                        arrays: tuple[str, ...] = ()) -> None:
    """``read(reader, doc, scene)`` for the top-level ``keys`` (registered again under the
    same ``name``, it replaces the earlier reader: a module reloaded in a test)."""
    clash = sorted(set(keys) & _taken(SCENE_KEYS, name, _OWN_TOP_KEYS))
    if clash:
        raise ValueError(f"scene keys {clash} are read elsewhere already")
    SCENE_KEYS.register(SceneKeys(name, tuple(keys), tuple(arrays), read, label=name))


def register_material_keys(name: str, keys: tuple[str, ...], read: str | Callable) -> None:
    """``read(reader, table, path, material) -> material`` for the material ``keys``."""
    clash = sorted(set(keys) & _taken(MATERIAL_KEYS, name, _OWN_MATERIAL_KEYS))
    if clash:
        raise ValueError(f"material keys {clash} are read elsewhere already")
    MATERIAL_KEYS.register(MaterialKeys(name, tuple(keys), read, label=name))


def register_scene_contents(key: str, bounds: Callable) -> None:
    """A top-level table array that draws something by itself (the ``[[volume]]``), so that a
    scene of it alone, with no ``[[geometry]]``, is read; ``bounds(scene) -> (n, 3)`` world
    points it spans (for the framing views and the default lights), called after the
    systems' readers have run."""
    CONTENTS.register(SceneContents(key, bounds, label=key))


def scene_contents() -> dict[str, Callable]:
    """key → bounds of every :func:`register_scene_contents`."""
    return {entry.name: entry.bounds for entry in CONTENTS.entries()}


_COLOUR_IMAGE: list[Callable] = []


def register_colour_image(make: Callable) -> None:
    """How a format whose files carry images (glTF's base colour texture) makes one a
    material's colour map: ``make(material, pixels, factor, source, state) -> material``,
    ``pixels`` ``(h, w, 4)`` uint8 sRGB as stored (row 0 the top), ``factor`` the linear RGB
    it is multiplied by, ``state`` a dict kept for one file (its texel budget); a ValueError
    says why it cannot (the texture system registers it)."""
    _COLOUR_IMAGE[:] = [make]


def colour_image_maker() -> Callable | None:
    """The registered :func:`register_colour_image` function, or None."""
    return _COLOUR_IMAGE[0] if _COLOUR_IMAGE else None


_NORMAL_IMAGE: list[Callable] = []


def register_normal_image(make: Callable) -> None:
    """How a format makes an image a material's tangent-space normal map (glTF's
    ``normalTexture``): ``make(material, pixels, scale, source, state) -> material``,
    ``pixels`` as for :func:`register_colour_image` but linear data (x = 2 r − 1 along
    ∂P/∂u, y along ∂P/∂v, z along the normal), ``scale`` the factor of x and y (glTF's
    ``normalTexture.scale``); a ValueError says why it cannot."""
    _NORMAL_IMAGE[:] = [make]


def normal_image_maker() -> Callable | None:
    """The registered :func:`register_normal_image` function, or None."""
    return _NORMAL_IMAGE[0] if _NORMAL_IMAGE else None


def scene_readers() -> tuple[SceneKeys, ...]:
    return SCENE_KEYS.entries()


def material_readers() -> tuple[MaterialKeys, ...]:
    return MATERIAL_KEYS.entries()


def top_keys() -> tuple[str, ...]:
    """Every top-level key a scene file may have: the reader's own and the registered."""
    return _OWN_TOP_KEYS + tuple(k for entry in SCENE_KEYS.entries() for k in entry.keys)


def table_arrays() -> tuple[str, ...]:
    return _OWN_ARRAYS + tuple(k for entry in SCENE_KEYS.entries() for k in entry.arrays)


def material_keys() -> tuple[str, ...]:
    return _OWN_MATERIAL_KEYS + tuple(k for entry in MATERIAL_KEYS.entries() for k in entry.keys)


# The reader's own keys (scenefile.py reads them); registered ones may not take their names.
_OWN_TOP_KEYS = ("name", "shading", "projection", "specular", "size", "ambient", "background",
                 "line_color", "views", "view", "geometry", "light", "keep_aspect",
                 "rasterizer", "renderer", "crease_angle", "tone", "transparency",
                 "coefficients")
_OWN_ARRAYS = ("geometry", "light", "view")          # written [[geometry]], [[light]], [[view]]
_OWN_MATERIAL_KEYS = ("ka", "kd", "ks", "n", "od", "os",
                      "kr", "kt", "ior",              # Whitted's global terms
                      "emission", "two_sided")        # area lights (radiosity, path tracing)
