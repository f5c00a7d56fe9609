"""The readers (core.scene.formats): .tri with its camera, mesh files, TOML scenes, view files.

Every reader is held against small hand-made inputs whose numbers are worked out by hand, and
every kind of bad input must give a ReaderError naming the file, the line and the reason.
"""

from __future__ import annotations

import io
import struct
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from conftest import DATA

from core.settings import RenderSettings
from core.scene import generators
from core.pipeline import project
from core.scene.formats import ReaderError, load_scene, read_mesh, read_scene_file, read_tri
from core.scene.formats.mesh import edge_problem, merge_vertices, signed_volume
from core.paths import SCENES_DIR
from core.render import render
from core.transforms import apply
from core.camera.view import normalizing_transform, problems



def tri_text(viewpoint, top_left, right, down, triangles, count=None) -> str:
    rows = [viewpoint, top_left, right, down]
    lines = [" ".join(f"{x:.17g}" for x in row) for row in rows]
    lines.append(str(len(triangles) if count is None else count))
    lines += [" ".join(f"{x:.17g}" for x in np.asarray(t, float).ravel()) for t in triangles]
    return "\n".join(lines) + "\n"


def course_pixel(point, viewpoint, top_left, right, down):
    """Where the startup code puts ``point``: eye + t (P - eye) = top_left + i right + j down."""
    a = np.column_stack([right, down, -(np.asarray(point) - viewpoint)])
    i, j, _ = np.linalg.solve(a, np.asarray(viewpoint) - top_left)
    return i, j


def our_pixel(scene, point, size):
    """Column and image row (pixel centres at integers) of ``point`` through view 1 of ``scene``."""
    view = scene.views[0]
    n, z_min = normalizing_transform(view, "perspective")
    vp = project.viewport(view.window, *size)
    device, _ = project.project_triangles(apply(n, np.atleast_2d(point))[:, :3], "perspective", z_min, vp)
    x, y = device[0, 0], device[0, 1]
    return x - 0.5, size[1] - y - 0.5


# ----------------------------------------------------------------------------- .tri

SQUARE = [[(-1, -1, -2), (1, -1, -2), (1, 1, -1)],
          [(-1, -1, -2), (1, 1, -1), (-1, 1, -1)]]


def test_tri_hand_made_scene():
    text = tri_text((0, 0, 10), (-1, 1, 0), (0.004, 0, 0), (0, -0.004, 0), SQUARE)
    scene = read_tri(text, "square.tri")
    mesh = scene.meshes[0]
    # Two triangles share two corners: 4 vertices, numbered in order of first appearance.
    assert mesh.positions.tolist() == [[-1, -1, -2], [1, -1, -2], [1, 1, -1], [-1, 1, -1]]
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]
    assert mesh.closed is False and mesh.normals is None
    view = scene.views[0]
    # VRP = top-left; u = right/|right| = x; v = -down/|down| = y; n = u x v = z.
    assert view.vrp == (-1, 1, 0) and view.vpn == (0, 0, 1) and view.vup == (0, 1, 0)
    # Pixel centres: u = 0.004 i, v = -0.004 j; the window reaches half a pixel beyond them.
    assert view.window == pytest.approx((-0.002, 499.5 * 0.004, -499.5 * 0.004, 0.002))
    # PRP = viewpoint - VRP in VRC.
    assert view.prp == pytest.approx((1, -1, 10))
    # Depths along n: -2 (far) and -1 (near); pad = 1% of (10 - (-2)) = 0.12.
    assert view.back == pytest.approx(-2.12)
    assert view.front == pytest.approx(-0.88)
    assert problems(view, "perspective") == []
    # The startup code's light: (vx + 40 rx, vy + 40 dy, vz).
    assert scene.lights[0].position == pytest.approx((0.16, -0.16, 10))
    assert scene.size == (500, 500) and scene.projection == "perspective"
    assert len(scene.views) == 4                  # the camera, then three framing views


def test_tri_size_sets_the_window():
    text = tri_text((0, 0, 10), (-1, 1, 0), (0.004, 0, 0), (0, -0.004, 0), SQUARE)
    scene = read_tri(text, "square.tri", size=(640, 480))
    assert scene.size == (640, 480)
    assert scene.views[0].window == pytest.approx((-0.002, 639.5 * 0.004, -479.5 * 0.004, 0.002))


