"""Hostile input to the readers: each reproducer gives one clean ReaderError, or a
scene that renders; nothing else escapes, and no input is read beyond its size limit.

Small inputs are written here; large ones are generated in the test (a sparse file costs no
disk).
"""

from __future__ import annotations

import io
import struct
import sys

import numpy as np
import pytest

from core.camera.view import View, n_per_factors, problems, vrc_basis
from core.render import render
from core.settings import RenderSettings
from core.scene.formats import MAX_INPUT_BYTES, ReaderError, load_scene, read_mesh, read_tri
from core.scene.formats.errors import MAX_MESSAGE, printable
from core.scene.formats.scenefile import read_scene_file

BIG = "9" * 5000                       # past Python's 4300-digit int() limit

CUBE = '[[geometry]]\ngenerator = "cube"\n'
TRI_HEADER = "0 0 10\n-1 1 0\n0.01 0 0\n0 -0.01 0\n"


def draw(scene, projection: str, shading: str, size=(16, 16)):
    """The scene's first view rendered (``core.render.render``)."""
    settings = RenderSettings.for_scene(scene, projection=projection, shading=shading, size=size)
    return render(scene, scene.views[0], settings)


def refused(read, *args) -> ReaderError:
    with pytest.raises(ReaderError) as info:
        read(*args)
    assert "Traceback" not in str(info.value)
    return info.value


# ----------------------------------------------------------------------------- > 4300 digits

@pytest.mark.parametrize("read, data, expect", [
    (lambda d: read_tri(d, "big.tri"), TRI_HEADER + BIG + "\n", "the triangle count has 5000 digits"),
    (lambda d: read_mesh(d, "big.ply", ".ply"),
     f"ply\nformat ascii 1.0\nelement vertex {BIG}\nproperty float x\nend_header\n".encode(),
     "the count of element 'vertex' has 5000 digits"),
    (lambda d: read_mesh(d, "big.off", ".off"), f"OFF\n{BIG} 1 0\n0 0 0\n".encode(),
     "the vertex count has 5000 digits"),
    (lambda d: read_mesh(d, "big.off", ".off"), f"OFF\n3 {BIG} 0\n0 0 0\n".encode(),
     "the face count has 5000 digits"),
    (lambda d: read_mesh(d, "big.obj", ".obj"), f"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 {BIG}\n".encode(),
     "a face index has 5000 digits"),
    (lambda d: read_mesh(d, "big.obj", ".obj"), f"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -{BIG}\n".encode(),
     "a face index has 5000 digits"),
    (lambda d: read_scene_file(d, "big.toml"), f"{CUBE}\nx = {BIG}\n",
     "TOML: a number cannot be read: Exceeds the limit (4300 digits)"),
])
def test_integers_past_4300_digits_are_refused(read, data, expect):
    error = refused(read, data)
    assert expect in str(error)


def test_a_toml_integer_past_4300_digits_names_its_line():
    error = refused(read_scene_file, f"name = 'x'\n\nsize = [{BIG}, 2]\n{CUBE}", "big.toml")
    assert error.line == 3


def test_non_ascii_digits_are_not_counts():
    # str.isdigit() takes a superscript two; int() of it raises ValueError
    error = refused(read_mesh, "OFF\n\u00b2 1 0\n".encode(), "sup.off", ".off")
    assert "the vertex count must be a whole number >= 0" in str(error)
    error = refused(read_mesh, b"ply\nformat ascii 1.0\nelement vertex \xd9\xa1\nend_header\n",
                    "arabic.ply", ".ply")
    assert "must be a whole number >= 0" in str(error)


# ----------------------------------------------------------------------------- views and lights

def _house_with(view: View):
    from core.scene.generators import house
    from core.scene.model import Scene
    return Scene(name="house", meshes=[house()], views=[view], shading="phong", size=(24, 24))


VIEWS_TEXT = "0 0 0\n0 0 1\n0 1 0\n-1 1 -1 1\n{prp}\n{fb}\n"


