"""glTF materials (core.scene.formats.gltf_materials): metallic-roughness to Cook-Torrance
(the texture as its mean), emission lighting a wall in radiosity as a TOML emitter does, a
normal map tilting a flat quad's shading by the angle derived by hand, alpha 0.5 blended by
the notes' interpolated formula, MASK, occlusion; bad factors and textures in one line.

The glTF files are written here by hand (JSON and a binary buffer) or by trimesh's exporter."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh
from PIL import Image

from core.render import render
from core.scene.formats import ReaderError, load_scene
from core.settings import RenderSettings

QUAD_UV = np.array([[0.0, 1], [1, 1], [1, 0], [0, 0]])      # glTF's v runs down the image


def quad(centre, half, normal_z=1.0):
    """A square in a plane z = const facing +z (or -z), corners counter-clockwise seen from
    the side it faces."""
    x, y, z = centre
    corners = np.array([[x - half, y - half, z], [x + half, y - half, z],
                        [x + half, y + half, z], [x - half, y + half, z]])
    faces = np.array([[0, 1, 2], [0, 2, 3]]) if normal_z > 0 else np.array([[0, 2, 1],
                                                                           [0, 3, 2]])
    return corners, faces


def write_gltf(folder, parts, materials, images=(), nodes=(), extensions=None,
               cameras=None, name="scene.gltf"):
    """A hand-written .gltf and its .bin: ``parts`` are ``(positions, faces, uv or None,
    material)``, one mesh and node each; ``images`` PNG file names (texture i is image i);
    ``nodes`` further nodes (cameras, lights) added to the scene."""
    blob, views, accessors, meshes = bytearray(), [], [], []

    def add(array, component, kind):
        data = np.ascontiguousarray(array).tobytes()
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)})
        blob.extend(data + b"\0" * (-len(data) % 4))
        accessor = {"bufferView": len(views) - 1, "componentType": component,
                    "count": len(array), "type": kind}
        if kind == "VEC3":
            accessor.update(min=array.min(axis=0).tolist(), max=array.max(axis=0).tolist())
        accessors.append(accessor)
        return len(accessors) - 1

    for positions, faces, uv, material in parts:
        attributes = {"POSITION": add(np.asarray(positions, np.float32), 5126, "VEC3")}
        if uv is not None:
            attributes["TEXCOORD_0"] = add(np.asarray(uv, np.float32), 5126, "VEC2")
        primitive = {"attributes": attributes, "material": material,
                     "indices": add(np.asarray(faces, np.uint32).ravel(), 5125, "SCALAR")}
        meshes.append({"primitives": [primitive]})
    all_nodes = [{"mesh": i} for i in range(len(meshes))] + list(nodes)
    (folder / "scene.bin").write_bytes(bytes(blob))
    doc = {"asset": {"version": "2.0"}, "scene": 0,
           "scenes": [{"nodes": list(range(len(all_nodes)))}], "nodes": all_nodes,
           "meshes": meshes, "materials": materials, "accessors": accessors,
           "bufferViews": views, "buffers": [{"uri": "scene.bin", "byteLength": len(blob)}]}
    if images:
        doc["images"] = [{"uri": uri} for uri in images]
        doc["textures"] = [{"source": i} for i in range(len(images))]
    if cameras:
        doc["cameras"] = cameras
    if extensions:
        doc["extensions"] = extensions
        doc["extensionsUsed"] = sorted(extensions)
    path = folder / name
    path.write_text(json.dumps(doc))
    return path


def png(folder, name, pixels):
    Image.fromarray(np.asarray(pixels, np.uint8)).save(folder / name)
    return name


# --- metallic-roughness -> Cook-Torrance ------------------------------------------------------

def test_a_metallic_spheres_material_row_is_the_mapping_worked_by_hand(tmp_path):
    """trimesh exports a sphere with base colour (230, 180, 50) / 255, metallic 1, roughness
    0.5 and a metallic-roughness texture whose left half has B = 255, G = 204 and right half
    B = 0, G = 204: metallic M = 1 x 0.5, roughness R = 0.5 x 0.8. The surface row the
    renderers light with: k_a 0.2, k_d 0.98 (1 - M), k_s 1, O_d the base colour, Cook-Torrance
    with m = R and F0 = 0.04 (1 - M) + base M."""
    from core.shading.illumination import KA, KD, KS, MODEL, OD, PARAMETERS, pack_surfaces
    from core.shading.models.registry import model_id
    texture = np.zeros((8, 8, 3), np.uint8)
    texture[:, :, 1] = 204
    texture[:, :4, 2] = 255
    ball = trimesh.creation.icosphere(2, 1.0)
    ball.visual = trimesh.visual.TextureVisuals(
        uv=np.zeros((len(ball.vertices), 2)),
        material=trimesh.visual.material.PBRMaterial(
            baseColorFactor=[230, 180, 50, 255], metallicFactor=1.0, roughnessFactor=0.5,
            metallicRoughnessTexture=Image.fromarray(texture)))
    path = tmp_path / "ball.glb"
    path.write_bytes(ball.export(file_type="glb"))
    scene = load_scene(path)
    (row,) = pack_surfaces([scene.meshes[0].material], [False])
    base = np.array([230, 180, 50]) / 255
    m, rough = 0.5, 0.5 * 204 / 255
    assert row[KA] == pytest.approx(0.2) and row[KS] == 1.0
    assert row[KD] == pytest.approx(0.98 * (1 - m))
    assert row[OD:OD + 3] == pytest.approx(base, abs=1e-6)
    assert row[MODEL] == model_id("cook-torrance")
    assert row[PARAMETERS] == pytest.approx(rough, abs=1e-6)
    assert row[PARAMETERS + 1:PARAMETERS + 4] == pytest.approx(0.04 * (1 - m) + base * m,
                                                               abs=1e-6)
    assert any("metallic-roughness textures drawn as their means" in line
               and "metallic 0.5, roughness 0.4" in line for line in scene.messages), \
        scene.messages


def test_emissive_and_occlusion_textures_enter_as_their_means(tmp_path):
    """emission = emissiveFactor x emissiveStrength x the texture's mean in linear light:
    a texture half sRGB 255, half sRGB 128 (linear 0.2158605) has the mean 0.6079303;
    k_a = 0.2 (1 + strength (mean occlusion - 1)): R half 255, half 0, strength 0.5 -> 0.15."""
    emissive = np.zeros((4, 4, 3), np.uint8)
    emissive[:, :2] = 255
    emissive[:, 2:] = 128
    occlusion = np.zeros((4, 4, 3), np.uint8)
    occlusion[:2, :, 0] = 255
    corners, faces = quad((0, 0, 0), 1.0)
    path = write_gltf(tmp_path, [(corners, faces, QUAD_UV, 0)], [{
        "pbrMetallicRoughness": {"metallicFactor": 0.0},
        "emissiveFactor": [1.0, 0.5, 0.25], "emissiveTexture": {"index": 0},
        "occlusionTexture": {"index": 1, "strength": 0.5},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}],
        images=[png(tmp_path, "glow.png", emissive), png(tmp_path, "ao.png", occlusion)])
    material = load_scene(path).meshes[0].material
    mean = (1.0 + ((128 / 255 + 0.055) / 1.055) ** 2.4) / 2
    assert mean == pytest.approx(0.6079303, abs=1e-6)
    assert material.emission == pytest.approx((4 * mean, 2 * mean, mean), abs=1e-9)
    assert material.ka == pytest.approx(0.15)


# --- emission ---------------------------------------------------------------------------------

def _lamp_and_wall(tmp_path, emissive):
    """A white wall (z = 0, 2 x 2) facing +z and a lamp (z = 1, 0.5 x 0.5) facing it; no
    light of its own but a black one (so that the default lights stay out)."""
    wall, wall_faces = quad((0, 0, 0), 1.0)
    lamp, lamp_faces = quad((0, 0, 1.0), 0.25, normal_z=-1.0)
    materials = [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1],
                                           "metallicFactor": 0.0}},
                 {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1],
                                           "metallicFactor": 0.0},
                  "emissiveFactor": list(emissive),
                  "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8}}}]
    dark = {"KHR_lights_punctual": {"lights": [{"type": "point", "color": [0, 0, 0]}]}}
    nodes = [{"translation": [0, 0, 5], "extensions": {"KHR_lights_punctual": {"light": 0}}},
             {"translation": [0, -2.5, 2.5], "camera": 0,      # 45 degrees about x: at the wall
              "rotation": [math.sin(math.pi / 8), 0, 0, math.cos(math.pi / 8)]}]
    cameras = [{"type": "perspective", "perspective": {"yfov": 0.9, "aspectRatio": 1.0,
                                                       "znear": 0.1, "zfar": 20}}]
    path = write_gltf(tmp_path, [(wall, wall_faces, None, 0), (lamp, lamp_faces, None, 1)],
                      materials, nodes=nodes, extensions=dark, cameras=cameras,
                      name="lamp.gltf")
    return path, (wall, wall_faces), (lamp, lamp_faces)


def _obj(path, corners, faces):
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners)
                    + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces))


def test_an_emissive_quad_lights_a_wall_in_radiosity_as_the_same_toml_emitter_does(tmp_path):
    """glTF emissiveFactor (1, 0.9, 0.8) times KHR_materials_emissive_strength 8 is the
    material's emission: radiosity draws the wall lit by the lamp as it draws the same two
    quads in a TOML scene with emission 8 (1, 0.9, 0.8) (the same Cook-Torrance materials,
    k_d 0.98), within a level; with emissiveFactor 0 the wall is dark."""
    path, (wall, wall_faces), (lamp, lamp_faces) = _lamp_and_wall(tmp_path, (1.0, 0.9, 0.8))
    glb = load_scene(path)
    assert glb.meshes[1].material.emission == pytest.approx((8.0, 7.2, 6.4))
    _obj(tmp_path / "wall.obj", wall, wall_faces)
    _obj(tmp_path / "lamp.obj", lamp, lamp_faces)
    look = ('ka = 0.2, kd = 0.98, ks = 1.0, model = "cook-torrance", roughness = 1.0, '
            'f0 = 0.04')
    (tmp_path / "lamp.toml").write_text(
        'background = [0.1, 0.1, 0.12]\nambient = [0.15, 0.15, 0.15]\n'
        f'[[geometry]]\nfile = "wall.obj"\nmaterial = {{ {look}, od = [0.8, 0.8, 0.8] }}\n'
        f'[[geometry]]\nfile = "lamp.obj"\nmaterial = {{ {look}, od = [0.5, 0.5, 0.5], '
        'emission = [8.0, 7.2, 6.4] }\n')
    toml = load_scene(tmp_path / "lamp.toml")
    settings = RenderSettings.for_scene(glb, size=(64, 64), renderer="radiosity")
    settings = settings.replace(max_elements=400)
    ours = render(glb, glb.views[0], settings).color.astype(int)
    theirs = render(toml, glb.views[0], settings).color.astype(int)
    assert np.abs(ours - theirs).max() <= 1, np.abs(ours - theirs).max()
    dark_path, _, _ = _lamp_and_wall(tmp_path, (0.0, 0.0, 0.0))
    dark = render(load_scene(dark_path), glb.views[0], settings).color.astype(int)
    below = (slice(26, 38), slice(24, 40))          # the pool of light on the wall
    assert ours[below].mean() > dark[below].mean() + 40, (ours[below].mean(), dark[below].mean())
    # the lamp's light is warm: red over blue on the white wall
    assert ours[below][..., 0].mean() > ours[below][..., 2].mean() + 3


# --- normal maps ------------------------------------------------------------------------------

def _cook_torrance(n, light, od, kd=0.98, ks=1.0, ka=0.2, ambient=0.15, m=1.0, f0=0.04):
    """FvDFH 16.7 by hand for a directional light of intensity 1 and the viewer along +z:
    I = I_a k_a O_d + k_d O_d (N.L) + k_s F D G / (N.V), Beckmann's D, Schlick's F."""
    n = np.asarray(n, float) / np.linalg.norm(n)
    v, l = np.array([0.0, 0, 1]), np.asarray(light, float)
    h = (l + v) / np.linalg.norm(l + v)
    nh, nv, nl, vh = n @ h, n @ v, n @ l, v @ h
    tan2 = (1 - nh * nh) / (nh * nh)
    d = math.exp(-tan2 / m ** 2) / (4 * m ** 2 * nh ** 4)
    g = min(1.0, 2 * nh * nv / vh, 2 * nh * nl / vh)
    f = f0 + (1 - f0) * (1 - vh) ** 5
    return min(1.0, ambient * ka * od + kd * od * max(nl, 0) + ks * f * d * g / nv)


@pytest.mark.parametrize("tilt, scale", [(30.0, 1.0), (-30.0, 1.0), (30.0, 0.5)])
def test_a_normal_map_tilts_a_flat_quads_shading_by_the_angle_worked_by_hand(
        tmp_path, tilt, scale):
    """A flat quad facing +z (u along +x, v up) with a constant normal texture
    (sin t, 0, cos t) stored as 255 (n + 1) / 2: glTF's tangent frame is (+x, +y, +z), so the
    shading normal is the stored one with x times the texture's ``scale``; a directional light
    from 40 degrees towards +x, an orthographic camera along -z: every pixel of the quad is
    Cook-Torrance at that normal (k_d 0.98, m 1, F0 0.04), not at +z."""
    t = math.radians(tilt)
    stored = np.round(255 * (np.array([math.sin(t), 0.0, math.cos(t)]) + 1) / 2)
    texture = np.tile(stored.astype(np.uint8), (4, 4, 1))
    n = (2 * stored / 255 - 1) * (scale, scale, 1.0)          # the angle the 8 bits hold
    phi = math.radians(40.0)
    light = (math.sin(phi), 0.0, math.cos(phi))
    corners, faces = quad((0, 0, 0), 1.0)
    nodes = [{"camera": 0, "translation": [0, 0, 5]},
             {"rotation": [0, math.sin(phi / 2), 0, math.cos(phi / 2)],   # its +z is `light`
              "extensions": {"KHR_lights_punctual": {"light": 0}}}]
    path = write_gltf(
        tmp_path, [(corners, faces, QUAD_UV, 0)],
        [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                   "metallicFactor": 0.0, "roughnessFactor": 1.0},
          "normalTexture": {"index": 0, "scale": scale}}],
        images=[png(tmp_path, "normal.png", texture)], nodes=nodes,
        cameras=[{"type": "orthographic", "orthographic": {"xmag": 1.5, "ymag": 1.5,
                                                            "znear": 0.1, "zfar": 20}}],
        extensions={"KHR_lights_punctual": {"lights": [{"type": "directional",
                                                         "color": [1, 1, 1]}]}})
    scene = load_scene(path, size=(60, 60))
    settings = RenderSettings.for_scene(scene, size=(60, 60), shading="phong")
    frame = render(scene, scene.views[0], settings).color.astype(float)
    middle = frame[20:40, 20:40, 0]
    assert middle.max() - middle.min() <= 1                      # one normal everywhere
    expected = 255 * _cook_torrance(n, light, 0.8)
    flat = 255 * _cook_torrance((0, 0, 1), light, 0.8)
    assert abs(middle.mean() - expected) <= 1.5, (middle.mean(), expected, flat)
    assert abs(expected - flat) > 10                    # the map moved it, not the geometry
    plain = render(scene, scene.views[0], settings.replace(bump=False)).color[20:40, 20:40, 0]
    assert abs(plain.astype(float).mean() - flat) <= 1.5     # `b` off: the quad's own normal


# --- alpha ------------------------------------------------------------------------------------

def _pane_scene(tmp_path, alpha, mode="BLEND", wall=True, pane=True, name="pane.gltf"):
    """A red wall at z = 0 and a blue-grey pane at z = 0.5 in front of it (both 2 x 2,
    facing +z), under one white point light, seen head on."""
    parts, materials = [], []
    if wall:
        parts.append((*quad((0, 0, 0), 1.0), None, len(materials)))
        materials.append({"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1],
                                                   "metallicFactor": 0.0}})
    if pane:
        parts.append((*quad((0, 0, 0.5), 1.0), None, len(materials)))
        materials.append({"pbrMetallicRoughness": {"baseColorFactor": [0.3, 0.5, 0.9, alpha],
                                                   "metallicFactor": 0.0},
                          "alphaMode": mode, "alphaCutoff": 0.5})
    nodes = [{"camera": 0, "translation": [0, 0, 5]},
             {"translation": [1, 2, 4], "extensions": {"KHR_lights_punctual": {"light": 0}}}]
    return load_scene(write_gltf(
        tmp_path, parts, materials, nodes=nodes, name=name,
        cameras=[{"type": "orthographic", "orthographic": {"xmag": 1.5, "ymag": 1.5,
                                                            "znear": 0.1, "zfar": 20}}],
        extensions={"KHR_lights_punctual": {"lights": [{"type": "point",
                                                         "color": [1, 1, 1]}]}}))


def test_alpha_half_blends_the_pane_by_the_interpolated_formula(tmp_path):
    """alphaMode BLEND, alpha 0.5: k_t = 0.5, and the scene's transparency is the notes'
    interpolated one, I = (1 - k_t) I_pane + k_t I_behind: the picture is the mean of the
    opaque pane's picture and the bare wall's, within a level."""
    both = _pane_scene(tmp_path, 0.5)
    assert both.meshes[1].material.kt == 0.5
    view = both.views[0]
    settings = RenderSettings.for_scene(both, size=(60, 60), shading="phong")
    assert settings.transparency == "interpolated"
    blended = render(both, view, settings).color.astype(float)
    opaque = render(_pane_scene(tmp_path, 1.0, wall=False, name="o.gltf"), view,
                    settings).color.astype(float)
    wall = render(_pane_scene(tmp_path, 1.0, pane=False, name="w.gltf"), view,
                  settings).color.astype(float)
    inside = (slice(15, 45), slice(15, 45))
    expected = 0.5 * opaque[inside] + 0.5 * wall[inside]
    assert np.abs(blended[inside] - expected).max() <= 1.0, \
        np.abs(blended[inside] - expected).max()
    assert np.abs(blended[inside] - opaque[inside]).max() > 30      # the wall shows through


def test_mask_draws_the_pane_opaque_above_its_cutoff_and_leaves_it_out_below(tmp_path):
    kept = _pane_scene(tmp_path, 0.7, mode="MASK", name="kept.gltf")
    assert len(kept.meshes) == 2 and kept.meshes[1].material.kt == 0.0
    gone = _pane_scene(tmp_path, 0.3, mode="MASK", name="gone.gltf")
    assert len(gone.meshes) == 1
    (line,) = [m for m in gone.messages if "MASK" in m]
    assert "gone.gltf" in line and "materials[1]" in line


# --- bad input --------------------------------------------------------------------------------

def _one_material_quad(tmp_path, material, images=()):
    corners, faces = quad((0, 0, 0), 1.0)
    return write_gltf(tmp_path, [(corners, faces, QUAD_UV, 0)], [material], images=images,
                      name="bad.gltf")


@pytest.mark.parametrize("material, words", [
    ({"pbrMetallicRoughness": {"metallicFactor": float("nan")}},
     r"bad.gltf: materials\[0\].pbrMetallicRoughness.metallicFactor is nan; expected a "
     r"number in \[0, 1\]"),
    ({"pbrMetallicRoughness": {"baseColorFactor": [1, float("inf"), 1, 1]}},
     r"materials\[0\].pbrMetallicRoughness.baseColorFactor is inf"),
    ({"emissiveFactor": [0, float("nan"), 0]}, r"materials\[0\].emissiveFactor is nan"),
    ({"normalTexture": {"index": 5}},
     r"bad.gltf: materials\[0\].normalTexture.index is 5; the file has 1 textures"),
    ({"pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": -1}}},
     r"metallicRoughnessTexture.index is -1"),
])
def test_bad_factors_and_texture_indices_are_one_line(tmp_path, material, words):
    png(tmp_path, "t.png", np.full((2, 2, 3), 128))
    path = _one_material_quad(tmp_path, material, images=["t.png"])
    with pytest.raises(ReaderError, match=words) as error:
        load_scene(path)
    assert "\n" not in str(error.value)


def _bomb(tmp_path):
    """A PNG of a few hundred bytes whose header says 20000 x 20000."""
    import struct
    import zlib

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data)))
    (tmp_path / "bomb.png").write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 20000, 20000, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(b"\x00" * 60001, 9)) + chunk(b"IEND", b""))
    return "bomb.png"


def test_a_metallic_roughness_texture_that_is_a_bomb_is_one_line_naming_it(tmp_path):
    path = _one_material_quad(
        tmp_path, {"pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": 0}}},
        images=[_bomb(tmp_path)])
    with pytest.raises(ReaderError) as error:
        load_scene(path)
    message = str(error.value)
    assert message.startswith(str(path)) or "bad.gltf" in message
    assert "images[0] 'bomb.png' (the metallic-roughness texture of materials[0])" in message
    assert "\n" not in message


def test_an_embedded_bomb_in_a_glb_leaves_the_factors_and_says_so(tmp_path):
    """trimesh's exporter embeds the texture in the .glb; a bomb put there is not decoded
    (Pillow refuses it from its header): the factors are drawn, one line names the part."""
    noise = np.random.default_rng(0).integers(0, 256, (64, 64, 3), dtype=np.uint8)
    box = trimesh.creation.box()
    box.visual = trimesh.visual.TextureVisuals(
        uv=np.zeros((len(box.vertices), 2)),
        material=trimesh.visual.material.PBRMaterial(
            metallicFactor=0.5, roughnessFactor=0.5,
            metallicRoughnessTexture=Image.fromarray(noise)))   # a noisy PNG: many bytes
    data = bytearray(box.export(file_type="glb"))
    start, length = data.find(b"\x89PNG"), _view_length_of_image(bytes(data))
    bomb = (tmp_path / _bomb(tmp_path)).read_bytes()
    assert start > 0 and len(bomb) < length
    # the bomb over the embedded PNG's bytes, padded to its view's length by zeros (a PNG
    # reader stops at IEND): Pillow reads its header first
    data[start:start + length] = bomb + b"\0" * (length - len(bomb))
    path = tmp_path / "box.glb"
    path.write_bytes(bytes(data))
    scene = load_scene(path)
    (line,) = [m for m in scene.messages if "could not be decoded" in m]
    assert "box.glb" in line and "the metallic-roughness texture of materials[0]" in line
    row = scene.meshes[0].material
    assert row.kd == pytest.approx(0.98 * 0.5)


def _view_length_of_image(glb: bytes) -> int:
    import struct
    (length,) = struct.unpack_from("<I", glb, 12)
    doc = json.loads(glb[20:20 + length])
    view = doc["bufferViews"][doc["images"][0]["bufferView"]]
    return view["byteLength"]
