"""Scene files (TOML, read with the standard library's ``tomllib``) into a :class:`Scene`.

Takes the text of a scene file and the folder its relative paths start from; returns the
Scene: meshes from mesh files or generators (each with its transform, material and ``closed``
flag), views (a view file, inline ``[[view]]`` tables, or ``"auto"``), lights, ambient light,
background and the default shading, projection and specular form. The format is documented in
the README ("Scene files"); in short::

    name = "Torus"
    shading = "gouraud"              # wireframe | flat | gouraud | phong
    views = "auto"                   # or "file.views"; [[view]] tables may follow
    [[geometry]]
    generator = "torus"              # or file = "mesh.obj" (relative to this file)
    params = { R = 1.0, r = 0.35 }
    transform = { rotate = [-60, 0, 0] }
    material = { kd = 0.7, od = [0.2, 0.45, 0.85] }
    [[light]]
    position = [4, 6, 8]

Every key is checked: an unknown key, a wrong type or a value out of range is a
:class:`ReaderError` naming the key's path (``geometry[2].material.kd``, tables counted from 1
as they appear in the file) and its line; TOML syntax errors keep the line tomllib reports.
"""

from __future__ import annotations

import bisect
import inspect
import json
import math
import re
import tomllib
from pathlib import Path

import numpy as np

from core.scene import generators
from core.scene.formats.camera import default_lights, framing_views
from core.scene.formats.errors import (path_text, MAX_COORDINATE, ReaderError, decode_text, file_stem, printable,
                                 read_file,
                                 tolerant_of_underflow)
from core.scene.formats.mesh import (MESH_EXTENSIONS, edge_problem, merge_vertices, read_mesh,
                                    signed_volume)
from core.registry import shading_names
from core.scene.model import CREASE_ANGLE, MAX_IMAGE_SIDE, Light, Material, Mesh, Scene
from core.transforms import (apply, rotate_axis, rotate_x, rotate_y, rotate_z, scale, shear,
                             translate)
from core.camera.view import PROJECTIONS, View, load_problems, unit3
from core.registry import renderer_names
from core.settings import RASTERIZERS, SPECULAR_FORMS
from core.scene.formats.keys import (material_keys, material_readers, scene_contents,
                                     scene_readers, table_arrays, top_keys)
from core.scene.media import index_of_refraction

MAX_NUMBER = MAX_COORDINATE
MAX_ANALYTIC = 1_000_000       # spheres past the triangle budget the ray tracers take