@pytest.mark.parametrize("prp, fb, projection, reason", [
    ("0 0 5", "1 0.9999999999999999", "perspective", "z_min = -1 rounds to -1"),
    ("0 0 1e-300", "1e-301 -1", None, "too close to give a direction of projection"),
])
def test_what_the_renderer_cannot_draw_is_refused_with_its_reason(tmp_path, prp, fb,
                                                                  projection, reason):
    path = tmp_path / "v.views"
    path.write_text(VIEWS_TEXT.format(prp=prp, fb=fb))
    scene = load_scene(path)
    if projection is None:                       # invalid for both: refused at load
        assert not scene.views and reason in scene.view_messages[0]
        return
    view = scene.views[0]                        # invalid for one projection: loads, and the
    assert reason in " ".join(problems(view, projection))   # renderer gives the same reason
    for shading in ("wireframe", "flat", "phong"):
        frame = draw(scene, projection, shading)
        assert reason in frame.message
        other = draw(scene, "parallel", shading)
        assert other.message is None


@pytest.mark.parametrize("vpn, vup", [((1e308, 1e308, 1e308), (0, 0, 1)),
                                      ((1e-320, 0, 0), (0, 1, 0)),
                                      ((-1e-320, 1e-320, 0), (0, 0, 1e-320))])
def test_huge_and_subnormal_vpn_keep_their_direction(vpn, vup):
    view = View((0, 0, 0), vpn, vup, (-1, 1, -1, 1), (0, 0, 5), 1, -1)
    assert problems(view) == []
    u, v, n = vrc_basis(view)
    expected = np.asarray(vpn) / np.max(np.abs(vpn))
    assert np.allclose(n, expected / np.linalg.norm(expected), rtol=0, atol=1e-15)
    assert np.allclose(np.array([u, v, n]) @ np.array([u, v, n]).T, np.eye(3), atol=1e-15)
    for projection in ("perspective", "parallel"):
        assert draw(_house_with(view), projection, "phong").message is None


def test_vup_parallel_to_vpn_is_still_named():
    view = View((0, 0, 0), (1e308, 1e308, 1e308), (1, 1, 1), (-1, 1, -1, 1), (0, 0, 5), 1, -1)
    assert problems(view) == ["VUP is parallel to VPN"]


def test_a_tiny_light_direction_is_a_direction(tmp_path):
    scene = read_scene_file(CUBE + "[[light]]\ndirection = [1e-300, 0, 0]\n"
                            "[[light]]\ndirection = [0, 1e-320, -1e-320]\n", "l.toml")
    assert scene.lights[0].direction == (1.0, 0.0, 0.0)
    assert np.allclose(scene.lights[1].direction, (0, 2 ** -0.5, -2 ** -0.5))
    for projection in ("perspective", "parallel"):
        frame = draw(scene, projection, "phong")
        assert frame.message is None


def test_a_zero_light_direction_is_refused_with_its_line():
    error = refused(read_scene_file, CUBE + "[[light]]\ndirection = [0, -0.0, 0]\n", "l.toml")
    assert error.line == 4 and "light[1].direction: the direction is zero" in str(error)


# ----------------------------------------------------------------------------- size limits

def test_a_sparse_file_past_its_limit_is_refused_before_reading(tmp_path):
    for ext, kind in ((".tri", "tri"), (".stl", "mesh"), (".toml", "scene"), (".views", "views")):
        path = tmp_path / f"huge{ext}"
        with open(path, "wb") as f:
            f.truncate(MAX_INPUT_BYTES[kind] + 1)       # sparse: no disk, no time
        error = refused(load_scene, path)
        assert f"a {kind} input may have at most {MAX_INPUT_BYTES[kind]} bytes" in str(error)


class EndlessStream:
    """Standard input that never ends (``yes |``, ``< /dev/zero``); counts what is read."""

    def __init__(self, byte: bytes) -> None:
        self.byte, self.read_bytes = byte, 0

    def read(self, n: int = -1) -> bytes:
        assert n >= 0, "an endless stream must be read with a bound"
        self.read_bytes += n
        return self.byte * n


@pytest.mark.parametrize("byte", [b"\0", b"y\n"])
def test_endless_stdin_is_refused_after_its_limit(monkeypatch, byte):
    stream = EndlessStream(byte)
    monkeypatch.setattr(sys, "stdin", type("Stdin", (), {"buffer": stream, "closed": False})())
    error = refused(load_scene, "-")
    assert "a views input may have at most" in str(error)
    assert stream.read_bytes == MAX_INPUT_BYTES["views"] + 1


@pytest.mark.parametrize("stdin", [None, "closed"])
def test_closed_stdin_is_a_message(monkeypatch, stdin):
    if stdin == "closed":
        stdin = io.TextIOWrapper(io.BytesIO(b""))
        stdin.close()
    monkeypatch.setattr(sys, "stdin", stdin)
    assert "standard input is closed" in str(refused(load_scene, "-"))


