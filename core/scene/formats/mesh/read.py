"""Mesh files (Wavefront OBJ, PLY, OFF, STL) read through trimesh into a :class:`Mesh`, each
format checked first by its own module; the common ASCII PLY read with numpy alone.

Takes the bytes of a mesh file and returns a Mesh: positions (V, 3), triangles (T, 3),
vertex normals when the file has them, (u, v) when it has texture coordinates, and ``closed``
when every edge is shared by exactly two triangles of opposite orientation and the enclosed
volume is positive (CCW seen from outside), so that back faces may be culled (FvDFH 15.2.4).

Why trimesh and not a parser of our own: it is well kept and already handles the corners of
these formats that a hand parser gets wrong: OBJ polygons fanned into triangles, negative
(relative) indices, ``v/vt/vn`` triplets unmerged into vertices that carry their own normal;
PLY in ASCII and both binary byte orders with any property types; binary and ASCII STL; OFF.
We call its format loaders (``trimesh.exchange.load.mesh_loaders``) directly instead of
``trimesh.load(..., force="mesh")``, because turning the loaded scene into one mesh drops the
normals the file carries (trimesh 4.x); faces that are all k-gons come back from a loader
untriangulated (trimesh's mesh constructor would fan them), so :func:`fan` does that here.

trimesh does not validate everything, and some malformed input goes through silently, so the
format's module checks its structure first and reports the line (:data:`MESH_FORMATS`, a
:class:`core.registries.Registry` of the file types by extension: ``obj``, ``ply``, ``off``,
``stl``), and the result is checked here for NaN, infinities, coordinates beyond 1e30 and
indices out of range ("vertex k has a NaN or infinite coordinate", "vertex k
has a coordinate beyond 1e+30", "triangle k refers to vertex [a, b, c], but there are V
vertices", "the file holds no triangles", "the file is empty", "not a mesh file type we
read ..."). Every trimesh exception becomes a :class:`ReaderError` naming the file ("the mesh
library could not read it: ..."). Vertices that are equal are merged into one by hashing
(:mod:`~core.scene.formats.mesh.topology`), as the course's ``.tri`` reader does.
"""

from __future__ import annotations

import contextlib
import gc
import io
import logging
from dataclasses import dataclass
from typing import Callable

import numpy as np

from core.registries import Registry, load
from core.scene.formats.errors import (MAX_COORDINATE, ReaderError, file_stem, over_budget,
                                       tolerant_of_underflow)
from core.scene.formats.mesh.topology import (drop_repeated_triangles, fan, inverse_of, is_closed,
                                              merge_vertices)
from core.scene.model import Mesh
from core.transforms import unit_rows


@dataclass(frozen=True)
class MeshFormat:
    """A mesh file type by its extension. ``check(data, file, budget) -> (data to read, the
    mesh read without the library or None)`` refuses bad files and too many triangles before
    the mesh library reads them."""

    name: str                    # the extension, ".obj"
    check: str | Callable        # "package.module:function": the format's own module
    label: str = ""
    description: str = ""


MESH_FORMATS = Registry("mesh file type")
MESH_FORMATS.register(MeshFormat(".obj", "core.scene.formats.mesh.obj:checked_obj", "OBJ",
                                 "Wavefront OBJ"))
MESH_FORMATS.register(MeshFormat(".ply", "core.scene.formats.mesh.ply:checked_ply", "PLY",
                                 "the Stanford polygon file"))
MESH_FORMATS.register(MeshFormat(".off", "core.scene.formats.mesh.off:checked_off", "OFF",
                                 "the Object File Format"))
MESH_FORMATS.register(MeshFormat(".stl", "core.scene.formats.mesh.stl:checked_stl", "STL",
                                 "stereolithography, binary or ASCII"))
MESH_EXTENSIONS = MESH_FORMATS.names()        # (".obj", ".ply", ".off", ".stl")

_QUIET = logging.NullHandler()            # added once: a logger keeps a set-like list


@contextlib.contextmanager
def _collector_paused():
    """Python's cyclic garbage collector paused while the mesh library parses: its ASCII
    loaders build a small list per row, and the collector, passing over all of them again as
    they pile up, made reading grow faster than the file (16k to 64k OFF rows: x6 with it,
    x4.5 without). The lists hold no cycles; reference counting frees them either way."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def _library_parts(data: bytes, ext: str, file: str) -> list[dict]:
    """The per-geometry kwargs (vertices, faces, ...) that trimesh's loader for ``ext`` reads."""
    from trimesh.exchange.load import mesh_loaders  # slow import: only when needed
    # trimesh logs what it could not read, with a traceback, as a warning; with no logging
    # set up Python prints that on stderr. What went wrong reaches the user as our message.
    logging.getLogger("trimesh").addHandler(_QUIET)
    try:
        with _collector_paused():
            return _loaded_parts(mesh_loaders[ext[1:]](io.BytesIO(data)))
    except Exception as error:           # trimesh raises many types; each becomes ours
        raise ReaderError(file, f"the mesh library could not read it: "
                                f"{type(error).__name__}: {error}") from None


def _loaded_parts(loaded: dict) -> list[dict]:
    """The per-geometry kwargs in what a trimesh format loader returns (one mesh or several)."""
    if "geometry" in loaded:
        return [g for g in loaded["geometry"].values() if isinstance(g, dict)]
    return [loaded]