def test_tri_equal_vertices_are_hashed():
    # A 60 x 60 grid of quads as a soup: 7200 triangles, 21600 corners, 61^2 distinct points.
    ticks = np.arange(61, dtype=float)
    x, y = np.meshgrid(ticks, ticks, indexing="ij")
    p = np.stack([x, y, np.full_like(x, -5.0)], -1)
    a, b, c, d = p[:-1, :-1], p[1:, :-1], p[:-1, 1:], p[1:, 1:]
    soup = np.concatenate([np.stack([a, b, d], 2).reshape(-1, 3, 3),
                           np.stack([a, d, c], 2).reshape(-1, 3, 3)])
    text = tri_text((30, 30, 50), (0, 60, 0), (0.12, 0, 0), (0, -0.12, 0), soup)
    mesh = read_tri(text, "grid.tri").meshes[0]
    assert len(mesh.triangles) == 7200
    assert len(mesh.positions) == 61 * 61
    assert np.array_equal(mesh.positions[mesh.triangles], soup)


def test_merge_vertices_first_appearance_and_signed_zero():
    points = np.array([(1, 2, 3), (0.0, 0, 0), (1, 2, 3), (-0.0, 0, -0.0), (5, 5, 5)])
    positions, inverse = merge_vertices(points)
    assert positions.tolist() == [[1, 2, 3], [0, 0, 0], [5, 5, 5]]
    assert inverse.tolist() == [0, 1, 0, 1, 2]


CAMERAS = {
    "axis-aligned": ((0.3, -0.2, 12.0), (-2.0, 2.0, 2.0), (0.008, 0, 0), (0, -0.008, 0)),
    # A camera turned about two axes; its displacements are perpendicular and 1.3 : 1.
    "turned": None,
}


def _turned_camera():
    yaw, pitch = np.radians(25.0), np.radians(-15.0)
    right = np.array([np.cos(yaw), 0.0, -np.sin(yaw)])
    up = np.array([np.sin(yaw) * np.sin(pitch), np.cos(pitch), np.cos(yaw) * np.sin(pitch)])
    forward = np.cross(up, right)
    eye = np.array([4.0, 1.5, 9.0])
    centre = eye + 2.0 * forward
    r, d = 0.006 * right, -0.006 * up
    return eye, centre - 250 * r - 200 * d, r, d


@pytest.mark.parametrize("size", [(500, 500), (400, 300)])
@pytest.mark.parametrize("name", ["axis-aligned", "turned", "behind the screen"])
def test_tri_vertex_lands_on_the_course_pixel(name, size):
    """Each vertex goes through N_per, M and the viewport to the pixel the .tri camera says."""
    if name == "axis-aligned":
        viewpoint, top_left, right, down = map(np.array, CAMERAS[name])
    else:
        viewpoint, top_left, right, down = _turned_camera()
    if name == "behind the screen":
        # Move the eye to the mirror image of itself across the screen plane: the course's
        # camera then looks at the grid from behind; the reader mirrors the world.
        n = np.cross(right, -down)
        n /= np.linalg.norm(n)
        viewpoint = viewpoint - 2 * np.dot(viewpoint - top_left, n) * n
    # Points well inside the image, in front of the eye.
    rng = np.random.default_rng(7)
    targets = []
    for _ in range(6):
        i, j = rng.uniform(20, size[0] - 20), rng.uniform(20, size[1] - 20)
        screen = top_left + i * right + j * down
        targets.append(viewpoint + rng.uniform(1.5, 4.0) * (screen - viewpoint))
    triangles = [targets[0:3], targets[3:6]]
    scene = read_tri(tri_text(viewpoint, top_left, right, down, triangles), "t.tri", size=size)
    if name == "behind the screen":
        assert "mirrored" in scene.views[0].label
    for k, point in enumerate(targets):
        want = course_pixel(point, viewpoint, top_left, right, down)
        got = our_pixel(scene, scene.meshes[0].positions[k], size)
        assert got == pytest.approx(want, abs=1e-6)


def test_tri_render_puts_vertices_on_their_pixels():
    """Rendered (wireframe), each vertex of a triangle lights exactly the pixel the camera says."""
    viewpoint, top_left, right, down = _turned_camera()
    pixels = [(123, 77), (301, 110), (200, 388)]
    corners = [viewpoint + 3.0 * (top_left + i * right + j * down - viewpoint) for i, j in pixels]
    scene = read_tri(tri_text(viewpoint, top_left, right, down, [corners]), "one.tri")
    scene.line_color = (1.0, 1.0, 1.0)
    frame = render(scene, scene.views[0],
                   RenderSettings.for_scene(scene, projection="perspective", shading="wireframe", size=(500, 500)))
    assert frame.message is None
    lit = np.any(frame.color > 0, axis=2)
    for i, j in pixels:
        assert lit[j, i], f"pixel column {i}, row {j} is not drawn"
    # ... and the picture is that triangle's outline: nothing far from it is lit.
    rows, cols = np.nonzero(lit)
    assert cols.min() >= 122 and cols.max() <= 302 and rows.min() >= 76 and rows.max() <= 389


