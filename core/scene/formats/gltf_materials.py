"""glTF 2.0 metallic–roughness materials as ours (the mapping is stated in
``docs/scene-format.md``).

The factors are read from the file's JSON, checked (a NaN or out-of-range factor, a texture
index past the file's textures: one line naming the material and the key); the images come
decoded from trimesh. To know which JSON material trimesh gave a mesh, the reader hands
trimesh the file with every material named by its index (:func:`tagged`).

- ``baseColorFactor`` → ``O_d`` (its alpha: see below); ``baseColorTexture`` → the colour map
  (by the texture system, :func:`core.scene.formats.keys.register_colour_image`).
- metallic ``M`` = ``metallicFactor`` × the mean of the metallic–roughness texture's B,
  roughness ``R`` = ``roughnessFactor`` × the mean of its G (the texture system has no
  per-pixel metal or roughness map: a texture is drawn as its mean, said) → Cook–Torrance with
  ``k_d = 0.98 (1 − M)``, ``k_s = 1``, Beckmann's ``m = R`` (clamped to [0.01, 1]),
  ``F0 = 0.04 (1 − M) + baseColorFactor · M``.
- ``emissiveFactor`` × ``KHR_materials_emissive_strength`` × the emissive texture's mean (in
  linear light) → ``emission``.
- ``normalTexture`` → the tangent-space normal map, x and y times its ``scale`` (through
  :func:`core.scene.formats.keys.register_normal_image`), tangents derived from ``TEXCOORD_0``.
- ``alphaMode``: ``BLEND`` → ``k_t = 1 − alpha`` (the factor's alpha); ``MASK`` → opaque where
  alpha ≥ ``alphaCutoff``, the mesh left out where below (said); the texture's alpha unread.
- ``occlusionTexture`` → ``k_a = 0.2 (1 + strength (mean of R − 1))``: the ambient term
  times the texture's mean occlusion.
"""

from __future__ import annotations

import dataclasses
import json
import struct
from dataclasses import dataclass, field

import numpy as np

from core.colour.srgb import decode
from core.scene.formats.errors import MAX_TEXTURE_SIDE, ReaderError
from core.scene.model import Material

# k_d of a dielectric (metallic 0): a white base colour would otherwise reflect all the light
# (rho = k_d O_d = 1), which no real surface does and which the radiosity solver and the
# path tracer refuse (the light would never die out); glTF's white is common
DIFFUSE_SHARE = 0.98
AMBIENT = 0.2                    # k_a before the occlusion texture's mean
TAG = "gltf-material#"           # trimesh keeps a material's name: ours carries its index
ROLES = {"baseColorTexture": "base colour", "metallicRoughnessTexture": "metallic-roughness",
         "normalTexture": "normal", "occlusionTexture": "occlusion",
         "emissiveTexture": "emissive"}
MAX_EMISSION = 1e6               # the scene files' bound on emission


@dataclass
class Factors:
    """One JSON material, checked: its factors and the image index of each texture role."""

    label: str                                  # "materials[2] 'paint'"
    base: tuple = (1.0, 1.0, 1.0, 1.0)
    metallic: float = 1.0
    roughness: float = 1.0
    emissive: tuple = (0.0, 0.0, 0.0)
    alpha_mode: str = "OPAQUE"
    cutoff: float = 0.5
    normal_scale: float = 1.0
    occlusion_strength: float = 1.0
    images: dict = field(default_factory=dict)   # role key -> image index


def tagged(data: bytes, doc: dict, glb: bool) -> bytes:
    """The file's bytes with each material's ``name`` its index (``TAG`` + index), for
    trimesh; a ``.glb``'s JSON chunk rewritten and its lengths mended."""
    if doc.get("materials"):
        doc = {**doc, "materials": [{**m, "name": f"{TAG}{i}"} if isinstance(m, dict) else m
                                    for i, m in enumerate(doc["materials"])]}
    text = json.dumps(doc).encode("utf-8")
    if not glb:
        return text
    text += b" " * (-len(text) % 4)                  # chunks are 4-byte aligned
    (total,), (old,) = struct.unpack_from("<I", data, 8), struct.unpack_from("<I", data, 12)
    return (data[:8] + struct.pack("<II4s", total + len(text) - old, len(text), b"JSON")
            + text + data[20 + old:])


def index_of(pbr) -> int | None:
    """The JSON index of a material trimesh read from a :func:`tagged` file."""
    name = getattr(pbr, "name", None)
    if isinstance(name, str) and name.startswith(TAG) and name[len(TAG):].isdigit():
        return int(name[len(TAG):])
    return None