def test_stdin_views_still_load(monkeypatch):
    data = VIEWS_TEXT.format(prp="0 0 5", fb="1 -1").encode()
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))
    assert len(load_scene("-").views) == 1


# ----------------------------------------------------------------------------- TOML pre-scan

def test_a_long_dotted_key_is_refused_before_parsing():
    error = refused(read_scene_file, CUBE + "a" + ".a" * 20_000 + " = 1\n", "dots.toml")
    assert "a dotted key of 20001 parts" in str(error) and error.line == 3


def test_a_dotted_string_value_is_not_a_key():
    scene = read_scene_file(f'name = "{".".join(["a"] * 40)}"\n' + CUBE, "dots.toml")
    assert scene.name.count(".") == 39


def test_deep_brackets_are_refused_before_parsing():
    error = refused(read_scene_file, CUBE + "a = " + "[" * 100_000 + "]" * 100_000, "deep.toml")
    assert "brackets nested more than 64 deep" in str(error) and error.line == 3


def test_quoted_key_with_control_characters_is_escaped_and_located():
    text = '# c\nname = "x"\n\n"x\\ny\\u001b[2J" = 1\n' + CUBE
    error = refused(read_scene_file, text, "k.toml")
    message = str(error)
    assert error.line == 4
    assert "\n" not in message and "\x1b" not in message
    assert "x\\ny\\x1b[2J: unknown key" in message


def test_messages_are_capped():
    error = refused(read_scene_file, CUBE + f'shading = "{"w" * 1_000_000}"\n', "long.toml")
    assert len(str(error)) < MAX_MESSAGE + 300


def test_printable_escapes_every_invisible_character():
    assert printable("a\r\n\t\x1b\x7f\u202e\u2028b") == "a\\r\\n\\t\\x1b\\x7f\\u202e\\u2028b"
    assert printable("x" * 10, 4) == "xxxx... (6 more characters)"


def test_view_names_from_the_file_are_escaped():
    text = CUBE + ('[[view]]\nname = "\\u001b[31mred"\nvrp = [0, 0, 0]\nvpn = [0, 0, 0]\n'
                   'vup = [0, 1, 0]\nwindow = [-1, 1, -1, 1]\nprp = [0, 0, 5]\nfront = 1\nback = -1\n')
    scene = read_scene_file(text, "n.toml")
    assert scene.view_messages and "\x1b" not in scene.view_messages[0]
    assert "\\x1b[31mred" in scene.view_messages[0]


# ----------------------------------------------------------------------------- the triangle budget

def _binary_stl(count: int, triangles: int | None = None) -> bytes:
    """A binary STL whose header says ``count``; ``triangles`` records follow (all zero)."""
    return b"\0" * 80 + struct.pack("<I", count) + b"\0" * (50 * (count if triangles is None
                                                              else triangles))


def test_a_mesh_file_opened_directly_is_held_to_the_budget(tmp_path):
    from core.scene.generators import MAX_TRIANGLES
    path = tmp_path / "many.stl"
    with open(path, "wb") as f:                     # 200 MB, sparse: the header is the data
        f.write(_binary_stl(0, 0)[:80] + struct.pack("<I", MAX_TRIANGLES + 1))
        f.truncate(84 + 50 * (MAX_TRIANGLES + 1))
    error = refused(load_scene, path)
    assert f"{MAX_TRIANGLES + 1} triangles; the limit is {MAX_TRIANGLES}" in str(error)


def _distinct_stl(count: int) -> bytes:
    return b"\0" * 80 + struct.pack("<I", count) + b"".join(
        struct.pack("<12fH", 0, 0, 1, 0, 0, k, 1, 0, k, 0, 1, k, 0) for k in range(count))


@pytest.mark.parametrize("ext, data", [
    (".stl", _distinct_stl(3)),
    (".stl", b"solid x\n" + b"".join(b"facet normal 0 0 1\nouter loop\nvertex 0 0 %d\nvertex 1 0 0"
                                      b"\nvertex 0 1 0\nendloop\nendfacet\n" % k for k in range(3))
             + b"endsolid x\n"),
    (".obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\nf 1 3 2\n"),
    (".off", b"OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n"),
    (".ply", b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
             b"property float z\nelement face 3\nproperty list uchar int vertex_indices\n"
             b"end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n"),
])
def test_every_mesh_format_checks_the_budget_before_reading(ext, data):
    assert len(read_mesh(data, "ok" + ext, ext, budget=3).triangles) == 3
    error = refused(read_mesh, data, "many" + ext, ext, 2)
    assert "the limit is 2" in str(error)