def test_tri_front_plane_cuts_geometry_behind_the_eye():
    scene = load_scene(SCENES_DIR / "crossing_front_plane.tri")
    view = scene.views[0]
    n, z_min = normalizing_transform(view, "perspective")
    depth = (scene.meshes[0].positions - np.array(view.vrp)) @ np.array(view.vpn)
    assert depth.max() > view.prp[2] > view.front > view.back     # reaches behind the eye
    assert view.front < depth.max() and depth.min() > view.back
    assert -1 < z_min < -0.005                                     # front plane kept off the eye


@pytest.mark.parametrize("file, line, reason", [
    ("empty.tri", 1, "the file ends before the header is complete"),
    ("truncated.tri", 9, "expected 9 numbers for triangle 3, got 5"),
    ("not_a_number.tri", 6, "'one' is not a number"),
    ("nan.tri", 7, "triangle 2, vertex 3 has a coordinate that is NaN"),
    ("inf.tri", 1, "the viewpoint has a coordinate that is infinite"),
    ("negative_count.tri", 5, "the triangle count must be a whole number >= 0, got '-1'"),
    ("huge_count.tri", 6, "the file ends after 1 triangle, but the count on line 5 says 1000000000000"),
    ("extra_numbers.tri", 7, "more numbers than the count on line 5 says (1 triangle)"),
    ("junk.tri", 3, "not a text file: byte 0x89"),
    ("index_out_of_range.obj", 7, "face index 7 is out of range: 4 vertices are defined"),
    ("nan_vertex.obj", 2, "vertex coordinate 'nan' is NaN or infinite"),
    ("huge_count.ply", 3, "the header says element 'vertex' has 1000000000000 rows"),
    ("huge_count.off", 2, "the counts say 3 vertices and 1000000000 faces"),
    ("unknown_key.toml", 8, "geometry[2].colour: unknown key 'colour'"),
    ("wrong_type.toml", 5, "geometry[1].material.kd: expected a number, got a string ('lots')"),
    ("syntax_error.toml", 5, "TOML: Invalid initial character for a key part"),
])
def test_bad_files_name_file_line_and_reason(file, line, reason):
    path = DATA / file
    with pytest.raises(ReaderError) as caught:
        load_scene(str(path))
    error = caught.value
    assert str(error).startswith(f"{path}:{line}: "), str(error)
    assert reason in str(error)
    assert error.file == str(path) and error.line == line


def _tri_error(text: str | bytes) -> ReaderError:
    with pytest.raises(ReaderError) as caught:
        read_tri(text, "x.tri")
    return caught.value


HEADER = "0 0 10\n-1 1 0\n0.004 0 0\n0 -0.004 0\n"


@pytest.mark.parametrize("text, line, reason", [
    (HEADER + "2.5\n", 5, "the triangle count must be a whole number >= 0, got '2.5'"),
    (HEADER + "1e3\n", 5, "the triangle count must be a whole number >= 0, got '1e3'"),
    (HEADER, 4, "the file ends before the triangle count N"),
    ("0 0 10\n-1 1\n", 2, "the top-left corner needs 3 numbers"),
    (HEADER + "1\n0 0 -1 1 0 -1 0 1 1e40\n", 6, "too large"),
    (HEADER + "2\n0 0 -1 1 0 -1 0 1 -1\n", 6, "the file ends after 1 triangle, but the count on line 5 says 2"),
    (HEADER + "0\n", None, None),                                       # empty scene: fine
    ("0 0 10\n-1 1 0\n0 0 0\n0 -0.004 0\n0\n", 3, "the right displacement is zero"),
    ("0 0 10\n-1 1 0\n0.004 0 0\n0.001 -0.004 0\n0\n", 3, "not perpendicular"),
    ("0 0 0\n-1 1 0\n0.004 0 0\n0 -0.004 0\n0\n", 1, "the viewpoint lies on the screen plane"),
    ("0 0 10 # the eye\n-1 1 0\n0.004 0 0\n0 -0.004 0\n1 # one triangle\n0 0 -1 1 0 -1\n0 1 -1\n",
     None, None),                                                       # comments, split lines
])
def test_tri_messages(text, line, reason):
    if reason is None:
        assert read_tri(text, "x.tri").meshes[0] is not None
        return
    error = _tri_error(text)
    assert error.line == line, str(error)
    assert reason in error.reason, str(error)
    assert str(error).startswith(f"x.tri:{line}: ")