def sphere_triangles(segments: int) -> int:
    """The triangles of a sphere's tessellation (``core.scene.primitives.tessellate``: a UV
    sphere of ``segments`` meridians and ``segments // 2`` bands, 2 s (b - 1) triangles)."""
    return 2 * segments * (max(2, segments // 2) - 1)

GEOMETRY_KEYS = ("name", "file", "generator", "params", "transform", "closed", "material",
                 "deform")              # Barr's taper, twist, bend (core/scene/deformations.py)
# Analytic primitives (the ray tracer intersects them, the z-buffer draws them tessellated):
# [[geometry]] primitive = "sphere" | "plane" with these keys.
PRIMITIVE_KEYS = ("primitive", "center", "radius", "point", "normal", "checker", "checker_color",
                  "extent", "segments")
GEOMETRY_KEYS += PRIMITIVE_KEYS
TRANSFORM_KEYS = ("scale", "shear", "rotate", "rotate_axis", "translate")
LIGHT_KEYS = ("position", "direction", "intensity", "attenuation", "attenuation_cap")
VIEW_KEYS = ("name", "vrp", "vpn", "vup", "window", "prp", "front", "back")
# The top-level and material keys: the reader's own and those the systems registered
# (core/scene/formats/keys.py: animation, the depth cue, textures, the bump demo).

Path_ = tuple            # a key path: ("geometry", 2, "material", "kd")


_BARE = re.compile(r"[A-Za-z0-9_-]+")


def _spellings(name: str) -> str:
    """A regex for the ways ``name`` may be written as a key: bare, or quoted with TOML's
    escapes (a control character as ``\\n`` or ``\\u000a``), so that a key such as
    ``"x\\ny"`` is found on its own line and never on another."""
    forms = [re.escape(f"'{name}'"), re.escape(json.dumps(name, ensure_ascii=False))]
    if _BARE.fullmatch(name):
        forms.append(re.escape(name))
    if not name.isprintable():            # control characters: any escape TOML allows
        parts = []
        for c in name:
            if c.isprintable() and c not in '"\\':
                parts.append(re.escape(c))
            else:
                code = ord(c)
                short_form = {"\n": "n", "\t": "t", "\r": "r", "\b": "b", "\f": "f",
                              '"': '"', "\\": "\\"}.get(c)
                alts = [f"u{code:04x}", f"U{code:08x}"] + ([short_form] if short_form else [])
                parts.append(r"\\(?:" + "|".join(re.escape(a) for a in alts) + ")")
        forms.append('"' + "".join(parts) + '"')
    return "|".join(forms)


class _Reader:
    """One scene file being read: its name, its text (to find lines), and its folder."""

    def __init__(self, text: str, file: str, folder: Path,
                 crease_angle: float | None = None) -> None:
        self.text = text
        self.crease_angle = crease_angle          # None: the file's, else CREASE_ANGLE
        self.file = file
        self.folder = folder
        self.notes: list[str] = []      # the systems' readers' messages (an unusable texture)
        self.state: dict = {}           # what one file's registered readers share
        self.lines = text.split("\n")
        # Indexed once, so that locating a key costs the lines of its own table, not the
        # file's: every [[view]] asks for its line, and a rescan per view was quadratic.
        self._tables = [i for i, line in enumerate(self.lines) if line.lstrip().startswith("[")]
        self._headers: dict[str, list[int]] = {}
        self.budget = generators.MAX_TRIANGLES

    # ------------------------------------------------------------------ errors and lines

    def fail(self, path: Path_, reason: str) -> ReaderError:
        where = path_text(path)
        return ReaderError(self.file, f"{where}: {reason}" if where else reason, self.locate(path))

    def _starts(self, name: str) -> list[int]:
        """The lines (0-based) of every ``[[name]]`` header, found on first use."""
        if name not in self._headers:
            header = re.compile(rf"\s*\[\[\s*{re.escape(name)}\s*\]\]")
            self._headers[name] = [i for i in self._tables if header.match(self.lines[i])]
        return self._headers[name]

    def locate(self, path: Path_) -> int | None:
        """Best-effort line of ``path``: its ``[[table]]`` block, then the key inside it."""
        start, stop = 0, len(self.lines)
        keys = list(path)
        in_block = len(keys) >= 2 and keys[0] in table_arrays() and isinstance(keys[1], int)
        if in_block:
            name, index = keys[0], keys[1]
            starts = self._starts(name)
            if len(starts) < index:
                return None
            start = starts[index - 1]
            own = re.compile(rf"\s*\[\[?\s*{re.escape(name)}\s*\.")   # [t.x] and [[t.x]]
            later = self._tables[bisect.bisect_right(self._tables, start):]
            stop = next((i for i in later if not own.match(self.lines[i])), len(self.lines))
            keys = keys[2:]
            # a nested array of tables ([[linkage.joint]] number k): its own header's block
            while len(keys) >= 2 and isinstance(keys[0], str) and isinstance(keys[1], int):
                sub = re.compile(rf"\s*\[\[\s*{re.escape(name)}\s*\.\s*"
                                 rf"(?:{_spellings(keys[0])})\s*\]\]")
                heads = [i for i in self._tables if start < i < stop and sub.match(self.lines[i])]
                if len(heads) < keys[1]:
                    break
                start = heads[keys[1] - 1]
                stop = next((i for i in self._tables if start < i < stop), stop)
                name, keys = f"{name}.{keys[0]}", keys[2:]
        elif keys:                            # a top-level key: before the first table,
            stop = self._tables[0] if self._tables else len(self.lines)
            if isinstance(keys[0], str):      # or inside its own [table] ([animation])
                own = re.compile(rf"\s*\[\s*(?:{_spellings(keys[0])})\s*\]")
                block = next((i for i in self._tables if own.match(self.lines[i])), None)
                if block is not None:
                    later = self._tables[bisect.bisect_right(self._tables, block):]
                    start, stop = block, later[0] if later else len(self.lines)
                    keys = keys[1:] or keys
        names = [k for k in keys if isinstance(k, str)]
        for name in reversed(names):          # the key itself, else the nearest enclosing one
            key = re.compile(rf"(^|[{{,\s.\[])({_spellings(name)})\s*[=\].]")
            for i in range(start, stop):
                if key.search(self.lines[i] if not _BARE.fullmatch(name) else
                              self.lines[i].split("#", 1)[0]):
                    return i + 1
        return start + 1 if in_block else None

    # ------------------------------------------------------------------ typed values

    def table(self, value, path: Path_, allowed: tuple[str, ...]) -> dict:
        if not isinstance(value, dict):
            raise self.fail(path, f"expected a table, got {_kind(value)}")
        for key in value:
            if key not in allowed:
                raise self.fail(path + (key,), f"unknown key {key!r} (allowed: {', '.join(allowed)})")
        return value

    def number(self, value, path: Path_, low: float = -MAX_NUMBER, high: float = MAX_NUMBER,
               above: float | None = None) -> float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.fail(path, f"expected a number, got {_kind(value)}")
        if isinstance(value, float) and not math.isfinite(value):
            raise self.fail(path, f"expected a finite number, got {value}")
        if not low <= value <= high:
            raise self.fail(path, f"{value!r} is out of range [{low:g}, {high:g}]")
        if above is not None and not value > above:
            raise self.fail(path, f"must be greater than {above:g}, got {value!r}")
        return float(value)

    def vector(self, value, path: Path_, length: int = 3, low: float = -MAX_NUMBER,
               high: float = MAX_NUMBER) -> tuple[float, ...]:
        if not isinstance(value, list) or len(value) != length:
            raise self.fail(path, f"expected a list of {length} numbers, got {_kind(value)}")
        return tuple(self.number(v, path + (i + 1,), low, high) for i, v in enumerate(value))

    def colour(self, value, path: Path_) -> tuple[float, float, float]:
        """An RGB list, or one colour-model table: ``{ hsv = [h, s, v] }`` (also ``rgb``,
        ``cmy``, ``hls``; hues in degrees), converted to RGB (core.scene.colours)."""
        from core.scene.colours import MODELS, to_rgb
        if not isinstance(value, dict):
            return self.vector(value, path, 3, 0.0, 1.0)
        if len(value) != 1 or next(iter(value)) not in MODELS:
            raise self.fail(path, f"a colour is [r, g, b] or one of {{ "
                                  f"{' | '.join(m + ' = [...]' for m in MODELS)} }}")
        model, numbers = next(iter(value.items()))
        numbers = self.vector(numbers, path + (model,), 3)
        try:
            return to_rgb(model, numbers)
        except ValueError as error:
            raise self.fail(path + (model,), str(error)) from None

    def string(self, value, path: Path_) -> str:
        if not isinstance(value, str):
            raise self.fail(path, f"expected a string, got {_kind(value)}")
        return value

    def choice(self, value, path: Path_, allowed: tuple[str, ...]) -> str:
        value = self.string(value, path)
        if value not in allowed:
            raise self.fail(path, f"{value!r} is not one of {', '.join(allowed)}")
        return value

    def boolean(self, value, path: Path_) -> bool:
        if not isinstance(value, bool):
            raise self.fail(path, f"expected true or false, got {_kind(value)}")
        return value

    def tables(self, value, path: Path_) -> list[dict]:
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            raise self.fail(path, f"expected [[{path[-1]}]] tables, got {_kind(value)}")
        return value

    # ------------------------------------------------------------------ the scene

    def scene(self, size: tuple[int, int] | None) -> Scene:
        doc = self.parsed_document()
        self.table(doc, (), top_keys())
        # the notes' 0 <= k <= 1 for ka, kd, ks, unless the file lifts it (up to 10)
        self.unbounded = "coefficients" in doc and self.choice(
            doc["coefficients"], ("coefficients",), ("notes", "unbounded")) == "unbounded"
        contents = [key for key in scene_contents() if key in doc]   # a [[volume]] alone
        if "geometry" not in doc and not contents:
            also = "".join(f" or [[{key}]]" for key in scene_contents())
            raise self.fail((), f"a scene needs at least one [[geometry]]{also} table")
        if self.crease_angle is None:
            self.crease_angle = (self.number(doc["crease_angle"], ("crease_angle",), 0.0, 180.0)
                                 if "crease_angle" in doc else CREASE_ANGLE)
        self.analytic = []
        meshes = self.scene_meshes(doc) if "geometry" in doc else []
        scene = Scene(name=self.string(doc.get("name", file_stem(self.file)), ("name",)),
                      meshes=meshes, views=[], lights=[], source=self.file,
                      crease_angle=self.crease_angle)
        if meshes or self.analytic:
            self.frame(doc, scene, [])
        # Spheres join scene.primitives (every ray caster traces them); planes stay with their
        # tessellation only (the exact ray caster knows spheres and tori; the ray tracer finds
        # planes through Mesh.tessellates).
        from core.scene.primitives import Sphere
        scene.primitives = list({id(m.tessellates): m.tessellates for m in meshes
                                 if isinstance(m.tessellates, Sphere)}.values()) + self.analytic
        scene.untessellated = list(self.analytic)
        self.scene_options(doc, scene, size)
        for entry in scene_readers():                         # the systems' keys
            entry.read(self, doc, scene)
        if not (meshes or self.analytic):       # framed by what the systems' tables hold
            self.frame(doc, scene, [bounds(scene) for key, bounds in scene_contents().items()
                                    if key in contents])
        scene.messages += self.notes
        return scene

    def frame(self, doc: dict, scene: Scene, more: list) -> None:
        """The views and the lights, from the scene's meshes, its untessellated spheres and
        ``more`` points (the extent of a volume): "auto" frames them, default lights light them."""
        meshes = scene.meshes
        points = np.concatenate([m.positions for m in meshes] + [
            np.array([np.subtract(s.center, s.radius), np.add(s.center, s.radius)])
            for s in self.analytic] + [np.asarray(p, np.float64).reshape(-1, 3) for p in more])
        order = self.views(doc, points)
        scene.view_order = order
        scene.views = [v for v in order if isinstance(v, View)]
        scene.view_messages = [v for v in order if not isinstance(v, View)]
        emitters = any(any(m.material.emission) for m in meshes)     # area lights light it
        scene.lights = ([self.light(t, ("light", i + 1))
                         for i, t in enumerate(self.tables(doc["light"], ("light",)))]
                        if "light" in doc else [] if emitters else default_lights(points))

    def parsed_document(self) -> dict:
        """The file as TOML, or a ReaderError that names the line."""
        prescan(self.text, self.file)
        try:
            return tomllib.loads(self.text)
        except tomllib.TOMLDecodeError as error:
            last = max(1, self.text.count("\n") + (not self.text.endswith("\n")))
            raise _toml_error(error, self.file, last) from None
        except RecursionError:
            raise ReaderError(self.file, "TOML nesting too deep") from None
        except ValueError as error:        # int() inside tomllib: more than 4300 digits
            raise ReaderError(self.file, f"TOML: a number cannot be read: "
                                         f"{str(error).split(':')[0]}",
                              _long_number_line(self.text)) from None

    def scene_meshes(self, doc: dict) -> list[Mesh]:
        """Every [[geometry]] table's meshes, the scene's triangles kept to the limit. A sphere
        whose tessellation would pass the limit is kept analytic only (:attr:`analytic`: the
        ray tracers draw it; the rasterizers say they leave it out), up to
        :data:`MAX_ANALYTIC` of them."""
        meshes, total = [], 0
        self.analytic = []
        for i, g in enumerate(self.tables(doc["geometry"], ("geometry",))):
            self.budget = generators.MAX_TRIANGLES - total     # what a mesh file may still add
            if "primitive" in g:             # a sphere or plane: its tessellation, 1-2 meshes
                found = self.primitive(g, ("geometry", i + 1), room=self.budget)
                if not isinstance(found, list):
                    self.analytic.append(found)
                    if len(self.analytic) > MAX_ANALYTIC:
                        raise self.fail(("geometry", i + 1), f"more than {MAX_ANALYTIC:,} "
                                        f"spheres past the triangle budget: the ray tracer "
                                        f"traces at most {MAX_ANALYTIC:,} analytic spheres")
                    continue
                meshes.extend(found)
            else:
                meshes.append(self.geometry(g, ("geometry", i + 1)))
            # Each generator keeps to the limit; the scene as a whole must too, or a short
            # file listing many big generators could take all the memory.
            total += len(meshes[-1].triangles)
            if total > generators.MAX_TRIANGLES:
                raise self.fail(("geometry", i + 1), f"the scene would have {total} triangles "
                                f"by here; the limit is {generators.MAX_TRIANGLES}")
        if not meshes and not self.analytic:
            raise self.fail(("geometry",), "a scene needs at least one [[geometry]] table")
        return meshes

    def scene_options(self, doc: dict, scene: Scene, size: tuple[int, int] | None) -> None:
        """The scene-wide keys (ambient, background, modes, size, transparency) onto ``scene``;
        ``size``, when given, wins over the file's."""
        for key, read in (("ambient", lambda v, p: self.vector(v, p, 3, 0.0, 10.0)),
                          ("background", self.colour),
                          ("line_color", self.colour),
                          ("shading", lambda v, p: self.choice(v, p, shading_names())),
                          ("projection", lambda v, p: self.choice(v, p, PROJECTIONS)),
                          ("specular", lambda v, p: self.choice(v, p, SPECULAR_FORMS)),
                          ("keep_aspect", self.boolean),
                          ("rasterizer", lambda v, p: self.choice(v, p, RASTERIZERS)),
                          ("renderer", lambda v, p: self.choice(v, p, renderer_names())),
                          ("tone", lambda v, p: self.choice(v, p, ("linear", "srgb")))):
            if key in doc:
                setattr(scene, key, read(doc[key], (key,)))
        if "size" in doc:
            w, h = self.vector(doc["size"], ("size",), 2, 1, MAX_IMAGE_SIDE)
            if w != int(w) or h != int(h):
                raise self.fail(("size",), "expected whole numbers of pixels")
            scene.size = (int(w), int(h))
        if size is not None:
            scene.size = tuple(size)
        if "transparency" in doc:
            from core.settings import TRANSPARENCIES
            scene.transparency = self.choice(doc["transparency"], ("transparency",),
                                             TRANSPARENCIES)

    def geometry(self, g, path: Path_) -> Mesh:
        self.table(g, path, GEOMETRY_KEYS)
        if ("file" in g) == ("generator" in g):
            raise self.fail(path, "give exactly one of 'file' or 'generator'")
        if "params" in g and "generator" not in g:
            raise self.fail(path + ("params",), "params belong to a generator")
        mesh = self.mesh_file(g["file"], path + ("file",)) if "file" in g else \
            self.generate(g["generator"], g.get("params", {}), path)
        if "transform" in g or "deform" in g:
            mesh = self.transform(mesh, g.get("transform", {}), path + ("transform",),
                                  g.get("deform"), path + ("deform",))
        if not np.all(np.abs(mesh.positions) <= MAX_NUMBER):
            raise self.fail(path, f"the geometry reaches coordinates beyond {MAX_NUMBER:g}")
        if "closed" in g:
            closed = self.boolean(g["closed"], path + ("closed",))
            if closed:
                # decided on merged positions (per-corner normals may keep vertices apart)
                merged, inverse = merge_vertices(mesh.positions)
                why = edge_problem(inverse[mesh.triangles])
                if why is None and signed_volume(merged, inverse[mesh.triangles]) <= 0.0:
                    why = ("its faces wind inward (signed volume <= 0), so culling would keep "
                           "the inside")
                if why is not None:
                    raise self.fail(path + ("closed",), f"the mesh is not closed: {why}")
            mesh.closed = closed
        if "material" in g:
            mesh.material = self.material(g["material"], path + ("material",), mesh.material)
        if "name" in g:
            mesh.name = self.string(g["name"], path + ("name",))
        if mesh.normals is not None or not len(mesh.triangles):
            return mesh                  # nothing to split (and numba stays unimported: lines)
        from core.scene.normals import with_creases      # (numba: only when a mesh is read)
        return with_creases(mesh, self.crease_angle)     # after the transform: its angles

    def mesh_file(self, value, path: Path_) -> Mesh:
        name = self.string(value, path)
        target = self.folder / name
        ext = target.suffix.lower()
        if ext not in MESH_EXTENSIONS + (".tri",):
            raise self.fail(path, f"{name!r}: not a mesh file type we read "
                                  f"({', '.join(MESH_EXTENSIONS + ('.tri',))})")
        shown = str(Path(self.file).parent / name)
        try:
            data = read_file(target, shown, "tri" if ext == ".tri" else "mesh")
            if ext == ".tri":
                from core.scene.formats.tri import read_tri_mesh
                return read_tri_mesh(data, shown, self.budget)
            return read_mesh(data, shown, ext, self.budget)
        except ReaderError as error:
            raise ReaderError(error.file, f"{error.reason} (the mesh of {path_text(path[:2])} "
                                          f"in {self.file})", error.line) from None

    def generate(self, name, params, path: Path_) -> Mesh:
        name = self.choice(name, path + ("generator",), tuple(generators.GENERATORS))
        make = generators.GENERATORS[name]
        params = self.table(params, path + ("params",),
                            tuple(inspect.signature(make).parameters))
        try:
            return make(**params)
        except (TypeError, ValueError) as error:
            raise self.fail(path + ("params",), f"{name}: {error}") from None

    def transform(self, mesh: Mesh, value, path: Path_, deform=None, deform_path=()) -> Mesh:
        """S, then the shears, R_x, R_y, R_z (degrees), the rotation about an axis, then T;
        normals by the inverse transpose. ``deform`` (Barr's deformations) acts between the
        shears and the rotations: in the object's own frame, at its own size."""
        t = self.table(value, path, TRANSFORM_KEYS)
        factor = t.get("scale", 1.0)
        if isinstance(factor, list):
            s = self.vector(factor, path + ("scale",), 3, -1e6, 1e6)
        else:
            s = (self.number(factor, path + ("scale",), -1e6, 1e6),) * 3
        if any(abs(c) < 1e-6 for c in s):
            raise self.fail(path + ("scale",), "a scale factor is zero (or below 1e-6 in size)")
        rx, ry, rz = self.vector(t.get("rotate", [0, 0, 0]), path + ("rotate",), 3, -1e6, 1e6)
        tx, ty, tz = self.vector(t.get("translate", [0, 0, 0]), path + ("translate",), 3)
        placed = (translate(tx, ty, tz) @ self.axis_rotation(t, path)
                  @ rotate_z(np.radians(rz)) @ rotate_y(np.radians(ry)) @ rotate_x(np.radians(rx)))
        sized = self.shears(t, path) @ scale(*s)
        if deform is None:
            return _moved(mesh, placed @ sized)
        return _moved(self.deform(_moved(mesh, sized), deform, deform_path), placed)

    def deform(self, mesh: Mesh, value, path: Path_) -> Mesh:
        """Barr's deformations in order, each refused where it would turn the mesh inside out."""
        from core.scene.deformations import deformed, folds, read_deformations
        for i, d in enumerate(read_deformations(self, value, path)):
            why = folds(mesh.positions, d)
            if why is not None:
                raise self.fail(path + (i + 1,), why)
            mesh.positions, mesh.normals = deformed(mesh.positions, mesh.normals, d)
        return mesh

    def shears(self, t: dict, path: Path_) -> np.ndarray:
        """``shear = { xy = [shx, shy], xz = [shx, shz], yz = [shy, shz] }`` (FvDFH's SH_xy:
        x and y move by z; likewise by y and by x)."""
        if "shear" not in t:
            return np.eye(4)
        sh = self.table(t["shear"], path + ("shear",), ("xy", "xz", "yz"))
        pairs = {k: self.vector(sh[k], path + ("shear", k), 2, -1e6, 1e6) for k in sh}
        return shear(**pairs)

    def axis_rotation(self, t: dict, path: Path_) -> np.ndarray:
        """``rotate_axis = { axis = [x, y, z], angle = degrees, point = [x, y, z] }``: about
        the line through ``point`` (default the origin) along ``axis``."""
        if "rotate_axis" not in t:
            return np.eye(4)
        where = path + ("rotate_axis",)
        r = self.table(t["rotate_axis"], where, ("axis", "angle", "point"))
        for key in ("axis", "angle"):
            if key not in r:
                raise self.fail(where, f"needs '{key}'")
        axis = self.vector(r["axis"], where + ("axis",), 3, -1e6, 1e6)
        angle = self.number(r["angle"], where + ("angle",), -1e6, 1e6)
        point = self.vector(r.get("point", [0, 0, 0]), where + ("point",), 3)
        try:
            return rotate_axis(axis, np.radians(angle), point)
        except ValueError as error:
            raise self.fail(where + ("axis",), str(error)) from None

    def material(self, value, path: Path_, base: Material) -> Material:
        t = self.table(value, path, material_keys())
        fields = {}
        for key in ("ka", "kd", "ks"):
            if key in t:
                fields[key] = self.number(t[key], path + (key,), 0.0, 10.0)
                if fields[key] > 1.0 and not getattr(self, "unbounded", False):
                    raise self.fail(path + (key,), f"{key} = {fields[key]:g} is outside the "
                                    f"notes' 0 <= {key} <= 1 (it would reflect more light than "
                                    f"falls on it); coefficients = \"unbounded\" at the top "
                                    f"of the file allows up to 10")
        if "n" in t:
            fields["n"] = self.number(t["n"], path + ("n",), 0.0, 1e4, above=0.0)
        for key in ("od", "os"):
            if key in t:
                fields[key] = self.colour(t[key], path + (key,))
        fields.update(self.whitted_terms(t, path))
        if "emission" in t:       # finite and >= 0 (NaN fails the range check)
            fields["emission"] = self.vector(t["emission"], path + ("emission",), 3, 0.0, 1e6)
        if "two_sided" in t:
            fields["two_sided"] = self.boolean(t["two_sided"], path + ("two_sided",))
        material = Material(**{**base.__dict__, **fields})
        for entry in material_readers():                      # the systems' keys
            material = entry.read(self, t, path, material)
        return material

    # ------------------------------------------------------------------ ray tracing

    def whitted_terms(self, t: dict, path: Path_) -> dict:
        """``kr``, ``kt`` in [0, 1] and ``ior``: a positive number or a medium's name."""
        fields = {}
        for key in ("kr", "kt"):
            if key in t:
                fields[key] = self.number(t[key], path + (key,), 0.0, 1.0)
        if "ior" in t:
            try:
                fields["ior"] = index_of_refraction(t["ior"], "ior")
            except ValueError as error:
                raise self.fail(path + ("ior",), str(error).removeprefix("ior: ")) from None
        return fields

    def primitive(self, g, path: Path_, room: float = math.inf):
        """``primitive = "sphere"`` (center, radius) or ``"plane"`` (point, normal, checker,
        checker_color, extent): the primitive, drawn by its tessellation's meshes; a sphere
        whose tessellation has more than ``room`` triangles is returned itself, untessellated
        (the ray tracers draw it exactly)."""
        from core.scene.primitives import Plane, Sphere, tessellate
        self.table(g, path, ("primitive", "name", "material", "segments") + {
            "sphere": ("center", "radius"),
            "plane": ("point", "normal", "checker", "checker_color", "extent")}.get(
                g["primitive"] if isinstance(g["primitive"], str) else "", ()))
        kind = self.choice(g["primitive"], path + ("primitive",), ("sphere", "plane"))
        material = (self.material(g["material"], path + ("material",), Material())
                    if "material" in g else Material())
        segments = self.number(g.get("segments", 96), path + ("segments",), 8, 1024)
        if segments != int(segments):
            raise self.fail(path + ("segments",), f"expected a whole number, got {segments!r}")
        if kind == "sphere":
            # the tessellation's (and every generator's) range of lengths
            shape = Sphere(self.vector(g.get("center", [0, 0, 0]), path + ("center",)),
                           self.number(g.get("radius", 1.0), path + ("radius",),
                                       *generators.LENGTH_RANGE), material)
        else:
            # kept as a unit vector, scaled first: [0, 1e-320, 0] is a direction, and a plain
            # norm of it underflows to zero (the plane then drew nothing)
            normal, length = unit3(self.vector(g.get("normal", [0, 1, 0]), path + ("normal",)))
            if length == 0.0:
                raise self.fail(path + ("normal",), "the plane's normal is the zero vector")
            shape = Plane(self.vector(g.get("point", [0, 0, 0]), path + ("point",)),
                          tuple(float(c) for c in normal), material,
                          self.number(g.get("checker", 0.0), path + ("checker",), 0.0, MAX_NUMBER),
                          self.vector(g.get("checker_color", [0.1, 0.1, 0.1]),
                                      path + ("checker_color",), 3, 0.0, 1.0),
                          self.number(g.get("extent", 20.0), path + ("extent",), 1e-6, 1e6))
            # (2 extent / checker)² squares, compared without dividing (1e-300 would overflow)
            if shape.checker > 0.0 and 2 * shape.extent > 1000.0 * shape.checker:
                raise self.fail(path + ("checker",), "over a million checker squares: make the "
                                "squares bigger or the extent smaller")
        if kind == "sphere" and sphere_triangles(int(segments)) > room:
            if "name" in g:
                self.string(g["name"], path + ("name",))      # checked all the same
            return shape
        meshes = tessellate(shape, int(segments))
        if not all(np.all(np.abs(m.positions) <= MAX_NUMBER) for m in meshes):
            raise self.fail(path, f"the primitive reaches coordinates beyond {MAX_NUMBER:g}")
        for mesh in meshes:
            if "name" in g:
                mesh.name = self.string(g["name"], path + ("name",))
        return meshes

    def light(self, value, path: Path_) -> Light:
        t = self.table(value, path, LIGHT_KEYS)
        if ("position" in t) == ("direction" in t):
            raise self.fail(path, "give exactly one of 'position' (a point light) or "
                                  "'direction' (towards a directional light)")
        light = Light(intensity=self.vector(t.get("intensity", [1, 1, 1]), path + ("intensity",),
                                            3, 0.0, 1e6))
        if "position" in t:
            light.position = self.vector(t["position"], path + ("position",))
        else:
            direction, length = unit3(self.vector(t["direction"], path + ("direction",)))
            if length == 0.0:
                raise self.fail(path + ("direction",), "the direction is zero")
            # stored as a unit vector (scaled first): a direction of 1e-300 is a direction,
            # and the renderer's plain norm of it would underflow to zero
            light.direction = tuple(float(c) for c in direction)
        if "attenuation" in t:
            light.attenuation = self.vector(t["attenuation"], path + ("attenuation",), 3, 0.0)
            if not any(light.attenuation):
                raise self.fail(path + ("attenuation",), "c1, c2 and c3 are all zero")
        if "attenuation_cap" in t:
            if not isinstance(t["attenuation_cap"], bool):
                raise self.fail(path + ("attenuation_cap",),
                                "must be true (FvDFH's min(1, f_att)) or false (the notes' "
                                f"f_att uncapped), not {t['attenuation_cap']!r}")
            light.attenuation_cap = t["attenuation_cap"]
        return light

    def views(self, doc: dict, points: np.ndarray) -> list[View | str]:
        """Every view in order (the view file's, then the [[view]] tables): the View when
        valid, its message when not."""
        order: list[View | str] = []
        source = doc.get("views", "auto" if "view" not in doc else None)
        if source is not None:
            source = self.string(source, ("views",))
            if source == "auto":
                order += framing_views(points, self.file)
            else:
                shown = str(Path(self.file).parent / source)
                try:
                    text = decode_text(read_file(self.folder / source, shown, "views"), shown)
                except ReaderError as error:
                    raise self.fail(("views",), str(error)) from None
                from core.scene.formats.viewfile import read_view_entries
                order += read_view_entries(text, shown)
        if "view" in doc:
            for i, t in enumerate(self.tables(doc["view"], ("view",))):
                view, problem = self.inline_view(t, ("view", i + 1))
                order.append(problem or view)
        return order

    def inline_view(self, value, path: Path_) -> tuple[View, str | None]:
        t = self.table(value, path, VIEW_KEYS)
        for key in VIEW_KEYS[1:]:
            if key not in t:
                raise self.fail(path, f"missing key {key!r} (a view needs "
                                      f"{', '.join(VIEW_KEYS[1:])})")
        label = f"{printable(self.file, 200)}: view {path[1]}"
        if "name" in t:
            label += f" ({printable(self.string(t['name'], path + ('name',)), 80)})"
        line = self.locate(path)
        view = View(vrp=self.vector(t["vrp"], path + ("vrp",)),
                    vpn=self.vector(t["vpn"], path + ("vpn",)),
                    vup=self.vector(t["vup"], path + ("vup",)),
                    window=self.vector(t["window"], path + ("window",), 4),
                    prp=self.vector(t["prp"], path + ("prp",)),
                    front=self.number(t["front"], path + ("front",)),
                    back=self.number(t["back"], path + ("back",)),
                    label=label + (f" (line {line})" if line else ""))
        found = load_problems(view)
        return view, (f"{view.label}: " + "; ".join(found)) if found else None


@tolerant_of_underflow
def read_scene_file(data: bytes | str, file: str, folder: Path | None = None,
                    size: tuple[int, int] | None = None,
                    crease_angle: float | None = None) -> Scene:
    """The scene in the TOML text ``data``; relative paths start at ``folder``;
    ``crease_angle`` (degrees) overrides the file's ``crease_angle`` key."""
    text = decode_text(data, file) if isinstance(data, bytes) else data
    folder = Path(folder) if folder is not None else Path(file).parent
    return _Reader(text, file, folder, crease_angle).scene(size)


# Bounds checked before tomllib sees the text. A scene needs keys four deep
# (geometry.material.od) and a few dozen keys per table; tomllib's cost grows with the square
# of a dotted key's length (20,000 parts: 23 s and 1.7 GB), so longer chains are refused.
MAX_KEY_PARTS = 16
MAX_NESTING = 64                 # [ and { open at once
MAX_KEYS = 1_000_000             # key = value pairs and table headers in one file
_STRING_OR_COMMENT = re.compile(r'''"""(?:[^\\]|\\.)*?"""|\'\'\'.*?\'\'\'|"(?:[^"\\\n]|\\.)*"|'[^'\n]*'|#[^\n]*''',
                                re.S)
_DOTS = re.compile(r"\s*\.\s*")
# A chain of more than MAX_KEY_PARTS bare parts, tried only at the start of a word and without
# backtracking (possessive), so that the scan stays linear in the text.
_LONG_KEY = re.compile(r"(?<![A-Za-z0-9_-])[A-Za-z0-9_-]++(?:[ \t]*+\.[ \t]*+[A-Za-z0-9_-]++){%d,}"
                       % MAX_KEY_PARTS)


def prescan(text: str, file: str) -> None:
    """Refuse, before parsing, a key of more than MAX_KEY_PARTS dotted parts, brackets nested
    deeper than MAX_NESTING, or more than MAX_KEYS keys: one linear pass over the text with
    strings and comments blanked out (a quoted key counts as one part)."""
    bare = _STRING_OR_COMMENT.sub(lambda m: ("s" if m.group(0)[0] in "\"'" else "")
                                  + "\n" * m.group(0).count("\n"), text)
    keys = bare.count("=") + bare.count("[")
    if keys > MAX_KEYS:
        raise ReaderError(file, f"TOML: {keys} keys and tables; a scene may have at most "
                                f"{MAX_KEYS}")
    for m in _LONG_KEY.finditer(bare):
        parts = len(_DOTS.findall(m.group(0))) + 1
        raise ReaderError(file, f"TOML: a dotted key of {parts} parts; keys here have at most "
                                f"{MAX_KEY_PARTS}", _line_of(text, bare, m.start()))
    depth = 0
    for bracket in re.finditer(r"[\[\]{}]", bare):
        if bracket.group() in "[{":
            depth += 1
            if depth > MAX_NESTING:
                raise ReaderError(file, f"TOML: brackets nested more than {MAX_NESTING} deep",
                                  _line_of(text, bare, bracket.start()))
        else:
            depth = max(depth - 1, 0)


def _line_of(text: str, bare: str, at: int) -> int:
    """The line of offset ``at`` of ``bare`` (blanking keeps every line break)."""
    return bare.count("\n", 0, at) + 1


def _long_number_line(text: str) -> int | None:
    m = re.search(r"[0-9_]{4300}", text)
    return text.count("\n", 0, m.start()) + 1 if m else None


def _toml_error(error: tomllib.TOMLDecodeError, file: str, last_line: int) -> ReaderError:
    """tomllib's message with its '(at line L, column C)' turned into our FILE:LINE: form."""
    message = str(error)
    at = re.search(r"\s*\(at line (\d+), column (\d+)\)", message)
    if at:
        return ReaderError(file, f"TOML: {message[:at.start()]} (column {at.group(2)})",
                           int(at.group(1)))
    end = re.search(r"\s*\(at end of document\)", message)
    if end:
        return ReaderError(file, f"TOML: {message[:end.start()]} (at the end of the file)",
                           last_line)
    return ReaderError(file, f"TOML: {message}")


def _moved(mesh: Mesh, m: np.ndarray) -> Mesh:
    """``mesh`` by the 4 x 4 ``m``: normals by the inverse transpose, a mirror rewound."""
    mesh.positions = apply(m, mesh.positions)[:, :3]
    if mesh.normals is not None:
        normals = mesh.normals @ np.linalg.inv(m[:3, :3])         # rows: n' = M^-T n
        mesh.normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    if np.linalg.det(m[:3, :3]) < 0:                              # a mirror turns winding over
        mesh.triangles = mesh.triangles[:, [0, 2, 1]]
    return mesh


def _kind(value) -> str:
    """How a TOML value is described in a message."""
    if isinstance(value, bool):
        return f"a boolean ({str(value).lower()})"
    if isinstance(value, (int, float)):
        return f"a number ({value!r})"
    if isinstance(value, str):
        return f"a string ({value[:30]!r})"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__