def read_factors(doc: dict, name: str) -> list[Factors]:
    """Every JSON material's :class:`Factors`; a bad one is a ReaderError naming it."""
    entries = doc.get("materials", []) or []
    if not isinstance(entries, list):
        raise ReaderError(name, "materials must be a list")
    return [_factors(entry, i, doc, name) for i, entry in enumerate(entries)]


def _factors(entry, index: int, doc: dict, name: str) -> Factors:
    where = f"materials[{index}]"
    if not isinstance(entry, dict):
        raise ReaderError(name, f"{where} must be an object")
    label = where + (f" {entry['name']!r}" if isinstance(entry.get("name"), str) else "")
    pbr = entry.get("pbrMetallicRoughness", {})
    if not isinstance(pbr, dict):
        raise ReaderError(name, f"{where}.pbrMetallicRoughness must be an object")
    p = f"{where}.pbrMetallicRoughness"
    strength = entry.get("extensions", {}).get("KHR_materials_emissive_strength", {}) \
        if isinstance(entry.get("extensions"), dict) else {}
    mode = entry.get("alphaMode", "OPAQUE")
    if mode not in ("OPAQUE", "MASK", "BLEND"):
        raise ReaderError(name, f"{where}.alphaMode is {mode!r}; expected OPAQUE, MASK or BLEND")
    boost = _number(strength.get("emissiveStrength", 1.0) if isinstance(strength, dict) else 1.0,
                    0.0, MAX_EMISSION, f"{where}.extensions.KHR_materials_emissive_strength."
                                       f"emissiveStrength", name)
    emissive = _numbers(entry.get("emissiveFactor", (0, 0, 0)), 3, f"{where}.emissiveFactor",
                        name)
    found = Factors(
        label=label,
        base=_numbers(pbr.get("baseColorFactor", (1, 1, 1, 1)), 4, f"{p}.baseColorFactor", name),
        metallic=_number(pbr.get("metallicFactor", 1.0), 0.0, 1.0, f"{p}.metallicFactor", name),
        roughness=_number(pbr.get("roughnessFactor", 1.0), 0.0, 1.0, f"{p}.roughnessFactor",
                          name),
        emissive=tuple(c * boost for c in emissive), alpha_mode=mode,
        cutoff=_number(entry.get("alphaCutoff", 0.5), 0.0, 1.0, f"{where}.alphaCutoff", name))
    infos = {**{k: (pbr.get(k), f"{p}.{k}") for k in ("baseColorTexture",
                                                      "metallicRoughnessTexture")},
             **{k: (entry.get(k), f"{where}.{k}") for k in ("normalTexture", "occlusionTexture",
                                                            "emissiveTexture")}}
    for key, (info, at) in infos.items():
        if info is not None:
            found.images[key] = _image_of(info, at, doc, name)
    if "normalTexture" in found.images:
        found.normal_scale = _number(entry["normalTexture"].get("scale", 1.0), -1e3, 1e3,
                                     f"{where}.normalTexture.scale", name)
    if "occlusionTexture" in found.images:
        found.occlusion_strength = _number(entry["occlusionTexture"].get("strength", 1.0), 0.0,
                                           1.0, f"{where}.occlusionTexture.strength", name)
    return found