def test_tri_huge_count_allocates_nothing():
    text = HEADER + "999999999999999999\n" + "0 0 -1 1 0 -1 0 1 -1\n" * 3
    tracemalloc.start()
    try:
        _tri_error(text)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 2_000_000


# ----------------------------------------------------------------------------- mesh files

OBJ = b"""# a unit square as one quad, and a triangle with negative (relative) indices
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
f 1 2 3 4
v 0 0 1
f -1 -5 -4
"""


def test_obj_polygons_are_fanned_and_negative_indices_resolved():
    mesh = read_mesh(OBJ, "sq.obj", ".obj")
    assert len(mesh.positions) == 5 and mesh.normals is None and not mesh.closed
    tris = {tuple(t) for t in mesh.positions[mesh.triangles].round(6).reshape(-1, 9).tolist()}
    # The quad became two triangles covering it; the last face is (v5, v1, v2).
    area = 0.5 * np.linalg.norm(np.cross(*(mesh.positions[mesh.triangles[:, 1:]]
                                           - mesh.positions[mesh.triangles[:, :1]]).transpose(1, 0, 2)), axis=1)
    assert len(tris) == 3 and area.sum() == pytest.approx(1.0 + 0.5)
    assert (0, 0, 1, 0, 0, 0, 1, 0, 0) in tris


def test_obj_keeps_the_files_normals():
    obj = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 2\nvn 0 0.6 0.8\nvn 0 0 1\n" \
          b"f 1//1 2//2 3//3 4//4\n"
    mesh = read_mesh(obj, "n.obj", ".obj")
    assert mesh.normals is not None
    assert mesh.normals[2].tolist() == pytest.approx([0, 0.6, 0.8])
    assert mesh.normals[1].tolist() == pytest.approx([0, 0, 1])       # normalised


def _cube_soup() -> np.ndarray:
    cube = generators.cube()
    return cube.positions[cube.triangles]


def _ply(binary: bool) -> bytes:
    cube = generators.cube()
    head = (f"ply\nformat {'binary_little_endian' if binary else 'ascii'} 1.0\n"
            f"element vertex {len(cube.positions)}\nproperty float x\nproperty float y\n"
            f"property float z\nelement face {len(cube.triangles)}\n"
            f"property list uchar int vertex_indices\nend_header\n").encode()
    if binary:
        body = cube.positions.astype("<f4").tobytes()
        body += b"".join(struct.pack("<B3i", 3, *t) for t in cube.triangles.tolist())
    else:
        body = "".join(f"{x} {y} {z}\n" for x, y, z in cube.positions.tolist()).encode()
        body += "".join(f"3 {a} {b} {c}\n" for a, b, c in cube.triangles.tolist()).encode()
    return head + body


def _stl(binary: bool) -> bytes:
    soup = _cube_soup()
    if binary:
        rows = np.zeros(len(soup), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
        rows["v"] = soup
        return b"\0" * 80 + struct.pack("<I", len(soup)) + rows.tobytes()
    text = "solid cube\n"
    for t in soup:
        text += "facet normal 0 0 0\nouter loop\n" + "".join(f"vertex {x} {y} {z}\n" for x, y, z in t)
        text += "endloop\nendfacet\n"
    return (text + "endsolid cube\n").encode()


def _off() -> bytes:
    cube = generators.cube()
    text = f"OFF\n# a cube\n{len(cube.positions)} {len(cube.triangles)} 0\n"
    text += "".join(f"{x} {y} {z}\n" for x, y, z in cube.positions.tolist())
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in cube.triangles.tolist())
    return text.encode()


@pytest.mark.parametrize("ext, data", [
    (".ply", _ply(False)), (".ply", _ply(True)), (".stl", _stl(False)), (".stl", _stl(True)),
    (".off", _off()),
])
def test_mesh_formats_give_the_same_closed_cube(ext, data):
    """A cube in every format: 8 vertices once STL's soup is merged, closed, outward."""
    mesh = read_mesh(data, f"cube{ext}", ext)
    assert len(mesh.positions) == 8 and len(mesh.triangles) == 12
    assert mesh.closed and edge_problem(mesh.triangles) is None
    assert signed_volume(mesh.positions, mesh.triangles) == pytest.approx(8.0)
    assert np.array_equal(np.sort(mesh.positions[mesh.triangles].reshape(-1, 9), axis=0),
                          np.sort(_cube_soup().reshape(-1, 9), axis=0))