def test_a_scene_passes_what_is_left_of_its_budget_to_a_mesh_file(tmp_path, monkeypatch):
    from core.scene import generators
    monkeypatch.setattr(generators, "MAX_TRIANGLES", 14)      # a cube is 12
    (tmp_path / "three.stl").write_bytes(_distinct_stl(3))
    (tmp_path / "s.toml").write_text(CUBE + '[[geometry]]\nfile = "three.stl"\n')
    error = refused(load_scene, tmp_path / "s.toml")
    assert "3 triangles; the limit is 2" in str(error) and "geometry[2]" in str(error)
    (tmp_path / "two.tri").write_text(TRI_HEADER + "3\n" + "".join(f"0 0 {k} 1 0 0 0 1 0\n"
                                                                    for k in range(3)))
    (tmp_path / "t.toml").write_text(CUBE + '[[geometry]]\nfile = "two.tri"\n')
    assert "3 triangles; the limit is 2" in str(refused(load_scene, tmp_path / "t.toml"))


# ----------------------------------------------------------------------------- right reasons

@pytest.mark.parametrize("header, reason", [
    ("0 0 10\n-1 1 0\n1e-300 0 0\n0 -0.01 0\n", "the pixel displacements are too small next to "
                                                 "the viewpoint's distance"),
    ("0 0 10\n-1 1 0\n1e-320 0 0\n0 -1e-320 0\n", "the pixel displacements are too small"),
    ("0 0 10\n-1 1 0\n0 0 0\n0 -1 0\n", "the right displacement is zero"),
    ("0 0 1e-290\n-1e-298 1e-298 0\n1e-300 0 0\n0 -1e-300 0\n",
     "the camera cannot be drawn: the PRP is 1e-290 from the window's centre"),
])
def test_tri_displacements_get_the_right_reason(header, reason):
    error = refused(read_tri, header + "1\n0 0 0 1 0 0 0 1 0\n", "d.tri")
    assert reason in error.reason


def test_a_tiny_but_drawable_tri_camera_loads_and_renders():
    scene = read_tri("0 0 1e-100\n-1e-102 1e-102 0\n1e-104 0 0\n0 -1e-104 0\n1\n"
                     "0 0 0 1e-102 0 0 0 1e-102 0\n", "tiny.tri")
    for projection in ("perspective", "parallel"):
        assert draw(scene, projection, "flat").message is None


def test_the_loader_renderer_agreement_case_passes():
    """``python -m app stability``'s case: every view the reader accepts draws (numpy set to
    raise on overflow here, so an overflow anywhere in the renderer is an exception)."""
    from core.analysis.stability_cases import loader_renderer_agreement
    outcome = loader_renderer_agreement()
    assert all(ok for _, ok in outcome.checks), outcome.checks


def test_a_view_neither_projection_can_draw_is_refused_at_load(tmp_path):
    path = tmp_path / "v.views"
    # a window 1e-290 wide: N would carry the scene's range (1e30) to 1e320
    path.write_text("0 0 0\n0 0 1\n0 1 0\n0 1e-290 0 1e-290\n0 0 5\n1 -1\n")
    scene = load_scene(path)
    assert not scene.views and "the normalizing transformation carries points" in \
        scene.view_messages[0]


def test_the_line_locator_finds_the_last_of_thousands_of_views():
    table = ('[[view]]\nvrp = [0, 0, 0]\nvpn = [0, 0, 1]\nvup = [0, 1, 0]\n'
             'window = [-2, 2, -2, 2]\nprp = [0, 0, 5]\nfront = 2\nback = -2\n')
    text = CUBE + table * 3000 + table.replace("front = 2", 'front = "near"')
    error = refused(read_scene_file, text, "many.toml")
    assert error.line == 2 + 8 * 3000 + 7
    assert "view[3001].front: expected a number" in error.reason
    scene = read_scene_file(CUBE + table * 3000, "many.toml")
    assert scene.views[-1].label == "many.toml: view 3000 (line 23995)"
