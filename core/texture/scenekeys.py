"""The scene file's texture keys, inside a ``material`` table (registered with the scene reader).

::

    material = { kd = 0.8, texture = "wood.png" }                 # an image, sRGB, repeat
    material = { texture = { file = "wood.png", wrap = "mirror" } }
    material = { texture = { procedural = "checker", scale = 8 } }  # core.texture.procedural
    material = { bump = { procedural = "bricks_height", rows = 8 }, bump_scale = 0.03 }
    material = { normal_map = "normals.png" }                      # tangent space, not sRGB
    material = { environment = { procedural = "sky" }, reflectivity = 0.6 }
    material = { uv_scale = [4, 4] }                               # (u, v) multiplied first
    material = { bump_demo = { map = 0, bump = true, viewpoint = [50, -50, 50] } }

A texture value is a file name (relative to the scene file) or a table with ``file`` or
``procedural`` (plus ``wrap``: repeat | clamp | mirror; ``srgb`` for files; the procedural
texture's own parameters). Keys and types are checked like every other key (a message naming
the key and its line). A texture *file* that cannot be used — missing, not an image, corrupt,
over 16384 texels on a side, past the scene's texel budget — is not an error of the scene: the message names the file and the
key, goes into ``SurfaceMaps.messages`` (the reader shows it), and the mesh is drawn without it.
A procedural past the budget is an error of the scene (its ``resolution`` is the file's own).
"""

from __future__ import annotations

import numpy as np

from core.scene.formats.keys import (register_colour_image, register_material_keys,
                                     register_normal_image, register_scene_keys)
from core.texture import procedural
from core.texture.image import TexelBudget, TextureError, load_image
from core.texture.material import MAPS_KEY, DemoMaterial, SurfaceMaps
from core.texture.demo_scene import MAPS, panel_views
from core.texture.modes import WRAPS

TEXTURE_KEYS = ("texture", "bump", "bump_scale", "normal_map", "environment", "reflectivity",
                "uv_scale", "bump_demo")
_FILE_KEYS = ("file", "wrap", "srgb")
_DEMO_KEYS = ("map", "bump", "viewpoint")
_ROLES = {"texture": ("color", True), "bump": ("height", False),
          "normal_map": ("normal_map", False), "environment": ("environment", True)}


def read_maps(reader, table: dict, path: tuple) -> SurfaceMaps | None:
    """The :class:`SurfaceMaps` of a material table (None when it names no texture key).

    ``reader`` is the scene reader (its ``fail``, ``number``, ``vector``, ``string``,
    ``choice``, ``table``, ``boolean`` checks, ``folder``/``file``, and in its ``state`` the
    :class:`core.texture.image.TexelBudget` every texture of the scene draws from).
    """
    if not any(key in table for key in TEXTURE_KEYS):
        return None
    maps = SurfaceMaps()
    for key, (role, srgb) in _ROLES.items():
        if key in table:
            setattr(maps, role, _texture(reader, table[key], path + (key,), srgb, maps))
    if "bump_scale" in table:
        maps.bump_scale = reader.number(table["bump_scale"], path + ("bump_scale",), -1e3, 1e3)
    if "reflectivity" in table:
        maps.reflectivity = reader.number(table["reflectivity"], path + ("reflectivity",),
                                          0.0, 1.0)
    if "uv_scale" in table:
        maps.uv_scale = reader.vector(table["uv_scale"], path + ("uv_scale",), 2, -1e6, 1e6)
    if "bump_demo" in table:
        maps.demo = _demo(reader, table["bump_demo"], path + ("bump_demo",))
    return maps


def _texture(reader, value, path: tuple, srgb: bool, maps: SurfaceMaps):
    from core.scene.formats.errors import path_text
    key = path_text(path)
    if isinstance(value, str):
        value = {"file": value}
    if not isinstance(value, dict):
        raise reader.fail(path, "expected a file name or a table (file = … or procedural = …)")
    if ("file" in value) == ("procedural" in value):
        raise reader.fail(path, "give exactly one of 'file' or 'procedural'")
    wrap = reader.choice(value.get("wrap", "repeat"), path + ("wrap",), tuple(WRAPS))
    if "file" in value:
        reader.table(value, path, _FILE_KEYS)
        name = reader.string(value["file"], path + ("file",))
        srgb = reader.boolean(value.get("srgb", srgb), path + ("srgb",))
        shown = f"{reader.file}: {name}" if not name.startswith("/") else name
        try:
            return load_image(reader.folder / name, key, wrap=wrap, srgb=srgb, shown=shown,
                              budget=_budget(reader))
        except TextureError as error:
            maps.messages.append(str(error))
            return None
    name = reader.choice(value["procedural"], path + ("procedural",), tuple(procedural.PROCEDURALS))
    allowed = ("procedural", "wrap") + procedural.parameters(name)
    params = {k: v for k, v in reader.table(value, path, allowed).items()
              if k not in ("procedural", "wrap")}
    try:
        params = procedural.check_parameters(name, params)
    except procedural.ParameterError as error:
        raise reader.fail(path + (error.key,), str(error)) from None
    resolution = params.get("resolution", procedural.DEFAULT_RESOLUTION)
    over = _budget(reader).take(resolution * resolution,
                                f"{name} at resolution {resolution}")
    if over:
        raise reader.fail(path + ("resolution",), over)
    return procedural.make(name, wrap=wrap, **params)