@pytest.mark.parametrize("ext, data, reason", [
    (".obj", b"", "the file is empty"),
    (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "face index 0 is out of range"),
    (".obj", b"v 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", "a vertex needs 3 coordinates, got 2"),
    (".obj", b"v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n", "vertex coordinate 'x' is not a number"),
    (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", "a face needs at least 3 vertices, got 2"),
    (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 2 3\n", "face index -4 is out of range"),
    (".obj", b"v 0 0 0\nf 1 1 1\n\xff\xfe\x00", "not a text file"),
    (".obj", b"v 0 0 0\nv 1 0 0\n", "the file holds no triangles"),
    (".ply", b"\x00\x01binary junk", "not a PLY file"),
    (".ply", _ply(False).replace(b"3 0 1 2\n", b"3 0 1 99\n", 1), "refers to vertex"),
    (".ply", _ply(True)[:-7], "the mesh library could not read it"),
    (".stl", b"\x00" * 80 + struct.pack("<I", 10 ** 9) + b"\x00" * 50, "not an STL file"),
    (".off", b"OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n", "the mesh library could not read it"),
    (".off", b"NOT\n", "not an OFF file"),
])
def test_mesh_messages(ext, data, reason):
    with pytest.raises(ReaderError) as caught:
        read_mesh(data, f"bad{ext}", ext)
    assert reason in str(caught.value)
    assert str(caught.value).startswith(f"bad{ext}")


def test_bunny_loads_with_framing_views(bunny_path):
    scene = load_scene(bunny_path)
    mesh = scene.meshes[0]
    assert len(mesh.triangles) == 69451
    # no two of the file's 35947 vertices coincide; the default crease angle (45°) splits the
    # 271 where its scan's rims fold sharply; 180° splits none
    assert len(mesh.positions) == 35947 + 271
    assert len(load_scene(bunny_path, crease_angle=180.0).meshes[0].positions) == 35947
    assert not mesh.closed                   # it has holes in its base
    assert [v.label.rsplit(": ", 1)[1] for v in scene.views] == ["front view", "three-quarter view",
                                                                  "top view"]
    for view in scene.views:
        assert problems(view, "perspective") == [] and problems(view, "parallel") == []
        n, z_min = normalizing_transform(view, "perspective")
        c = apply(n, mesh.positions)[:, :3]
        # Every vertex is inside the canonical perspective volume: the views frame the bunny.
        assert np.all(np.abs(c[:, :2]) <= -c[:, 2:3]) and np.all((c[:, 2] >= -1) & (c[:, 2] <= z_min))
    assert len(scene.lights) >= 1


# ----------------------------------------------------------------------------- TOML scenes

FULL = """
name = "everything"
shading = "phong"
projection = "parallel"
specular = "halfway"
size = [320, 200]
ambient = [0.1, 0.2, 0.3]
background = [0.0, 0.1, 0.2]
line_color = [1, 1, 0]

[[geometry]]
generator = "uv_sphere"
params = { radius = 2.0, segments = 8, rings = 4 }
transform = { scale = 0.5, rotate = [0, 0, 90], translate = [10, 0, 0] }
material = { ka = 0.1, kd = 0.5, ks = 0.4, n = 12, od = [1, 0, 0], os = [0.5, 0.5, 0.5] }

[[geometry]]
generator = "cube"
name = "mirror cube"
transform = { scale = [-1, 2, 1] }
closed = true

[[view]]
name = "front"
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 5]
front = 2
back = -2

[[view]]
name = "broken"
vrp = [0, 0, 0]
vpn = [0, 0, 0]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 5]
front = 2
back = -2

[[light]]
position = [1, 2, 3]
intensity = [0.5, 0.6, 0.7]
attenuation = [1, 0.1, 0.01]

[[light]]
direction = [0, 0, 1]
"""


def test_toml_scene_reads_every_key():
    scene = read_scene_file(FULL, "full.toml", Path("."))
    assert (scene.name, scene.shading, scene.projection, scene.specular) == \
        ("everything", "phong", "parallel", "halfway")
    assert scene.size == (320, 200) and scene.ambient == (0.1, 0.2, 0.3)
    assert scene.background == (0.0, 0.1, 0.2) and scene.line_color == (1, 1, 0)
    sphere, cube = scene.meshes
    # S(0.5) then R_z(90 degrees) then T(10, 0, 0): the north pole (0, 2, 0) -> (9, 0, 0).
    assert sphere.positions[0] == pytest.approx((9, 0, 0))
    assert sphere.normals[0] == pytest.approx((-1, 0, 0))
    assert sphere.material.od == (1, 0, 0) and sphere.material.n == 12 and sphere.material.os == (0.5,) * 3
    # A mirroring scale turns the winding over, so the cube still faces outward.
    assert cube.name == "mirror cube" and cube.closed
    assert signed_volume(cube.positions, cube.triangles) == pytest.approx(16.0)
    assert len(scene.views) == 1 and scene.views[0].label.startswith("full.toml: view 1 (front)")
    assert len(scene.view_messages) == 1
    assert scene.view_messages[0].startswith("full.toml: view 2 (broken) (line 33): VPN is zero")
    point, sun = scene.lights
    assert point.position == (1, 2, 3) and point.intensity == (0.5, 0.6, 0.7)
    assert point.attenuation == (1, 0.1, 0.01)
    assert sun.direction == (0, 0, 1) and sun.position is None and sun.intensity == (1, 1, 1)


def test_toml_auto_views_default_lights_and_size_override():
    scene = read_scene_file('[[geometry]]\ngenerator = "torus"\n', "t.toml", Path("."), size=(64, 48))
    assert len(scene.views) == 3 and scene.name == "t" and scene.size == (64, 48)
    assert scene.lights and scene.meshes[0].closed


def test_toml_files_relative_to_the_scene(tmp_path):
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "sq.obj").write_bytes(OBJ)
    (tmp_path / "two.views").write_text((DATA / "two.views").read_text())
    (tmp_path / "s.toml").write_text('views = "two.views"\n[[geometry]]\nfile = "meshes/sq.obj"\n'
                                     'transform = { translate = [0, 0, 5] }\n')
    scene = load_scene(tmp_path / "s.toml")
    assert len(scene.meshes[0].triangles) == 3
    assert scene.meshes[0].positions[:, 2].min() == 5
    assert len(scene.views) == 1 and len(scene.view_messages) == 1


def _toml_error(text: str) -> ReaderError:
    with pytest.raises(ReaderError) as caught:
        read_scene_file(text, "bad.toml", DATA)
    return caught.value


CUBE = '[[geometry]]\ngenerator = "cube"\n'


@pytest.mark.parametrize("text, line, reason", [
    ('colour = 1\n' + CUBE, 1, "colour: unknown key 'colour'"),
    ('name = "x"\n', None, "a scene needs at least one [[geometry]] or [[volume]] table"),
    ('shading = "gouraud shading"\n' + CUBE, 1, "shading: 'gouraud shading' is not one of"),
    ('size = [500.5, 10]\n' + CUBE, 1, "size: expected whole numbers of pixels"),
    ('size = [100000000000000000000000000000000000, 10]\n' + CUBE, 1, "size[1]"),
    ('ambient = [nan, 0, 0]\n' + CUBE, 1, "ambient[1]: expected a finite number, got nan"),
    ('background = [1, 2, 0]\n' + CUBE, 1, "background[2]: 2 is out of range [0, 1]"),
    ('views = "missing.views"\n' + CUBE, 1, "views: "),
    (CUBE + '[[geometry]]\nfile = "x.obj"\ngenerator = "cube"\n', 3, "geometry[2]: give exactly one"),
    (CUBE + '[[geometry]]\ngenerator = "dodecahedron"\n', 4, "geometry[2].generator: 'dodecahedron' is not one of"),
    (CUBE + 'params = { edges = 3 }\n', 3, "geometry[1].params.edges: unknown key 'edges'"),
    ('[[geometry]]\ngenerator = "torus"\nparams = { sides = 2 }\n', 3,
     "geometry[1].params: torus: sides must lie in 3..100000, got 2"),
    ('[[geometry]]\ngenerator = "torus"\nparams = { segments = 2.0 }\n', 3, "segments must be a whole number"),
    ('[[geometry]]\ngenerator = "icosphere"\nparams = { subdivisions = 10 }\n', 3, "the limit is"),
    ('[[geometry]]\ngenerator = "bezier_surface"\nclosed = true\n', 3,
     "geometry[1].closed: the mesh is not closed: edge"),
    ('[[geometry]]\nfile = "nan_vertex.obj"\n', 2, "vertex coordinate 'nan'"),
    ('[[geometry]]\nfile = "nowhere.obj"\n', None, "no such file"),
    ('[[geometry]]\nfile = "two.views"\n', 2, "not a mesh file type"),
    (CUBE + 'transform = { scale = 0 }\n', 3, "geometry[1].transform.scale: a scale factor is zero"),
    (CUBE + 'transform = { translate = [1e40, 0, 0] }\n', 3, "out of range"),
    (CUBE + '[geometry.material]\nkd = true\n', 4, "geometry[1].material.kd: expected a number, got a boolean"),
    (CUBE + '[[light]]\nintensity = [1, 1, 1]\n', 3, "light[1]: give exactly one of 'position'"),
    (CUBE + '[[light]]\ndirection = [0, 0, 0]\n', 4, "light[1].direction: the direction is zero"),
    (CUBE + '[[view]]\nvrp = [0, 0, 0]\n', 3, "view[1]: missing key 'vpn'"),
    (CUBE + 'generator = "torus"\n', 3, "TOML: Cannot overwrite a value (column"),
    ('a = [[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[[\n', 1,
     "TOML: brackets nested more than 64 deep"),
    ('a = [[[[[[[[[[\n', 1, "TOML: Invalid value (at the end of the file)"),
    ('a = ' + '[' * 5000 + ']' * 5000 + '\n', 1, "TOML: brackets nested more than 64 deep"),
])
def test_toml_messages(text, line, reason):
    error = _toml_error(text)
    assert reason in str(error), str(error)
    assert error.line == line, str(error)


# ----------------------------------------------------------------------------- view files and stdin

def test_bare_view_file_is_shown_with_the_house():
    scene = load_scene(DATA / "two.views")
    assert scene.meshes[0].name == "house" and len(scene.meshes[0].edges) == 15
    assert len(scene.views) == 1 and scene.shading == "wireframe"
    assert "view 2 (line 9): VPN is zero" in scene.view_messages[0]


def test_views_from_standard_input(monkeypatch):
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO((DATA / "two.views").read_bytes())))
    scene = load_scene("-")
    assert len(scene.views) == 1 and scene.source == "<stdin>"


