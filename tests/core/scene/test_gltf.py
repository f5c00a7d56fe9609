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
    assert box.material.od == (1.0, 0.0, 0.0) and box.material.kd == 1.0
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