def _number(value, low: float, high: float, key: str, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or not low <= value <= high:                  # NaN fails the range too
        raise ReaderError(name, f"{key} is {value!r}; expected a number in [{low:g}, {high:g}]")
    return float(value)


def _numbers(value, count: int, key: str, name: str) -> tuple:
    if not isinstance(value, (list, tuple)) or len(value) != count:
        raise ReaderError(name, f"{key} must be {count} numbers in [0, 1]")
    return tuple(_number(v, 0.0, 1.0, key, name) for v in value)


def _image_of(info, key: str, doc: dict, name: str) -> int | None:
    """The image index a texture-info names (None: a texture with no source)."""
    textures, images = doc.get("textures", []) or [], doc.get("images", []) or []
    index = info.get("index") if isinstance(info, dict) else None
    if isinstance(index, bool) or not isinstance(index, int) or not 0 <= index < len(textures):
        raise ReaderError(name, f"{key}.index is {index!r}; the file has {len(textures)} "
                                f"textures")
    source = textures[index].get("source") if isinstance(textures[index], dict) else None
    if source is None:
        return None
    if isinstance(source, bool) or not isinstance(source, int) or not 0 <= source < len(images):
        raise ReaderError(name, f"textures[{index}].source is {source!r} (named by {key}); the "
                                f"file has {len(images)} images")
    return source


def image_roles(factors: list[Factors]) -> dict[int, str]:
    """Each image index: the first texture role and material that use it (for messages)."""
    roles: dict[int, str] = {}
    for f in factors:
        for key, image in f.images.items():
            if image is not None:
                roles.setdefault(image, f"the {ROLES[key]} texture of {f.label}")
    return roles


def channel_means(image, srgb: bool, where: str, name: str) -> np.ndarray:
    """The mean of each of an image's R, G, B in [0, 1], from its histogram (decoded from sRGB
    first when ``srgb``: a mean in linear light)."""
    w, h = image.size
    if max(w, h) > MAX_TEXTURE_SIDE:
        raise ReaderError(name, f"{where} is {w} x {h}; textures may be at most "
                                f"{MAX_TEXTURE_SIDE} on a side")
    counts = np.asarray(image.convert("RGB").histogram(), np.float64).reshape(3, 256)
    levels = np.arange(256) / 255.0
    if srgb:
        levels = decode(levels)           # the sRGB curve (core.colour.srgb)
    return counts @ levels / counts.sum(axis=1)


def material_of(f: Factors, pbr, name: str, notes: "Notes") -> Material | None:
    """Our material for checked factors ``f`` and trimesh's material ``pbr`` (its decoded
    images), before the colour and normal maps; None for a MASK material whose alpha is
    below its cutoff (the mesh is left out)."""
    alpha = f.base[3]
    if f.alpha_mode == "MASK" and alpha < f.cutoff:
        notes.add("masked out", f.label)
        return None
    metallic, roughness = f.metallic, f.roughness
    image = decoded_image(pbr, "metallicRoughnessTexture", f, notes)
    if image is not None:
        means = channel_means(image, False, f"the metallic-roughness texture of {f.label}", name)
        metallic, roughness = metallic * means[2], roughness * means[1]
        notes.add("metallic-roughness", f"{f.label} (metallic {metallic:.3g}, roughness "
                                        f"{roughness:.3g})")
    emission = np.asarray(f.emissive)
    image = decoded_image(pbr, "emissiveTexture", f, notes)
    if image is not None:
        emission = emission * channel_means(image, True, f"the emissive texture of {f.label}",
                                            name)
        notes.add("emissive", f.label)
    ka = AMBIENT
    image = decoded_image(pbr, "occlusionTexture", f, notes)
    if image is not None:
        mean = channel_means(image, False, f"the occlusion texture of {f.label}", name)[0]
        ka = AMBIENT * (1.0 + f.occlusion_strength * (mean - 1.0))
        notes.add("occlusion", f"{f.label} ({mean:.3g})")
    if f.alpha_mode != "OPAQUE" and "baseColorTexture" in f.images:
        notes.add("texture alpha", f.label)
    base = f.base[:3]
    f0 = tuple(float(0.04 * (1.0 - metallic) + c * metallic) for c in base)
    material = Material(ka=ka, kd=DIFFUSE_SHARE * (1.0 - metallic), ks=1.0, od=base,
                        kt=1.0 - alpha if f.alpha_mode == "BLEND" else 0.0,
                        emission=tuple(float(c) for c in emission))
    return dataclasses.replace(material, extra={"lighting": {
        "model": "cook-torrance",
        "parameters": {"roughness": min(max(roughness, 0.01), 1.0), "f0": f0}}})


def decoded_image(pbr, key: str, f: Factors, notes: "Notes"):
    """trimesh's decoded image for a role the material names, or None (said when the file
    names one that could not be decoded)."""
    if f.images.get(key) is None:
        return None
    image = getattr(pbr, key, None)
    if image is None:
        notes.add("undecoded", f"the {ROLES[key]} texture of {f.label}")
    return image


class Notes:
    """The material messages of one file, one line per kind (each kind lists its
    materials once)."""

    WORDS = {
        "metallic-roughness": "metallic-roughness textures drawn as their means (there is no "
                              "per-pixel metal or roughness map here)",
        "emissive": "emissive textures drawn as their mean in linear light times the "
                    "emissive factor (emission is one colour per material)",
        "occlusion": "occlusion textures drawn as their mean times the ambient term",
        "texture alpha": "the base colour texture's alpha is not read (the factor's alpha is)",
        "masked out": "alphaMode MASK with the factor's alpha below alphaCutoff: its meshes "
                      "are left out",
        "undecoded": "textures that could not be decoded (their factors are drawn)",
        "no uv": "base colour or normal textures not drawn: the meshes have no TEXCOORD_0",
    }

    def __init__(self, name: str):
        self.name, self.seen = name, {}

    def add(self, kind: str, what: str) -> None:
        listed = self.seen.setdefault(kind, [])
        if what not in listed:
            listed.append(what)

    def lines(self) -> list[str]:
        return [f"{self.name}: {self.WORDS[kind]}: {', '.join(listed[:6])}"
                + (f" and {len(listed) - 6} more" if len(listed) > 6 else "")
                for kind, listed in self.seen.items()]
