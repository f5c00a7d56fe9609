"""glTF 2.0 scenes (core.scene.formats.gltf): meshes with their node transforms, the
metallic-roughness materials mapped to Cook-Torrance, a perspective camera as a course view
held to a pinhole worked by hand, KHR_lights_punctual lights, and bad files in one line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh

from core.render import render
from core.scene.formats import ReaderError, load_scene
from core.settings import RenderSettings


def _pbr(rgba, metallic, roughness):
    return trimesh.visual.TextureVisuals(material=trimesh.visual.material.PBRMaterial(
        baseColorFactor=rgba, metallicFactor=metallic, roughnessFactor=roughness))


def _two_objects():
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    box.visual = _pbr([255, 0, 0, 255], 0.0, 0.4)
    ball = trimesh.creation.icosphere(3, 0.6)
    ball.visual = _pbr([200, 200, 255, 255], 1.0, 0.3)
    scene = trimesh.Scene()
    scene.add_geometry(box, node_name="box",
                       transform=trimesh.transformations.translation_matrix([1.2, 0, 0]))
    scene.add_geometry(ball, node_name="ball",
                       transform=trimesh.transformations.translation_matrix([-0.8, 0, 0]))
    return scene


def test_a_glb_gives_its_meshes_in_place_and_its_materials(tmp_path):
    path = tmp_path / "two.glb"
    path.write_bytes(_two_objects().export(file_type="glb"))
    scene = load_scene(path)
    box = next(m for m in scene.meshes if m.name == "box")
    assert np.allclose(box.positions.mean(axis=0), [1.2, 0, 0], atol=1e-6)
    assert len(box.triangles) == 12 and box.closed
    # plastic: k_d = 1 - metallic, F0 = 0.04; metal: k_d = 0, F0 = its base colour
    assert box.material.od == (1.0, 0.0, 0.0) and box.material.kd == pytest.approx(0.98)
    lighting = box.material.extra["lighting"]
    assert lighting["model"] == "cook-torrance"
    assert lighting["parameters"] == {"roughness": pytest.approx(0.4),
                                      "f0": pytest.approx((0.04, 0.04, 0.04))}
    ball = next(m for m in scene.meshes if m.name == "ball")
    assert ball.material.kd == 0.0
    assert ball.material.extra["lighting"]["parameters"]["f0"] == pytest.approx(
        (200 / 255, 200 / 255, 1.0))
    assert len(scene.views) == 3 and len(scene.lights) >= 1     # no camera: the framing views


def _gltf_with_camera_and_lights(tmp_path):
    files = _two_objects().export(file_type="gltf")
    doc = json.loads(files["model.gltf"])
    for name, data in files.items():
        if name != "model.gltf":
            (tmp_path / name).write_bytes(data)
    doc["cameras"] = [{"type": "perspective", "perspective": {
        "yfov": 0.8, "aspectRatio": 1.0, "znear": 0.1, "zfar": 100.0}}]
    c = math.sqrt(0.5)
    doc["nodes"] += [{"name": "eye", "camera": 0, "translation": [0, 0, 5]},
                     {"name": "lamp", "translation": [2, 3, 4],
                      "extensions": {"KHR_lights_punctual": {"light": 0}}},
                     {"name": "sun", "rotation": [-c, 0, 0, c],        # -90° about x: down
                      "extensions": {"KHR_lights_punctual": {"light": 1}}}]
    count = len(doc["nodes"])
    doc["scenes"][doc.get("scene", 0)]["nodes"] += [count - 3, count - 2, count - 1]
    doc["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1.0, 0.5, 0.5], "intensity": 100.0},
        {"type": "directional", "color": [0.5, 0.5, 0.5]}]}}
    doc.setdefault("extensionsUsed", []).append("KHR_lights_punctual")
    path = tmp_path / "lit.gltf"
    path.write_text(json.dumps(doc))
    return path


def test_a_camera_becomes_a_course_view_and_the_picture_is_the_pinholes(tmp_path):
    scene = load_scene(_gltf_with_camera_and_lights(tmp_path), size=(200, 200))
    (view,) = scene.views
    d = 5.0                                     # the bounds' centre is at z = 0
    assert view.vpn == pytest.approx((0, 0, 1)) and view.vup == pytest.approx((0, 1, 0))
    assert view.prp == pytest.approx((0, 0, d)) and view.vrp == pytest.approx((0, 0, 0), abs=1e-9)
    half = d * math.tan(0.4)
    assert view.window == pytest.approx((-half, half, -half, half))
    assert (view.front, view.back) == pytest.approx((d - 0.1, d - 100.0))
    # a pinhole at (0, 0, 5) looking down -z: the box's front face centre (1.2, 0, 0.5) lands
    # at x = 1.2 / (4.5 tan 0.4) of the half-width right of the centre
    frame = render(scene, view, RenderSettings.for_scene(scene, shading="flat"))
    red = (frame.color[:, :, 0] > 60) & (frame.color[:, :, 1] < 30)
    columns = np.nonzero(red.any(axis=0))[0]
    expected = 100 + 100 * 1.2 / (4.5 * math.tan(0.4))
    assert abs((columns.min() + columns.max()) / 2 - expected) <= 3.0
    # the lights: the point light at its node, the directional one shining down its -z
    point = next(li for li in scene.lights if li.position is not None)
    sun = next(li for li in scene.lights if li.direction is not None)
    assert point.position == pytest.approx((2, 3, 4)) and point.intensity == (1.0, 0.5, 0.5)
    assert sun.direction == pytest.approx((0, 1, 0), abs=1e-9)     # towards the light: up


@pytest.mark.parametrize("data, words", [
    (b"not json at all", "not glTF JSON"),
    (b'{"asset": {"version": "1.0"}}', "not a glTF 2.0 file"),
    (b"glTF\x02\x00\x00\x00", "shorter than its 20-byte header"),
])
def test_bad_gltf_files_are_one_line(tmp_path, data, words):
    path = tmp_path / ("bad.glb" if data.startswith(b"glTF") else "bad.gltf")
    path.write_bytes(data)
    with pytest.raises(ReaderError, match=words):
        load_scene(path)


def test_a_buffer_outside_the_files_folder_is_not_read(tmp_path):
    files = _two_objects().export(file_type="gltf")
    doc = json.loads(files["model.gltf"])
    doc["buffers"][0]["uri"] = "../../etc/passwd"
    path = tmp_path / "sneaky.gltf"
    path.write_text(json.dumps(doc))
    with pytest.raises(ReaderError, match=r"buffers\[0\] '../../etc/passwd' lies outside the "
                                          r"file's folder: not read"):
        load_scene(path)


def test_a_gltf_with_its_external_bin_loads_and_a_missing_bin_is_one_line(tmp_path):
    path = _gltf_with_camera_and_lights(tmp_path)
    assert len(load_scene(path).meshes) == 2
    for other in tmp_path.iterdir():
        if other.suffix == ".bin":
            other.unlink()
    with pytest.raises(ReaderError, match=r"buffers\[0\] .*: no such file beside it"):
        load_scene(path)


def test_a_node_graph_with_a_cycle_is_read_once_per_node():
    from core.scene.formats.gltf import node_matrices
    doc = {"nodes": [{"children": [1], "translation": [1, 0, 0]},
                     {"children": [0], "translation": [0, 2, 0]}],
           "scenes": [{"nodes": [0]}]}
    world = node_matrices(doc)
    assert sorted(world) == [0, 1]
    assert world[1][:3, 3] == pytest.approx((1, 2, 0))


def test_a_million_nodes_are_refused_before_they_are_walked(tmp_path):
    path = tmp_path / "many.gltf"
    path.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": [{}] * 1_000_000}))
    with pytest.raises(ReaderError, match=r"1,000,000 nodes; at most 100,000"):
        load_scene(path)


def test_the_cameras_picture_agrees_with_llvmpipe_using_the_gltfs_own_matrices(tmp_path):
    # The oracle: OpenGL draws the same world triangles with glTF's own camera: the view
    # matrix is the inverse of the camera node's world matrix, the projection the glTF
    # specification's perspective matrix of yfov, aspectRatio, znear, zfar. Which pixels are
    # covered must agree with our course view of the same camera.
    from tests.tools import llvmpipe_context
    size = (200, 200)
    scene = load_scene(_gltf_with_camera_and_lights(tmp_path), size=size)
    ours = render(scene, scene.views[0], RenderSettings.for_scene(scene, shading="flat"))
    covered = np.isfinite(ours.depth)
    yfov, aspect, near, far = 0.8, 1.0, 0.1, 100.0
    f = 1.0 / math.tan(yfov / 2)
    projection = np.array([[f / aspect, 0, 0, 0], [0, f, 0, 0],
                           [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
                           [0, 0, -1, 0]])
    camera = np.eye(4)
    camera[:3, 3] = (0, 0, 5)                       # the "eye" node: a translation only
    mvp = projection @ np.linalg.inv(camera)
    ctx = llvmpipe_context()
    try:
        program = ctx.program(
            vertex_shader="#version 330\nuniform mat4 mvp; in vec3 p;\n"
                          "void main() { gl_Position = mvp * vec4(p, 1.0); }",
            fragment_shader="#version 330\nout vec4 c; void main() { c = vec4(1.0); }")
        program["mvp"].write(mvp.T.astype("f4").tobytes())        # GL is column-major
        points = np.concatenate([m.positions[m.triangles].reshape(-1, 3) for m in scene.meshes])
        buffer = ctx.buffer(points.astype("f4").tobytes())
        vao = ctx.vertex_array(program, [(buffer, "3f", "p")])
        target = ctx.simple_framebuffer(size)
        target.use()
        target.clear(0.0, 0.0, 0.0, 1.0)
        vao.render()
        gl = np.frombuffer(target.read(components=1), np.uint8).reshape(size[1], size[0])
    finally:
        ctx.release()
    theirs = gl[::-1] > 0                           # GL's rows run bottom up
    assert theirs.mean() > 0.1
    # the same pixels but for the edges' rounding: a pixel or so along the outlines
    assert np.mean(covered != theirs) < 0.01, np.mean(covered != theirs)


def _textured_quad(tmp_path, factor=(255, 255, 255, 255)):
    """A unit quad in z = 0 with (u, v) over [0, 1]² and a 64 x 64 PNG whose quadrants are
    red (top left), green (top right), blue (bottom left) and white, as a .glb and as an OBJ
    with ``vt`` beside the same PNG."""
    from PIL import Image
    pixels = np.zeros((64, 64, 3), np.uint8)
    pixels[:32, :32] = (255, 0, 0)
    pixels[:32, 32:] = (0, 255, 0)
    pixels[32:, :32] = (0, 0, 255)
    pixels[32:, 32:] = (255, 255, 255)
    Image.fromarray(pixels).save(tmp_path / "tex.png")
    corners = np.array([[-1.0, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]])
    uv = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    material = trimesh.visual.material.PBRMaterial(
        baseColorTexture=Image.open(tmp_path / "tex.png"), baseColorFactor=factor,
        metallicFactor=0.0, roughnessFactor=1.0)
    quad = trimesh.Trimesh(corners, faces, process=False,
                           visual=trimesh.visual.TextureVisuals(uv=uv, material=material))
    (tmp_path / "quad.glb").write_bytes(quad.export(file_type="glb"))
    (tmp_path / "quad.obj").write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in corners)
        + "".join(f"vt {u} {v}\n" for u, v in uv) + "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")
    return tmp_path / "quad.glb"


def test_a_textured_quad_draws_as_the_same_quad_in_a_toml_scene(tmp_path):
    """The glTF's base colour texture against our own reader's: the quad as an OBJ with
    ``vt`` and the PNG as ``texture``, lit by the same model with the glTF's material
    (metallic 0, roughness 1: k_d 0.98, k_s 1, m 1, F0 0.04), drawn through the same view."""
    glb = load_scene(_textured_quad(tmp_path))
    (tmp_path / "quad.toml").write_text(
        'background = [0.1, 0.1, 0.12]\nambient = [0.15, 0.15, 0.15]\n'
        '[[geometry]]\nfile = "quad.obj"\nmaterial = { ka = 0.2, kd = 0.98, ks = 1.0, '
        'od = [1, 1, 1], model = "cook-torrance", roughness = 1.0, f0 = 0.04, '
        'texture = "tex.png" }\n')
    toml = load_scene(tmp_path / "quad.toml")
    assert glb.meshes[0].uv is not None
    view = glb.views[0]
    settings = RenderSettings.for_scene(glb, size=(96, 96), shading="phong")
    a = render(glb, view, settings).color.astype(int)
    b = render(toml, view, settings).color.astype(int)
    assert np.abs(a - b).max() <= 1, np.abs(a - b).max()
    # the quadrants where the picture says: the top-left quarter of the picture is red
    q = a[20:28, 20:28].mean(axis=(0, 1))
    assert q[0] > 2 * max(q[1], q[2]), q


def test_the_base_colour_factor_multiplies_the_decoded_texture(tmp_path):
    """glTF: base colour = factor x texel (texel decoded from sRGB); the white quadrant with
    a factor of (0.5, 1, 1) becomes linear (0.5, 1, 1), which our O_d is."""
    scene = load_scene(_textured_quad(tmp_path, factor=(128, 255, 255, 255)))
    from core.texture.material import maps_of
    texture = maps_of(scene.meshes[0].material).color
    level = texture.levels[0]                       # row 0 at v = 0: the bottom of the PNG
    assert np.allclose(level[0, -1, :3], (128 / 255, 1.0, 1.0), atol=1e-6)   # white, bottom right
    assert np.allclose(level[-1, 0, :3], (128 / 255, 0.0, 0.0), atol=1e-6)   # red, top left


def _quad_gltf_by_hand(tmp_path, image_uri: str):
    """A .gltf written by hand (JSON, and its .bin: positions, TEXCOORD_0, indices) whose
    material's base colour texture is the image file ``image_uri``."""
    positions = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float32)
    uv = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)      # glTF's v runs down
    indices = np.array([0, 1, 2, 0, 2, 3], np.uint16)
    blob = positions.tobytes() + uv.tobytes() + indices.tobytes()
    (tmp_path / "quad.bin").write_bytes(blob)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                       "indices": 2, "material": 0}]}],
           "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                    "metallicFactor": 0.0}}],
           "textures": [{"source": 0}], "images": [{"uri": image_uri}],
           "buffers": [{"uri": "quad.bin", "byteLength": len(blob)}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                           {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                           {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-1, -1, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                         {"bufferView": 2, "componentType": 5123, "count": 6,
                          "type": "SCALAR"}]}
    path = tmp_path / "quad.gltf"
    path.write_text(json.dumps(doc))
    return path


def test_a_hand_written_gltf_reads_its_texture_the_right_way_up(tmp_path):
    """glTF's (u, v) has v down the image; the quad's top-left corner has (0, 0), the PNG's
    top-left texel: the top-left of the picture is red."""
    _textured_quad(tmp_path)                                   # writes tex.png
    scene = load_scene(_quad_gltf_by_hand(tmp_path, "tex.png"))
    settings = RenderSettings.for_scene(scene, size=(96, 96), shading="phong")
    image = render(scene, scene.views[0], settings).color.astype(float)
    corners = {"top left": image[20:28, 20:28], "top right": image[20:28, 68:76],
               "bottom left": image[68:76, 20:28]}
    means = {k: v.mean(axis=(0, 1)) for k, v in corners.items()}
    assert means["top left"][0] > 2 * max(means["top left"][1:]), means
    assert means["top right"][1] > 2 * max(means["top right"][[0, 2]]), means
    assert means["bottom left"][2] > 2 * max(means["bottom left"][:2]), means


def test_an_image_that_is_a_decompression_bomb_is_one_line(tmp_path):
    """A PNG whose header says 20000 x 20000 (400 M texels, a few hundred bytes on disk):
    refused from its header, one line naming the file, nothing decoded."""
    import struct as st
    import zlib

    def chunk(kind, data):
        return st.pack(">I", len(data)) + kind + data + st.pack(">I", zlib.crc32(kind + data))
    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", st.pack(">IIBBBBB", 20000, 20000, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(b"\x00" * 60001, 9)) + chunk(b"IEND", b""))
    (tmp_path / "bomb.png").write_bytes(png)
    with pytest.raises(ReaderError) as error:
        load_scene(_quad_gltf_by_hand(tmp_path, "bomb.png"))
    message = str(error.value)
    assert "quad.gltf" in message and "\n" not in message


def test_a_white_dielectric_is_drawn_by_radiosity_and_the_path_tracer(tmp_path):
    """glTF's white, metallic 0: k_d 0.98, so rho = k_d O_d stays below 1 and the two global
    renderers draw it rather than refuse it (a red box and a metal ball, lit by the default
    lights: radiosity's picture is not one flat colour)."""
    path = tmp_path / "two.glb"
    path.write_bytes(_two_objects().export(file_type="glb"))
    scene = load_scene(path)
    for renderer in ("radiosity", "pathtrace"):
        settings = RenderSettings.for_scene(scene, size=(48, 48), renderer=renderer)
        frame = render(scene, scene.views[0], settings.replace(
            **({"samples": 1} if renderer == "pathtrace" else {"max_elements": 200})))
        assert frame.message is None or "cannot" not in frame.message, frame.message
        box = frame.color[frame.color[..., 0] > frame.color[..., 1] + 60]    # the red box
        assert len(box) > 20, renderer


def test_an_accessor_that_overruns_its_buffer_and_a_truncated_glb_are_one_line(tmp_path):
    """An accessor counting 10^6 vertices in a 48-byte view, and a .glb cut inside its
    binary chunk: one line naming the file, nothing read past the data."""
    _textured_quad(tmp_path)
    path = _quad_gltf_by_hand(tmp_path, "tex.png")
    doc = json.loads(path.read_text())
    doc["accessors"][0]["count"] = 1_000_000
    path.write_text(json.dumps(doc))
    with pytest.raises(ReaderError) as error:
        load_scene(path)
    assert "quad.gltf" in str(error.value) and "\n" not in str(error.value)
    whole = (tmp_path / "quad.glb").read_bytes()
    cut = tmp_path / "cut.glb"
    cut.write_bytes(whole[:len(whole) - 200])
    with pytest.raises(ReaderError) as error:
        load_scene(cut)
    assert "cut.glb" in str(error.value) and "\n" not in str(error.value)