def test_missing_file_and_bad_size():
    with pytest.raises(ReaderError, match="no such file"):
        load_scene("does/not/exist.toml")
    with pytest.raises(ReaderError, match="not a regular file"):
        load_scene("/dev/null")
    with pytest.raises(ReaderError, match="outside 1..8192"):
        load_scene(SCENES_DIR / "cube.toml", size=(0, 10))


# ----------------------------------------------------------------------------- shipped scenes

SHIPPED = sorted(p.name for p in SCENES_DIR.iterdir() if p.suffix in (".toml", ".tri"))


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_scene_loads(name):
    scene = load_scene(SCENES_DIR / name)
    assert len(scene.views) >= 1, name
    # lit by [[light]]s, or by emitting materials, which get no default lights
    emitters = any(any(m.material.emission) for m in scene.meshes)
    from core.volume.data import volumes_of
    alone = name == "volume_alone.toml"      # a [[volume]] and nothing else
    assert bool(scene.lights) != emitters or name in ("radiosity_room.toml", "two_pass.toml")
    assert scene.meshes or (alone and volumes_of(scene))
    if name != "house.toml":                  # the house's view file has invalid views on purpose
        assert scene.view_messages == []
    if name not in ("house.toml", "house_depth_cue.toml",       # the wireframe houses: lines only
                    "house_projections.toml", "volume_alone.toml"):
        assert scene.triangle_count > 0
    for view in scene.views:
        assert problems(view) == []


