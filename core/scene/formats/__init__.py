"""Readers: every file the viewer opens becomes a :class:`core.scene.Scene` here.

:func:`load_scene` takes a path (or ``-`` for standard input) and dispatches on the extension:

- ``.toml``: a scene file (:mod:`core.scene.formats.scenefile`);
- ``.tri``: the course's triangle file with its pixel-grid camera (:mod:`core.scene.formats.tri`);
- ``.obj`` ``.ply`` ``.off`` ``.stl``: a mesh file (:mod:`core.scene.formats.mesh`), shown from
  three views that frame its bounding box (:mod:`core.scene.formats.camera`);
- ``.gltf`` ``.glb``: a glTF 2.0 scene, its meshes, materials, cameras and lights
  (:mod:`core.scene.formats.gltf`);
- anything else: a bare view file (Assignment #1's input), shown with the FvDFH house;
- ``-``: a view file on standard input (the course's ``prog < grade.data``).

Bad input of any kind raises :class:`ReaderError` (a ``ValueError``) whose message names the
file, the line where there is one, and the reason. Invalid views do not raise: they are
listed in ``Scene.view_messages`` and the valid ones still load.
"""

from __future__ import annotations

import sys
from numbers import Integral      # (core.scene.formats.numbers would shadow the module name)
from pathlib import Path

from core.scene.formats.errors import (MAX_INPUT_BYTES, ReaderError, decode_text, read_file,
                                      read_stream, tolerant_of_underflow)
from core.scene.formats.mesh import MESH_EXTENSIONS, read_mesh

GLTF_EXTENSIONS = (".gltf", ".glb")   # core.scene.formats.gltf (imported when one is read)
from core.scene.formats.scenefile import read_scene_file
from core.scene.formats.tri import read_tri
from core.scene.model import CREASE_ANGLE, MAX_IMAGE_SIDE, Scene

__all__ = ["MAX_INPUT_BYTES", "ReaderError", "load_scene", "read_mesh", "read_scene_file", "read_tri",
           "MESH_EXTENSIONS"]

STDIN = "-"


def load_scene(source: str | Path, size: tuple[int, int] | None = None,
               crease_angle: float | None = None) -> Scene:
    """The scene in ``source``; ``size`` (width, height) overrides the scene's image size.

    Meshes without normals of their own have their vertices split where faces meet at more
    than ``crease_angle`` degrees (:func:`core.scene.normals.with_creases`; default: the scene
    file's ``crease_angle`` key, else ``CREASE_ANGLE``, 45).

    For a ``.tri`` file ``size`` is the image its camera's pixel grid spans (500 x 500 unless
    given), so it changes the window of the view as well.
    """
    name = str(source)
    if size is not None:
        size = _size(size, name)
    if name == STDIN:
        stream = getattr(sys.stdin, "buffer", sys.stdin)    # bytes, so junk is reported
        text = decode_text(read_stream(stream, "<stdin>", "views"), "<stdin>")
        return _views_scene(text, "<stdin>", size)
    path = Path(source)
    ext = path.suffix.lower()
    data = read_file(path, name, input_kind(ext))
    if crease_angle is not None and not (0.0 <= crease_angle <= 180.0):
        raise ReaderError(name, f"the crease angle must be from 0 to 180 degrees, "
                                f"not {crease_angle!r}")
    if ext == ".toml":
        return read_scene_file(data, name, path.parent, size, crease_angle)
    angle = CREASE_ANGLE if crease_angle is None else float(crease_angle)
    if ext == ".tri":
        scene = read_tri(data, name, size)
    elif ext in MESH_EXTENSIONS:
        scene = _mesh_scene(read_mesh(data, name, ext), name, size)
    elif ext in GLTF_EXTENSIONS:
        from core.scene.formats.gltf import read_gltf
        scene = read_gltf(data, name, path.parent, size)
    else:
        return _views_scene(decode_text(data, name), name, size)
    from core.scene.normals import with_creases
    scene.meshes = [with_creases(m, angle) for m in scene.meshes]
    scene.crease_angle = angle
    return scene


def input_kind(ext: str) -> str:
    """Which input-size limit (``errors.MAX_INPUT_BYTES``) a file with extension ``ext`` has."""
    return {".toml": "scene", ".tri": "tri"}.get(
        ext, "mesh" if ext in MESH_EXTENSIONS + GLTF_EXTENSIONS else "views")


def _size(size, name: str) -> tuple[int, int]:
    try:
        width, height = size
        whole = all(isinstance(s, Integral) and not isinstance(s, bool)
                    for s in (width, height))
    except (TypeError, ValueError):
        whole = False
    if not whole:
        raise ReaderError(name, f"the image size must be two whole numbers, got {size!r}")
    if not (1 <= width <= MAX_IMAGE_SIDE and 1 <= height <= MAX_IMAGE_SIDE):
        raise ReaderError(name, f"the image size {width} x {height} is outside "
                                f"1..{MAX_IMAGE_SIDE}")
    return int(width), int(height)


@tolerant_of_underflow
def _mesh_scene(mesh, name: str, size) -> Scene:
    """A bare mesh file: framing views, default lights, flat shading (the menu picks another)."""
    from core.scene.formats.camera import default_lights, framing_views
    return Scene(name=mesh.name, meshes=[mesh], views=framing_views(mesh.positions, name),
                 lights=default_lights(mesh.positions), ambient=(0.15, 0.15, 0.15),
                 background=(0.1, 0.1, 0.12), shading="flat", size=size or (500, 500),
                 source=name)


def _views_scene(text: str, name: str, size) -> Scene:
    """A bare view file: its views of the FvDFH house, in wireframe."""
    from core.scene.generators import house
    from core.camera.view import View
    from core.scene.formats.viewfile import read_view_entries
    order = read_view_entries(text, name)
    return Scene(name="house", meshes=[house()], views=[v for v in order if isinstance(v, View)],
                 view_messages=[v for v in order if not isinstance(v, View)], view_order=order,
                 shading="wireframe", size=size or (500, 500), source=name)
