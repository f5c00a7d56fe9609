"""glTF 2.0 scenes: a ``.glb``, or a ``.gltf`` with its buffers beside it.

trimesh reads the meshes (its glTF loader: accessors, buffers, node transforms); the JSON's
cameras and ``KHR_lights_punctual`` lights, which trimesh does not keep, are read here from
the same document. What becomes what:

- **Meshes**: every triangle mesh of the default scene, its node transform applied (the
  scene graph flattened: an instanced mesh becomes one mesh per instance); closed (culled)
  when watertight. Points and lines are left out, and said.
- **Materials** (metallic–roughness): :mod:`core.scene.formats.gltf_materials` maps them to
  Cook–Torrance (FvDFH 16.7), the base colour texture to the colour map and the normal
  texture to the normal map (by the texture system), emission, alpha and occlusion. An image
  over ``MAX_TEXTURE_SIDE`` on a side is refused from its header before its pixels are
  decoded (an image file beside the glTF before trimesh opens it, an embedded one before its
  pixels are read: Pillow's bomb limit); one that cannot be opened leaves the factor, said.
- **Cameras** become course views: the VRP a distance ``d`` in front of the eye (the scene's
  centre's depth), VPN the camera's +z (it looks down −z), VUP its +y, PRP ``(0, 0, d)``;
  perspective: the window ``± d tan(yfov/2)`` high and ``aspectRatio`` times that wide (the
  picture's aspect when absent); orthographic: ``± xmag, ± ymag``; ``znear``/``zfar`` give F
  and B (a missing ``zfar``: just past the scene).
- **Lights** (``KHR_lights_punctual``): a point light at its node; a spot light as a point
  light (no cone: said); a directional light along its node's −z. Each shines at its colour
  (glTF's photometric intensity is not mapped to the course's 0..1 intensities).

A file without cameras gets the framing views (as a bare mesh file does), one without lights
the default lights.
"""

from __future__ import annotations

import io
import json
import struct
import warnings
from pathlib import Path

import numpy as np

from core.scene.formats.errors import ReaderError
from core.scene.model import Light, Material, Mesh

GLB_MAGIC = b"glTF"
MAX_ITEMS = 100_000          # nodes, meshes, accessors … a file may list (10^6 nodes: refused)