def test_shipped_scene_kinds():
    counts = {name: load_scene(SCENES_DIR / name).triangle_count for name in SHIPPED}
    assert counts["big.toml"] >= 100_000
    assert counts["few_triangles.tri"] < 10
    assert {"cube.toml", "icosphere.toml", "torus.toml", "bezier.toml", "sphere.toml",
            "house.toml", "interpenetrating.tri", "crossing_front_plane.tri"} <= set(counts)


def test_sphere_scene_is_the_analytic_unit_sphere():
    """The shading tests' reference is the sphere of radius 1 about the origin."""
    scene = load_scene(SCENES_DIR / "sphere.toml")
    mesh, = scene.meshes
    assert np.linalg.norm(mesh.positions, axis=1) == pytest.approx(1.0)
    assert np.allclose(mesh.normals, mesh.positions)
    assert len(scene.lights) == 1 and scene.lights[0].position is not None


def test_a_missing_file_is_named_once_with_its_reason(tmp_path):
    from core.scene.formats import ReaderError, load_scene
    with pytest.raises(ReaderError) as missing:
        load_scene(tmp_path / "nowhere.toml")
    assert str(missing.value) == f"{tmp_path / 'nowhere.toml'}: cannot read it: no such file"
    with pytest.raises(ReaderError) as folder:
        load_scene(tmp_path)
    assert str(folder.value).endswith(": cannot read it: not a regular file")
    assert str(folder.value).count("cannot read it") == 1


# --- found in review -----------------------------------------------------------------------

