"""The readers' fuzz targets, shared by the CI fuzz tests (``tests/test_fuzz_readers.py``,
hypothesis, a bounded number of cases) and the long run (``tests/fuzz_long.py``, plain seeded
mutation, 100k+ cases per reader, run once by hand).

The invariant (issue 15): a reader given any bytes either raises a :class:`ReaderError` with a
message, or returns a scene that renders: every view it accepts (up to ``VIEWS_RENDERED``) is
drawn through ``core.render.render`` in both projections without an exception, and a frame
that comes back with a message is one whose view the validity rules refuse for that projection.
"""

from __future__ import annotations

import random
import re
import struct

from core.camera.view import PROJECTIONS, problems
from core.paths import SCENES_DIR
from core.render import render
from core.scene.formats import ReaderError, read_mesh, read_scene_file, read_tri
from core.scene.formats.viewfile import read_views
from core.scene.generators import house
from core.scene.model import Scene
from core.settings import RenderSettings

VIEWS_RENDERED = 3           # per scene; a fuzzed view file may hold hundreds
FRAME = (8, 8)               # small: the invariant is about exceptions, not pixels

NASTY = [b"nan", b"inf", b"-inf", b"-1", b"0", b"1e308", b"-1e308", b"1e-320", b"1e40",
         b"99999999999999999999", b"1000000000000", b"abc", b"#", b"\x00", b"", b"3.5", b"+",
         b"-0", b"0x10", b"1_0", "\u0661".encode(), b"\xff\xfe", b"[", b"]", b"{", b"}", b"=",
         b'"', b"'", b"[[geometry]]", b"true", b"1e999", b"-", b"/", b"//", b"f", b"v",
         b"9" * 400, b"9" * 5000, b"vn 1e200 0 0", b"1e200", b"1e-300", b"5e-324",
         b"0.9999999999999999", b"\t", b"\x1b[2J", b"a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a.a",
         b"\"\\u001b\"", b"\r\n", b"1//1", b"1/1/1", b"vt", b"vn", b"-1e-320"]

TRI = (SCENES_DIR / "interpenetrating.tri").read_bytes()
OBJ = b"""# a cube: quads, a triangle pair with negative indices, normals, texture coordinates
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
vn 0 0 1
vt 0.5 0.5
f 5/1/1 6/1/1 7/1/1 8/1/1
f 1 4 3 2
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f -4 -8 -5
f -4 -5 -1
"""
PLY = (b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
       b"property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
       b"0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n")
PLY_BINARY = (b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 1\n"
              b"property list uchar int vertex_indices\nend_header\n"
              + struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2))
OFF = b"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"
STL_ASCII = (b"solid fuzz\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
             b"vertex 1 1 0\nendloop\nendfacet\nendsolid fuzz\n")
STL_BINARY = (b"\0" * 80 + struct.pack("<I", 1)
              + struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0))
TOML = b"""name = "fuzz"
shading = "gouraud"
size = [200, 100]
background = [0.1, 0.1, 0.1]

[[geometry]]
generator = "uv_sphere"
params = { radius = 1.0, segments = 8, rings = 5 }
transform = { scale = 0.5, rotate = [10, 20, 30], translate = [1, 0, 0] }
material = { ka = 0.2, kd = 0.7, ks = 0.3, n = 10, od = [1, 0.5, 0.2] }

[[geometry]]
generator = "cube"
closed = true

[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 5]
front = 2
back = -2

[[light]]
position = [1, 2, 3]
attenuation = [1, 0.1, 0]

[[light]]
direction = [0, 1, 1]
"""
VIEWS = (SCENES_DIR / "house.views").read_bytes()


def _views_scene(data: bytes) -> Scene:
    """A bare view file, read as ``load_scene`` reads one (decoded, then its views)."""
    from core.scene.formats.errors import decode_text
    views, messages = read_views(decode_text(data, "fuzz.views"), "fuzz.views")
    return Scene(name="house", meshes=[house()], views=views, view_messages=messages,
                 shading="flat", size=(500, 500), source="fuzz.views")