def _demo(reader, value, path: tuple) -> DemoMaterial:
    t = reader.table(value, path, _DEMO_KEYS)
    demo = DemoMaterial()
    if "map" in t:
        number = reader.number(t["map"], path + ("map",), 0, MAPS - 1)
        if number != int(number):
            raise reader.fail(path + ("map",), "expected a whole number")
        demo.bump_map = int(number)
    if "bump" in t:
        demo.bump = reader.boolean(t["bump"], path + ("bump",))
    if "viewpoint" in t:
        demo.viewpoint = reader.vector(t["viewpoint"], path + ("viewpoint",))
    return demo


def _budget(reader) -> TexelBudget:
    """What the textures of the file being read may still hold (one budget per file)."""
    return reader.state.setdefault("texel_budget", TexelBudget())


def read_material(reader, table: dict, path: tuple, material):
    """A material's textures ride on ``Material.extra["maps"]``; a file that cannot be used
    leaves the mesh untextured, and its message (naming file and key) is the scene's."""
    maps = read_maps(reader, table, path)
    if maps is not None:
        material.extra = {**material.extra, "maps": maps}
        reader.notes.extend(maps.messages)
    return material


def add_panel_view(reader, doc: dict, scene) -> None:
    """The bump demo's panel: the file's first view when a material is the demo's."""
    panel = panel_views(scene)
    scene.views = panel + scene.views
    if scene.view_order:
        scene.view_order = panel + list(scene.view_order)


register_material_keys("textures", TEXTURE_KEYS, read_material)
register_scene_keys("bump demo panel", (), add_panel_view)


def with_colour_image(material, pixels, factor, source: str, state: dict):
    """``material`` with the image ``pixels`` ``(h, w, 4)`` uint8 sRGB (row 0 the top) as its
    colour map times the linear RGB ``factor`` (glTF's base colour: the decoded texel times
    the factor), repeated and mipmapped. Raises TextureError past the file's texel budget
    (kept in ``state``, one dict per file)."""
    import dataclasses

    # decoded a band of rows at a time, as an image file is (never the whole image in float64)
    texture = _budgeted_texture(pixels, True, source, state)
    for level in texture.levels:      # linear, and the mipmaps are means: scale each level
        level[..., :3] *= np.asarray(factor, np.float32)[:3]
    maps = SurfaceMaps(color=texture)
    return dataclasses.replace(material, extra={**material.extra, MAPS_KEY: maps})


register_colour_image(with_colour_image)


def _budgeted_texture(pixels, srgb: bool, source: str, state: dict):
    """A repeating, mipmapped texture of the glTF image ``pixels`` ``(h, w, c)`` uint8 (row 0
    the top), its texels taken from the file's budget (``state``; TextureError past it)."""
    from core.texture.image import Texture
    h, w = pixels.shape[:2]
    over = state.setdefault("budget", TexelBudget()).take(w * h, f"the image ({w} x {h})")
    if over:
        raise TextureError(over)
    return Texture.from_array(pixels[::-1], wrap="repeat", srgb=srgb, divisor=255.0,
                              source=source)


def with_normal_image(material, pixels, scale, source: str, state: dict):
    """``material`` with the image ``pixels`` ``(h, w, 4)`` uint8 (row 0 the top; linear
    data) as its tangent-space normal map, x and y times ``scale`` (glTF's
    ``normalize((2 t − 1) · (scale, scale, 1))``), repeated and mipmapped; its colour map,
    if any, kept. Raises TextureError past the file's texel budget (``state``)."""
    import dataclasses

    texture = _budgeted_texture(pixels, False, source, state)
    # the shader reads n = 2 t − 1: t' = scale t + (1 − scale) / 2 gives scale (2 t − 1);
    # linear in t, so exact on the mip levels' means too (the shader normalises after)
    for level in texture.levels:
        level[..., :2] = scale * level[..., :2] + (1.0 - scale) / 2.0
    maps = material.extra.get(MAPS_KEY) or SurfaceMaps()
    maps = dataclasses.replace(maps, normal_map=texture)
    return dataclasses.replace(material, extra={**material.extra, MAPS_KEY: maps})


register_normal_image(with_normal_image)
