"""glTF 2.0 scenes: a ``.glb``, or a ``.gltf`` with its buffers beside it.

trimesh reads the meshes (its glTF loader: accessors, buffers, node transforms); the JSON's
cameras and ``KHR_lights_punctual`` lights, which trimesh does not keep, are read here from
the same document. What becomes what:

- **Meshes**: every triangle mesh of the default scene, its node transform applied (the
  scene graph flattened: an instanced mesh becomes one mesh per instance); closed (culled)
  when watertight. Points and lines are left out, and said.
- **Materials** (metallic–roughness): the base colour factor is ``O_d``; the model is
  Cook–Torrance (FvDFH 16.7) with ``k_d = 0.98 (1 − metallic)`` (``DIFFUSE_SHARE``: below
  1, so that a white base colour reflects less than all the light), ``k_s = 1``, Beckmann's slope
  ``m = roughness`` (glTF's is a perceptual roughness for GGX: taken as ``m`` directly, an
  approximation) and ``F0 = 0.04 (1 − metallic) + base colour · metallic``; glTF's defaults
  (metallic 1, roughness 1) hold where a factor is absent. Emission is the emissive factor
  (radiosity and the path tracer light with it); alpha below 1 with ``alphaMode = BLEND`` is
  ``k_t = 1 − alpha``. The base colour texture (with the mesh's ``TEXCOORD_0``) is the
  colour map, sRGB, repeated, mipmapped, times the base colour factor (glTF's product); the
  metallic–roughness, normal, occlusion and emissive textures are not read (said). An image
  over ``MAX_TEXTURE_SIDE`` on a side, or over the scene's texel budget, is refused from
  its header before its pixels are decoded (an image file beside the glTF before trimesh
  opens it, an embedded one before its pixels are read); one that cannot be opened leaves
  the factor, said.
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
# k_d of a dielectric (metallic 0): a white base colour would otherwise reflect all the light
# (rho = k_d O_d = 1), which no real surface does and which the radiosity solver and the
# path tracer refuse (the light would never die out); glTF's white is common
DIFFUSE_SHARE = 0.98


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
    scene = Scene(name=Path(name).stem, meshes=meshes,
                  views=views or framing_views(points, name), view_messages=view_messages,
                  lights=lights or default_lights(points), shading="phong", size=size,
                  source=name, background=(0.1, 0.1, 0.12), ambient=(0.15, 0.15, 0.15))
    scene.messages += notes
    return scene


def _check_uris(doc: dict, folder: Path, name: str) -> None:
    """Every external buffer and image a regular file inside the glTF's own folder (a URI
    of ``../../etc/passwd`` reads nothing), within the mesh files' size limit."""
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
            where = f"{kind}[{index}] {uri!r}"
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
    _check_uris(doc, folder, name)
    kind = "glb" if data[:4] == GLB_MAGIC else "gltf"
    resolver = trimesh.resolvers.FilePathResolver(str(folder) + "/")
    try:
        with warnings.catch_warnings():      # Pillow's bomb warning an error: trimesh then
            # leaves such an image out (said below) rather than decode it
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            loaded = trimesh.load(io.BytesIO(data), file_type=kind, process=False,
                                  resolver=resolver, force="scene")
    except Exception as error:        # trimesh raises many kinds for a broken file
        raise ReaderError(name, f"the glTF's meshes cannot be read ({type(error).__name__}: "
                                f"{error})") from None
    meshes, skipped, textured = [], 0, 0
    textures = _Textures(name)
    for node in sorted(loaded.graph.nodes_geometry):
        matrix, geometry = loaded.graph[node]
        part = loaded.geometry[geometry]
        if not isinstance(part, trimesh.Trimesh) or len(part.faces) == 0:
            skipped += 1
            continue
        positions = np.asarray(part.vertices, np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
        triangles = np.asarray(part.faces, np.int64)
        if np.linalg.det(matrix[:3, :3]) < 0:             # a mirror turns the winding over
            triangles = triangles[:, [0, 2, 1]]
        material, has_texture = _material(part.visual)
        textured += has_texture
        material, uv = textures.colour_map(part.visual, material)
        meshes.append(Mesh(positions=positions, triangles=triangles, material=material,
                           name=str(node), closed=bool(part.is_watertight), uv=uv))
    if skipped:
        notes.append(f"{name}: {skipped} point or line primitives left out (triangles only)")
    if textured:
        notes.append(f"{name}: {textured} meshes have metallic-roughness, normal, occlusion or "
                     f"emissive textures: not read, their material's factors are drawn")
    if _names_colour_maps(doc) and not textures.made:
        notes.append(f"{name}: its base colour textures could not be decoded, or its meshes "
                     f"have no TEXCOORD_0: drawn with the base colour factors")
    return meshes


def _names_colour_maps(doc: dict) -> bool:
    return any(isinstance(m, dict) and isinstance(m.get("pbrMetallicRoughness"), dict)
               and "baseColorTexture" in m["pbrMetallicRoughness"]
               for m in doc.get("materials", []) or [])


class _Textures:
    """The colour maps of one file's materials, each image made a texture once (by the
    texture system, through :func:`core.scene.formats.keys.register_colour_image`)."""

    def __init__(self, name: str):
        from core.scene.formats.keys import colour_image_maker
        self.name, self.make, self.made = name, colour_image_maker(), {}
        self.state = {}                # the texture system's own, for the whole file

    def colour_map(self, visual, material: Material):
        """``(material with its colour map, uv)``, or ``(material, None)`` where the mesh has
        no base colour texture or no texture coordinates."""
        pbr = getattr(visual, "material", None)
        image = getattr(pbr, "baseColorTexture", None)
        uv = getattr(visual, "uv", None)
        if self.make is None or image is None or uv is None or len(uv) == 0:
            return material, None
        key = (id(image), material.od)
        if key not in self.made:
            self.made[key] = self._mapped(image, material)
        return self.made[key], np.asarray(uv, np.float64)

    def _mapped(self, image, material: Material) -> Material:
        from core.scene.formats.errors import MAX_TEXTURE_SIDE
        w, h = image.size
        where = f"its base colour texture ({w} x {h})"
        if max(w, h) > MAX_TEXTURE_SIDE:
            raise ReaderError(self.name, f"{where}: textures may be at most "
                                         f"{MAX_TEXTURE_SIDE} on a side")
        pixels = np.asarray(image.convert("RGBA"))   # (h, w, 4) uint8, row 0 the top
        try:
            return self.make(material, pixels, material.od, f"{self.name}: base colour "
                             f"texture", self.state)
        except ValueError as error:
            raise ReaderError(self.name, f"{where}: {error}") from None


def _material(visual) -> tuple[Material, bool]:
    """Our material for a trimesh visual (glTF metallic–roughness), and whether it has a
    texture the reader leaves out (any but the base colour's)."""
    import dataclasses
    pbr = getattr(visual, "material", None)
    if pbr is None or not hasattr(pbr, "baseColorFactor"):
        colour = getattr(visual, "main_color", None)
        od = tuple(float(c) / 255.0 for c in colour[:3]) if colour is not None else (0.8,) * 3
        return Material(od=od), False
    base = np.asarray(pbr.baseColorFactor if pbr.baseColorFactor is not None
                      else (255, 255, 255, 255), np.float64)
    base = base / 255.0 if base.max() > 1.0 or base.dtype.kind in "ui" else base
    metallic = 1.0 if pbr.metallicFactor is None else float(pbr.metallicFactor)
    roughness = 1.0 if pbr.roughnessFactor is None else float(pbr.roughnessFactor)
    emissive = tuple(float(c) for c in (pbr.emissiveFactor if pbr.emissiveFactor is not None
                                        else (0.0, 0.0, 0.0)))
    alpha = float(base[3]) if len(base) > 3 else 1.0
    blended = str(getattr(pbr, "alphaMode", "") or "").upper() == "BLEND"
    f0 = tuple(float(0.04 * (1.0 - metallic) + c * metallic) for c in base[:3])
    material = Material(ka=0.2, kd=DIFFUSE_SHARE * (1.0 - metallic), ks=1.0,
                        od=tuple(float(c) for c in base[:3]),
                        kt=1.0 - alpha if blended and alpha < 1.0 else 0.0,
                        emission=emissive)
    material = dataclasses.replace(material, extra={"lighting": {
        "model": "cook-torrance",
        "parameters": {"roughness": min(max(roughness, 0.01), 1.0), "f0": f0}}})
    textured = any(getattr(pbr, k, None) is not None for k in
                   ("metallicRoughnessTexture", "normalTexture", "occlusionTexture",
                    "emissiveTexture"))
    return material, textured


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