@tolerant_of_underflow
def read_mesh(data: bytes, file: str, ext: str, budget: int | None = None) -> Mesh:
    """The mesh in ``data``, a file of type ``ext`` (``.obj``, ``.ply``, ``.off``, ``.stl``).

    ``budget`` (default: ``generators.MAX_TRIANGLES``, what a scene may hold) bounds the
    triangles; it is checked from the header, or in the pre-check's pass, before the mesh
    library reads any data.
    """
    from core.scene.generators import MAX_TRIANGLES
    budget = MAX_TRIANGLES if budget is None else budget
    ext = ext.lower()
    if ext not in MESH_FORMATS:
        raise ReaderError(file, f"not a mesh file type we read "
                                f"({', '.join(MESH_FORMATS.names())})")
    if not data.strip():
        raise ReaderError(file, "the file is empty")
    data, fast = load(MESH_FORMATS.get(ext).check)(data, file, budget)
    parts = [fast] if fast is not None else _library_parts(data, ext, file)
    positions, triangles, normals, uvs = _gathered(parts, file)
    if not triangles:
        raise ReaderError(file, "the file holds no triangles")
    positions = np.concatenate(positions)
    triangles = np.concatenate(triangles)
    _check_vertices(positions, triangles, file, budget)
    vertex_normals = _unit_normals(normals)
    # Closed or not is a property of the surface, so it is decided on merged positions even
    # where the file's per-corner normals keep its vertices apart (a flat-shaded OBJ).
    uv = np.concatenate(uvs) if all(u is not None for u in uvs) else None
    merged, inverse = merge_vertices(positions)
    if vertex_normals is None and uv is None:
        # the file's vertices may repeat (STL always does): one mesh vertex per position
        positions, triangles = merged, inverse[triangles]
    elif vertex_normals is None:
        # ... but a texture seam keeps its copies apart: merge equal (position, uv) pairs
        rows, seams = merge_vertices(np.concatenate([positions, uv], axis=1))
        positions, uv, triangles = rows[:, :3], rows[:, 3:], seams[triangles]
    triangles = drop_repeated_triangles(triangles)
    surface = (triangles if vertex_normals is None and uv is None
               else drop_repeated_triangles(inverse_of(positions, merged, inverse, triangles)))
    closed = is_closed(merged, surface)
    return Mesh(positions=positions, triangles=triangles, normals=vertex_normals, uv=uv,
                closed=closed, name=file_stem(file))


def _gathered(parts, file: str) -> tuple[list, list, list, list]:
    """Each part's positions, triangles (fanned, indexed into the parts joined), normals and
    (u, v), or None for normals or (u, v) a part lacks."""
    positions, triangles, normals, uvs = [], [], [], []
    offset = 0
    for part in parts:
        try:
            v = np.asarray(part.get("vertices", np.zeros((0, 3))), dtype=np.float64)
            f = np.asarray(part.get("faces", np.zeros((0, 3))))
            if len(f) == 0:
                continue
            if v.ndim != 2 or v.shape[1] != 3:
                raise ValueError(f"vertices have shape {v.shape}, not (V, 3)")
            if f.ndim != 2 or f.shape[1] < 3 or f.dtype.kind not in "iu":
                raise ValueError(f"faces have shape {f.shape} and type {f.dtype}, not (T, k) "
                                 f"integers with k >= 3")
            f = fan(f)
        except (TypeError, ValueError) as error:
            raise ReaderError(file, f"unexpected result from the mesh library: {error}") from None
        n = part.get("vertex_normals")
        n = np.asarray(n, dtype=np.float64) if n is not None else None
        positions.append(v)
        triangles.append(f.astype(np.int64) + offset)
        normals.append(n if n is not None and n.shape == v.shape else None)
        uvs.append(_texture_coordinates(part, len(v)))
        offset += len(v)
    return positions, triangles, normals, uvs


def _check_vertices(positions, triangles, file: str, budget: int) -> None:
    """Refuse too many triangles, vertices not finite or too far out, and indices out of range."""
    if len(triangles) > budget:                # polygons fanned into more than the header said
        raise over_budget(file, "the faces make", len(triangles), budget)
    bad = ~np.all(np.isfinite(positions), axis=1)
    if np.any(bad):
        raise ReaderError(file, f"vertex {int(np.argmax(bad))} has a NaN or infinite coordinate")
    bad = np.any(np.abs(positions) > MAX_COORDINATE, axis=1)
    if np.any(bad):
        raise ReaderError(file, f"vertex {int(np.argmax(bad))} has a coordinate beyond "
                                f"{MAX_COORDINATE:g}")
    if triangles.min() < 0 or triangles.max() >= len(positions):
        k = int(np.argmax((triangles < 0).any(axis=1) | (triangles >= len(positions)).any(axis=1)))
        raise ReaderError(file, f"triangle {k} refers to vertex {triangles[k].tolist()}, but "
                                f"there are {len(positions)} vertices")


def _unit_normals(normals: list):
    """The file's normals joined and of unit length, or None when a part has none or one is
    unusable (they are computed from the faces instead)."""
    if not all(n is not None for n in normals):
        return None
    vertex_normals = np.concatenate(normals)
    if np.all(np.isfinite(vertex_normals)):
        # scaled first, so that a normal of length 1e200 neither overflows nor underflows
        vertex_normals, lengths = unit_rows(vertex_normals)
    if not np.all(np.isfinite(vertex_normals)) or np.any(lengths == 0.0):
        return None                                # unusable: computed from the faces instead
    return vertex_normals


def _texture_coordinates(part: dict, count: int) -> np.ndarray | None:
    """The (u, v) per vertex that the mesh library found (OBJ ``vt``; PLY ``s t``/``u v``
    /``texture_u texture_v``), or None; finite values only."""
    uv = getattr(part.get("visual"), "uv", None)
    if uv is None:
        return None
    uv = np.asarray(uv, dtype=np.float64)
    if uv.shape != (count, 2) or not np.all(np.isfinite(uv)):
        return None
    return uv