# reader name -> (the reader, the valid file mutated from)
TARGETS = {
    "tri": (lambda d: read_tri(d, "fuzz.tri"), TRI),
    "obj": (lambda d: read_mesh(d, "fuzz.obj", ".obj"), OBJ),
    "ply": (lambda d: read_mesh(d, "fuzz.ply", ".ply"), PLY),
    "ply-binary": (lambda d: read_mesh(d, "fuzz.ply", ".ply"), PLY_BINARY),
    "off": (lambda d: read_mesh(d, "fuzz.off", ".off"), OFF),
    "stl-ascii": (lambda d: read_mesh(d, "fuzz.stl", ".stl"), STL_ASCII),
    "stl-binary": (lambda d: read_mesh(d, "fuzz.stl", ".stl"), STL_BINARY),
    "toml": (lambda d: read_scene_file(d, "fuzz.toml", SCENES_DIR), TOML),
    "views": (_views_scene, VIEWS),
}


def as_scene(result) -> Scene:
    """A mesh reader returns a Mesh: seen as ``load_scene`` shows a bare mesh file."""
    if isinstance(result, Scene):
        return result
    from core.scene.formats import _mesh_scene
    return _mesh_scene(result, "fuzz", None)


def check(name: str, data: bytes) -> str:
    """Run target ``name`` on ``data`` and hold the invariant; returns the outcome:
    ``"refused"`` (a ReaderError), ``"rendered"`` (a scene whose views all drew), or
    ``"no views"`` (a scene without a valid view: its frame says so). Anything else raises."""
    read, _ = TARGETS[name]
    try:
        result = read(data)
    except ReaderError as error:
        assert str(error).strip() and error.reason.strip(), "an empty message"
        assert "\n" not in str(error) and "\x1b" not in str(error), "an unescaped message"
        return "refused"
    return renders(result)


def renders(result) -> str:
    """Hold the second half of the invariant on what a reader returned: every view it
    accepted draws in both projections; ``"rendered"`` or ``"no views"``."""
    scene = as_scene(result)
    if not scene.views:
        frame = render(scene, None, RenderSettings.for_scene(scene, size=FRAME))
        assert frame.message, "a frame without a view must say so"
        return "no views"
    for view in scene.views[:VIEWS_RENDERED]:
        for projection in PROJECTIONS:
            settings = RenderSettings.for_scene(scene, projection=projection, size=FRAME)
            frame = render(scene, view, settings)
            if frame.message:      # only a view the rules refuse for this projection
                assert problems(view, projection), frame.message
    return "rendered"


# Token edits keep a file's structure, so they reach past the header more often: weighted up.
# A "number" edit swaps one number for another plausible one and keeps the syntax whole, so
# that a fair share of the inputs gets through the reader to the renderer (a test holds it).
KINDS = ("byte", "insert", "delete", "truncate", "token", "token", "token", "repeat",
         "number", "number", "number")
NUMBER = re.compile(rb"(?<![\w.])-?\d+(\.\d+)?([eE][-+]?\d+)?(?![\w.])")
PLAUSIBLE = [b"0", b"1", b"-1", b"2", b"0.5", b"-0.5", b"3", b"10", b"-7.25", b"1e-3", b"100",
             b"0.001", b"1e5", b"-2", b"4"]


def _swap_number(rng: random.Random, data: bytearray) -> None:
    spans = [m.span() for m in NUMBER.finditer(bytes(data))]
    if spans:
        a, b = spans[rng.randint(0, len(spans) - 1)]
        data[a:b] = rng.choice(PLAUSIBLE)


def mutate(rng: random.Random, base: bytes) -> bytes:
    """``base`` with 1 to 4 byte- and token-level edits (the CI strategy's edits, seeded)."""
    data = bytearray(base)
    for _ in range(rng.randint(1, 4)):
        kind = rng.choice(KINDS)
        at = rng.randint(0, max(len(data) - 1, 0))
        if kind == "byte" and data:
            data[at] = rng.randint(0, 255)
        elif kind == "insert":
            data[at:at] = bytes(rng.randint(0, 255) for _ in range(rng.randint(0, 8)))
        elif kind == "delete":
            del data[at:at + rng.randint(1, 24)]
        elif kind == "truncate":
            del data[at:]
        elif kind == "repeat":
            data[at:at] = data[at:at + rng.randint(1, 60)]
        elif kind == "number":
            _swap_number(rng, data)
        else:
            spans = [m.span() for m in re.finditer(rb"[^\s,=\[\]{}/]+", bytes(data))]
            if spans:
                a, b = spans[rng.randint(0, len(spans) - 1)]
                data[a:b] = rng.choice(NASTY)
    return bytes(data)