def test_a_huge_toml_integer_is_a_reader_error(tmp_path):
    text = '[[geometry]]\ngenerator = "torus"\nparams = { R = ' + "9" * 400 + ' }\n'
    with pytest.raises(ReaderError, match=r"geometry\[1\]\.params.*too large"):
        read_scene_file(text, "big.toml", tmp_path)


def test_huge_file_normals_are_normalised_without_overflow():
    obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 1e200 0 0\nvn 0 1e200 0\nvn 0 0 1e200\nf 1//1 2//2 3//3\n"
    mesh = read_mesh(obj.encode(), "big-normals.obj", ".obj")
    assert np.allclose(mesh.normals, np.eye(3))


def test_flat_shaded_obj_with_split_vertices_is_still_closed():
    cube = generators.cube()
    lines = [f"v {x} {y} {z}" for x, y, z in cube.positions]
    normals = np.cross(cube.positions[cube.triangles[:, 1]] - cube.positions[cube.triangles[:, 0]],
                       cube.positions[cube.triangles[:, 2]] - cube.positions[cube.triangles[:, 0]])
    lines += [f"vn {x} {y} {z}" for x, y, z in normals]
    lines += [f"f {a + 1}//{k + 1} {b + 1}//{k + 1} {c + 1}//{k + 1}"
              for k, (a, b, c) in enumerate(cube.triangles)]
    mesh = read_mesh("\n".join(lines).encode(), "flat-cube.obj", ".obj")
    assert mesh.normals is not None and mesh.closed


def test_closed_true_refuses_an_inside_out_mesh(tmp_path):
    cube = generators.cube()
    lines = [f"v {x} {y} {z}" for x, y, z in cube.positions]
    lines += [f"f {a + 1} {c + 1} {b + 1}" for a, b, c in cube.triangles]      # wound inward
    (tmp_path / "inside-out.obj").write_text("\n".join(lines))
    text = '[[geometry]]\nfile = "inside-out.obj"\nclosed = true\n'
    with pytest.raises(ReaderError, match="wind inward"):
        read_scene_file(text, "s.toml", tmp_path)


def test_a_tri_mesh_in_a_scene_file_keeps_the_files_coordinates(tmp_path):
    # The viewpoint is behind the screen (read_tri mirrors such a world for its camera); as a
    # scene's geometry the triangles must come as the file gives them.
    (tmp_path / "behind.tri").write_text(
        tri_text((0, 0, -5), (-1, 1, 0), (0.004, 0, 0), (0, -0.004, 0),
                 [((0, 0, 1), (1, 0, 1), (0, 1, 1))]))
    scene = read_scene_file('[[geometry]]\nfile = "behind.tri"\n', "s.toml", tmp_path)
    assert sorted(scene.meshes[0].positions[:, 2].tolist()) == [1.0, 1.0, 1.0]


def test_a_scene_of_many_big_generators_is_refused_before_it_takes_the_memory(tmp_path):
    one = '[[geometry]]\ngenerator = "torus"\nparams = { segments = 1500, sides = 1000 }\n'
    with pytest.raises(ReaderError, match=r"geometry\[2\].*limit is 4000000"):
        read_scene_file(one * 3, "many.toml", tmp_path)


@pytest.mark.parametrize("size", [(2.7, 100), (True, 100), (0, 100), (8193, 10), "big"])
def test_image_sizes_are_whole_and_bounded(size):
    with pytest.raises(ReaderError, match="image size"):
        load_scene(SCENES_DIR / "house.toml", size=size)


def test_a_coefficient_above_one_is_refused_naming_the_line_unless_the_file_lifts_it(tmp_path):
    # FvDFH 16.2: 0 <= ka, kd, ks <= 1; a kd of 2 reflects more light than falls on it
    from core.scene.formats import ReaderError, load_scene
    path = tmp_path / "bright.toml"
    path.write_text('name = "bright"\n[[geometry]]\ngenerator = "cube"\n'
                    'material = { ka = 0.2, kd = 2.0, ks = 1.0 }\n')
    with pytest.raises(ReaderError) as error:
        load_scene(path)
    assert str(error.value) == (
        f"{path}:4: geometry[1].material.kd: kd = 2 is outside the notes' 0 <= kd <= 1 (it "
        f"would reflect more light than falls on it); coefficients = \"unbounded\" at the top "
        f"of the file allows up to 10")
    path.write_text('name = "bright"\ncoefficients = "unbounded"\n[[geometry]]\n'
                    'generator = "cube"\nmaterial = { ka = 0.2, kd = 2.0, ks = 1.0 }\n')
    assert load_scene(path).meshes[0].material.kd == 2.0