def document(data: bytes, name: str) -> dict:
    """The glTF JSON of a ``.gltf`` file or of a ``.glb``'s first chunk."""
    if data[:4] == GLB_MAGIC:
        if len(data) < 20:
            raise ReaderError(name, "a .glb shorter than its 20-byte header")
        length, kind = struct.unpack_from("<I4s", data, 12)
        if kind != b"JSON" or 20 + length > len(data):
            raise ReaderError(name, "a .glb whose first chunk is not its JSON")
        text = data[20:20 + length]
    else:
        text = data
    try:
        doc = json.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as error:
        raise ReaderError(name, f"not glTF JSON ({error})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("asset"), dict) \
            or str(doc["asset"].get("version", "")).split(".")[0] != "2":
        raise ReaderError(name, "not a glTF 2.0 file (asset.version must be 2.x)")
    for part in ("nodes", "meshes", "accessors", "buffers", "images", "cameras"):
        found = doc.get(part, [])
        if not isinstance(found, list):
            raise ReaderError(name, f"{part} must be a list")
        if len(found) > MAX_ITEMS:
            raise ReaderError(name, f"{len(found):,} {part}; at most {MAX_ITEMS:,}")
    return doc


def node_matrices(doc: dict) -> dict[int, np.ndarray]:
    """Each node of the default scene's graph: its world matrix (parents first)."""
    nodes = doc.get("nodes", [])
    scenes = doc.get("scenes", [])
    roots = scenes[int(doc.get("scene", 0))].get("nodes", []) if scenes else range(len(nodes))
    world: dict[int, np.ndarray] = {}
    stack = [(int(r), np.eye(4)) for r in roots]
    while stack:
        index, parent = stack.pop()
        if index in world or not 0 <= index < len(nodes):
            continue                                  # a cycle or a bad index: once, or never
        world[index] = parent @ _local(nodes[index])
        stack.extend((int(c), world[index]) for c in nodes[index].get("children", []))
    return world


def _local(node: dict) -> np.ndarray:
    if "matrix" in node:
        return np.array(node["matrix"], dtype=np.float64).reshape(4, 4).T   # column-major
    t = np.eye(4)
    t[:3, 3] = node.get("translation", (0.0, 0.0, 0.0))
    x, y, z, w = node.get("rotation", (0.0, 0.0, 0.0, 1.0))
    r = np.eye(4)
    r[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                 [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                 [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    s = np.diag([*node.get("scale", (1.0, 1.0, 1.0)), 1.0])
    return t @ r @ s


def read_gltf(data: bytes, name: str, folder: Path, size) -> "Scene":
    """The scene of a glTF file (see the module's text for what becomes what)."""
    from core.scene.formats.camera import default_lights, framing_views
    from core.scene.generators import MAX_TRIANGLES
    from core.scene.model import Scene
    doc = document(data, name)
    notes: list[str] = []
    meshes = _meshes(data, name, folder, doc, notes)
    total = sum(len(m.triangles) for m in meshes)
    if total > MAX_TRIANGLES:
        raise ReaderError(name, f"{total:,} triangles; at most {MAX_TRIANGLES:,}")
    if not meshes:
        raise ReaderError(name, "no triangle mesh in the glTF's scene")
    points = np.concatenate([m.positions for m in meshes])
    world = node_matrices(doc)
    size = size or (500, 500)
    views, view_messages = _views(doc, world, points, size, name)
    lights = _lights(doc, world, notes)
    projection = _projection(doc, world, notes)
    scene = Scene(name=Path(name).stem, meshes=meshes, projection=projection,
                  views=views or framing_views(points, name), view_messages=view_messages,
                  lights=lights or default_lights(points), shading="phong", size=size,
                  source=name, background=(0.1, 0.1, 0.12), ambient=(0.15, 0.15, 0.15))
    scene.messages += notes
    return scene


def _check_uris(doc: dict, folder: Path, name: str, roles: dict[int, str]) -> None:
    """Every external buffer and image a regular file inside the glTF's own folder (a URI
    of ``../../etc/passwd`` reads nothing), within the mesh files' size limit; ``roles``
    names what each image is (the metallic-roughness texture of materials[0])."""
    from urllib.parse import unquote

    from core.scene.formats.errors import MAX_INPUT_BYTES
    limit = MAX_INPUT_BYTES["mesh"]
    home = folder.resolve()
    for kind in ("buffers", "images"):
        for index, item in enumerate(doc.get(kind, [])):
            uri = item.get("uri") if isinstance(item, dict) else None
            if not isinstance(uri, str) or uri.startswith("data:"):
                continue
            target = (folder / unquote(uri)).resolve()
            where = f"{kind}[{index}] {uri!r}" + (f" ({roles[index]})" if kind == "images"
                                                    and index in roles else "")
            if home not in target.parents:
                raise ReaderError(name, f"{where} lies outside the file's folder: not read")
            if not target.is_file():
                raise ReaderError(name, f"{where}: no such file beside it"
                                  if not target.exists() else f"{where}: not a regular file")
            if target.stat().st_size > limit:
                raise ReaderError(name, f"{where} has {target.stat().st_size:,} bytes; at "
                                        f"most {limit:,}")
            if kind == "images":
                _check_image_size(target, where, name)


def _check_image_size(path: Path, where: str, name: str) -> None:
    """An image file's size from its header, before anything decodes it: a PNG of a few
    hundred bytes may say 20000 x 20000 (a decompression bomb)."""
    from PIL import Image

    from core.scene.formats.errors import MAX_TEXTURE_SIDE
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as image:
                w, h = image.size
    except Image.DecompressionBombError as error:
        raise ReaderError(name, f"{where}: too large ({error})") from None
    except Exception:                  # not an image Pillow reads: trimesh leaves it out
        return
    if max(w, h) > MAX_TEXTURE_SIDE:
        raise ReaderError(name, f"{where} is {w} x {h}; textures may be at most "
                                f"{MAX_TEXTURE_SIDE} on a side")


def _meshes(data: bytes, name: str, folder: Path, doc: dict, notes: list) -> list[Mesh]:
    import trimesh
    from PIL import Image

    from core.scene.formats import gltf_materials
    factors = gltf_materials.read_factors(doc, name)
    _check_uris(doc, folder, name, gltf_materials.image_roles(factors))
    glb = data[:4] == GLB_MAGIC
    resolver = trimesh.resolvers.FilePathResolver(str(folder) + "/")
    try:
        with warnings.catch_warnings():      # Pillow's bomb warning an error: trimesh then
            # leaves such an image out (said below) rather than decode it
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            loaded = trimesh.load(io.BytesIO(gltf_materials.tagged(data, doc, glb)),
                                  file_type="glb" if glb else "gltf", process=False,
                                  resolver=resolver, force="scene")
    except Exception as error:        # trimesh raises many kinds for a broken file
        raise ReaderError(name, f"the glTF's meshes cannot be read ({type(error).__name__}: "
                                f"{error})") from None
    meshes, skipped = [], 0
    said = gltf_materials.Notes(name)
    made = _Materials(name, factors, said)
    for node in sorted(loaded.graph.nodes_geometry):
        matrix, geometry = loaded.graph[node]
        part = loaded.geometry[geometry]
        if not isinstance(part, trimesh.Trimesh) or len(part.faces) == 0:
            skipped += 1
            continue
        material, uv = made.of(part.visual)
        if material is None:                  # alphaMode MASK below its cutoff
            continue
        positions = np.asarray(part.vertices, np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
        triangles = np.asarray(part.faces, np.int64)
        if np.linalg.det(matrix[:3, :3]) < 0:             # a mirror turns the winding over
            triangles = triangles[:, [0, 2, 1]]
        meshes.append(Mesh(positions=positions, triangles=triangles, material=material,
                           name=str(node), closed=bool(part.is_watertight), uv=uv))
    if skipped:
        notes.append(f"{name}: {skipped} point or line primitives left out (triangles only)")
    notes.extend(said.lines())
    if _has_tangents(doc) and made.normal_maps:
        notes.append(f"{name}: TANGENT is not read: the normal maps' tangents are derived from "
                     f"TEXCOORD_0")
    return meshes


def _has_tangents(doc: dict) -> bool:
    return any(isinstance(p, dict) and "TANGENT" in (p.get("attributes") or {})
               for m in doc.get("meshes", []) if isinstance(m, dict)
               for p in m.get("primitives", []) or [])


class _Materials:
    """Our material of each JSON material (made once; its maps once with texture
    coordinates, once without), the colour and normal maps made by the texture system
    (through :func:`core.scene.formats.keys.register_colour_image` and
    :func:`~core.scene.formats.keys.register_normal_image`)."""

    def __init__(self, name: str, factors: list, notes):
        from core.scene.formats.keys import colour_image_maker, normal_image_maker
        self.name, self.factors, self.notes = name, factors, notes
        self.colour, self.normal = colour_image_maker(), normal_image_maker()
        self.made: dict = {}
        self.normal_maps = 0
        self.state = {}                # the texture system's own, for the whole file

    def of(self, visual) -> tuple[Material | None, np.ndarray | None]:
        """``(material, uv)`` of a trimesh visual: uv None where no map is drawn."""
        from core.scene.formats.gltf_materials import index_of
        pbr = getattr(visual, "material", None)
        index = index_of(pbr)
        if index is None or not 0 <= index < len(self.factors):
            return _plain(visual), None
        uv = getattr(visual, "uv", None)
        uv = None if uv is None or len(uv) == 0 else np.asarray(uv, np.float64)
        key = (index, uv is not None)
        if key not in self.made:
            self.made[key] = self._material(self.factors[index], pbr, uv is not None)
        material = self.made[key]
        mapped = material is not None and "maps" in material.extra
        return material, uv if mapped else None

    def _material(self, f, pbr, has_uv: bool) -> Material | None:
        from core.scene.formats.gltf_materials import decoded_image, material_of
        material = material_of(f, pbr, self.name, self.notes)
        if material is None or not has_uv:
            if material is not None and any(k in f.images for k in ("baseColorTexture",
                                                                     "normalTexture")):
                self.notes.add("no uv", f.label)
            return material
        image = decoded_image(pbr, "baseColorTexture", f, self.notes)
        if image is not None and self.colour is not None:
            material = self._mapped(self.colour, image, material, material.od,
                                    f"the base colour texture of {f.label}")
        image = decoded_image(pbr, "normalTexture", f, self.notes)
        if image is not None and self.normal is not None:
            material = self._mapped(self.normal, image, material, f.normal_scale,
                                    f"the normal texture of {f.label}")
            self.normal_maps += 1
        return material

    def _mapped(self, make, image, material: Material, factor, where: str) -> Material:
        from core.scene.formats.errors import MAX_TEXTURE_SIDE
        w, h = image.size
        if max(w, h) > MAX_TEXTURE_SIDE:
            raise ReaderError(self.name, f"{where} is {w} x {h}: textures may be at most "
                                         f"{MAX_TEXTURE_SIDE} on a side")
        pixels = np.asarray(image.convert("RGBA"))   # (h, w, 4) uint8, row 0 the top
        try:
            return make(material, pixels, factor, f"{self.name}: {where}", self.state)
        except ValueError as error:
            raise ReaderError(self.name, f"{where} ({w} x {h}): {error}") from None


def _plain(visual) -> Material:
    """The material of a primitive with no glTF material: its colour, else grey."""
    colour = getattr(visual, "main_color", None)
    od = tuple(float(c) / 255.0 for c in colour[:3]) if colour is not None else (0.8,) * 3
    return Material(od=od)


def _projection(doc: dict, world: dict, notes: list) -> str:
    """The scene's projection (ours is one per scene, not per view): parallel when the
    first camera is orthographic; mixed kinds are said."""
    cameras = doc.get("cameras", [])
    kinds = [cameras[int(n["camera"])].get("type") for i, n in enumerate(doc.get("nodes", []))
             if isinstance(n, dict) and "camera" in n and i in world
             and isinstance(n["camera"], int) and 0 <= n["camera"] < len(cameras)
             and isinstance(cameras[n["camera"]], dict)]
    if len(set(kinds)) > 1:
        notes.append(f"perspective and orthographic cameras: every view is drawn with the "
                     f"first camera's projection ({kinds[0]}); p and o switch it")
    return "parallel" if kinds and kinds[0] == "orthographic" else "perspective"


def _views(doc, world, points, size, name) -> tuple[list, list]:
    from core.camera.view import View, problems
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    reach = float(np.linalg.norm(points.max(axis=0) - points.min(axis=0)))
    cameras = doc.get("cameras", [])
    views, messages = [], []
    for index, node in enumerate(doc.get("nodes", [])):
        if "camera" not in node or index not in world:
            continue
        try:
            camera = cameras[int(node["camera"])]
            view = _camera_view(camera, world[index], centre, reach, size,
                                f"{name}: camera of node {node.get('name', index)}")
        except (IndexError, KeyError, TypeError, ValueError) as error:
            messages.append(f"{name}: the camera of node {index} cannot be used ({error})")
            continue
        found = problems(view)
        if found:
            messages.append(f"{view.label}: {'; '.join(found)}")
        else:
            views.append(view)
    return views, messages


def _camera_view(camera: dict, matrix: np.ndarray, centre, reach: float, size, label: str):
    from core.camera.view import View
    eye = matrix[:3, 3]
    axes = matrix[:3, :3] / np.linalg.norm(matrix[:3, :3], axis=0)
    n, v = axes[:, 2], axes[:, 1]
    d = max(float(np.dot(eye - centre, n)), 1e-3 * max(reach, 1e-12))
    vrp = eye - d * n
    if camera.get("type") == "orthographic":
        o = camera["orthographic"]
        half_w, half_h = float(o["xmag"]), float(o["ymag"])
        near, far = float(o.get("znear", 0.0)), float(o.get("zfar", d + reach))
    else:
        p = camera["perspective"]
        half_h = d * np.tan(float(p["yfov"]) / 2)
        half_w = half_h * float(p.get("aspectRatio", size[0] / size[1]))
        near = float(p.get("znear", 1e-3 * d))
        far = float(p["zfar"]) if "zfar" in p else d + reach
    return View(vrp=tuple(map(float, vrp)), vpn=tuple(map(float, n)), vup=tuple(map(float, v)),
                window=(-half_w, half_w, -half_h, half_h), prp=(0.0, 0.0, d),
                front=d - near, back=d - far, label=label)


def _lights(doc: dict, world: dict, notes: list) -> list[Light]:
    defined = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    lights, spots = [], 0
    for index, node in enumerate(doc.get("nodes", [])):
        which = node.get("extensions", {}).get("KHR_lights_punctual", {}).get("light")
        if which is None or index not in world or not 0 <= int(which) < len(defined):
            continue
        light = defined[int(which)]
        colour = tuple(float(c) for c in light.get("color", (1.0, 1.0, 1.0)))
        m = world[index]
        if light.get("type") == "directional":
            towards = m[:3, 2] / np.linalg.norm(m[:3, 2])          # it shines down its -z
            lights.append(Light(intensity=colour, direction=tuple(map(float, towards))))
        else:
            spots += light.get("type") == "spot"
            lights.append(Light(intensity=colour, position=tuple(map(float, m[:3, 3]))))
    if spots:
        notes.append(f"{spots} spot lights drawn as point lights (no cone)")
    return lights
