"""The readers' fuzz targets, shared by the CI fuzz tests
(``tests/core/scene/test_fuzz_readers.py``, hypothesis, a bounded number of cases) and the long
run (``tests/fuzz_long.py``, plain seeded mutation, 100k+ cases per reader, run once by hand).

The invariant: a reader given any bytes either raises a :class:`ReaderError` with a
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

# The systems' keys. Each seed is a small valid scene that uses most of its system's
# keys; its files (a 4 x 4 PNG) lie in FOLDER, made once per process.
TEXTURES = b"""[[geometry]]
generator = "uv_sphere"
params = { radius = 1.0, segments = 8, rings = 5 }
material = { kd = 0.7, texture = { file = "tex.png", wrap = "mirror", srgb = true }, uv_scale = [2, 3] }
[[geometry]]
generator = "cube"
material = { texture = { procedural = "checker", scale = 4, resolution = 16, a = [1, 0, 0], b = [0, 0, 1] }, bump = { procedural = "bricks_height", rows = 4, columns = 2, mortar = 0.1, resolution = 16 }, bump_scale = 0.05 }
[[geometry]]
generator = "torus"
params = { segments = 8, sides = 6 }
material = { normal_map = { procedural = "bricks_normal", resolution = 8, strength = 2.0 }, environment = { procedural = "sky", resolution = 8, sun = [0.3, 0.7], squares = 4 }, reflectivity = 0.5, texture = { procedural = "perlin", scale = 2, octaves = 2, seed = 3, resolution = 16 } }
[[geometry]]
generator = "plane"
material = { bump_demo = { map = 2, bump = true, viewpoint = [50, -50, 50] }, texture = "missing.png" }
"""
KEYS = b"""[[geometry]]
generator = "cube"
name = "box"
[[geometry]]
primitive = "plane"
name = "floor"
checker = 1.0
extent = 3.0
[[light]]
position = [3, 4, 5]
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-3, 3, -3, 3]
prp = [0, 0, 10]
front = 5
back = -5
[animation]
duration = 2.0
fps = 4
interpolation = "kochanek-bartels"
orientation = "squad"
tension = 0.2
continuity = 0.1
bias = -0.1
constant_speed = true
[animation.track."view.vrp"]
interpolation = "double"
[[key]]
time = 0.0
view = { vrp = [0, 0, 0], vpn = [0, 0, 1], vup = [0, 1, 0], window = [-3, 3, -3, 3], prp = [0, 0, 10], front = 5, back = -5 }
object.box = { translate = [0, 0, 0], rotate = [0, 0, 0], scale = 1.0 }
light.1 = { position = [3, 4, 5] }
material.floor = { od = [1, 0, 0] }
[[key]]
time = 1.0
view = { vrp = [1, 0, 0], vpn = [0.2, 0, 1], vup = [0, 1, 0], prp = [0, 0, 12] }
object.box = { translate = [1, 1, 0], rotate = [0, 90, 0], scale = [1, 2, 1] }
object.floor = { translate = [0, -1, 0] }
[[key]]
time = 2.0
view = { vrp = [0, 1, 0], front = 4, back = -6 }
object.box = { translate = [0, 0, 1], rotate = [45, 0, 0], scale = 0.5 }
light.1 = { position = [-3, 4, 5] }
material.floor = { od = [0, 1, 0] }
"""
EMITTERS = b"""[[geometry]]
generator = "cube"
name = "box"
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-3, 3, -3, 3]
prp = [0, 0, 10]
front = 5
back = -5
[animation]
duration = 1.0
fps = 8
seed = 7
[[emitter]]
name = "fountain"
shape = "disc"
radius = 0.5
normal = [0, 1, 0]
rate = 20
rate_var = 5
speed = 3
speed_var = 1
velocity = [0, 1, 0]
velocity_var = [0.2, 0.2, 0.2]
size = 0.1
size_var = 0.02
size_end = 0.5
color = [0.3, 0.5, 1]
color_var = [0.1, 0.1, 0.1]
color_end = [1, 1, 1]
alpha = 0.9
alpha_end = 0.1
lifetime = 0.5
lifetime_var = 0.2
gravity = [0, -9.8, 0]
wind = [0.5, 0, 0]
drag = 0.1
plane = { point = [0, -1, 0], normal = [0, 1, 0], restitution = 0.5, friction = 0.2 }
region = { min = [-5, -5, -5], max = [5, 5, 5] }
alpha_min = 0.01
size_min = 0.001
draw = "streak"
streak = 0.05
children = 2
children_var = 1
child = { lifetime = 0.2, size = 0.05, draw = "point", inherit = 0.5 }
[[emitter]]
shape = "mesh"
mesh = "box"
rate = 5
speed = 1
draw = "sprite"
start = 0.1
stop = 0.8
"""
PRIMITIVES = b"""[[geometry]]
primitive = "sphere"
center = [0, 1, 0]
radius = 0.8
segments = 16
material = { kr = 0.3, kt = 0.2, ior = 1.5, od = [0.9, 0.2, 0.2] }
[[geometry]]
primitive = "plane"
point = [0, -1, 0]
normal = [0, 1, 0]
checker = 1.0
checker_color = [0.2, 0.2, 0.2]
extent = 4.0
name = "floor"
"""

# Motion capture: a take of three joints (read through a scene that plays it on its limbs),
# and reactive actors (value edits of their senses and behaviours).
BVH = b"""HIERARCHY
ROOT a
{
  OFFSET 0 1 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT b
  {
    OFFSET 0 -0.5 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT c
    {
      OFFSET 0 -0.5 0
      CHANNELS 2 Yrotation Xrotation
      End Site
      {
        OFFSET 0 0 0.2
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.25
0 0 0 0 0 0 0 -20 0 0 10
0.2 0 0 5 10 0 0 20 0 30 -10
0.4 0 0 0 0 90 0 -20 0 0 10
"""
BVH_SCENE = b"""[[geometry]]
generator = "cube"
[[view]]
vrp = [0, 0.8, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 10]
front = 5
back = -5
[[mocap]]
file = "fuzz.bvh"
limb = "box"
radii = { a = 0.1 }
materials = { b = { od = [0.2, 0.4, 0.9] } }
"""
ACTORS = b"""[[geometry]]
generator = "cube"
name = "a"
transform = { scale = 0.1 }
[[geometry]]
generator = "cube"
name = "b"
transform = { scale = 0.1 }
[[geometry]]
generator = "icosphere"
name = "rock"
params = { subdivisions = 1, radius = 0.5 }
[[view]]
vrp = [0, 0, 0]
vpn = [0, 1, 1]
vup = [0, 1, 0]
window = [-3, 3, -3, 3]
prp = [0, 0, 10]
front = 5
back = -5
[animation]
duration = 1.0
fps = 4
[[actor]]
name = "hunter"
mesh = "a"
behaviours = ["avoid_obstacles", "pursue", "wander"]
steering = "priority"
position = [-2, 0, 0]
velocity = [1, 0, 0]
max_speed = 2
max_force = 5
[actor.senses]
radius = 3
fov = 120
[actor.avoid_obstacles]
obstacles = ["rock"]
spheres = [{ center = [1, 0, 1], radius = 0.3 }]
clearance = 0.2
acceleration = 4
horizontal = true
[actor.pursue]
target = "prey"
prediction = 0.5
[actor.wander]
speed = 1
turn = 30
[[actor]]
name = "prey"
mesh = "b"
count = 3
behaviours = ["flee", "wander"]
position = [1, 0, 0]
spread = [1, 0, 1]
velocity_var = [0.5, 0, 0.5]
[actor.senses]
radius = 2
[actor.flee]
threat = "hunter"
"""


def _mocap_scene(data: bytes):
    """``data`` as the take a small scene plays (the file written where the scene finds it)."""
    (FOLDER / "fuzz.bvh").write_bytes(data)
    return read_scene_file(BVH_SCENE, "fuzz.toml", FOLDER)


def _texture_folder():
    """A folder with the textures' seed file ``tex.png`` (4 x 4, made once)."""
    import tempfile
    from pathlib import Path

    import numpy as np
    from PIL import Image
    folder = Path(tempfile.mkdtemp(prefix="fuzz-textures-"))
    image = (np.arange(48, dtype=np.uint8).reshape(4, 4, 3) * 5)
    Image.fromarray(image).save(folder / "tex.png")
    return folder


FOLDER = _texture_folder()


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
    # the systems' keys
    "textures": (lambda d: read_scene_file(d, "fuzz.toml", FOLDER), TEXTURES),
    "keys": (lambda d: read_scene_file(d, "fuzz.toml", FOLDER), KEYS),
    "emitters": (lambda d: read_scene_file(d, "fuzz.toml", FOLDER), EMITTERS),
    "primitives": (lambda d: read_scene_file(d, "fuzz.toml", FOLDER), PRIMITIVES),
    "bvh": (_mocap_scene, BVH),
    "actors": (lambda d: read_scene_file(d, "fuzz.toml", FOLDER), ACTORS),
}
SYSTEMS = ("textures", "keys", "emitters", "primitives", "actors")

# While fuzzing, the budgets are small, so that a mutation that asks for a day of particles or
# a 4096² texture is refused (or stopped) in milliseconds: the budgets are what is tested, not
# the machine's patience. Restored after every case (other tests share the process).
SMALL_BUDGETS = {("core.animation.particles", "MAX_SIMULATION_STEPS"): 2_000,
                 ("core.animation.particles", "MAX_PARTICLE_WORK"): 2_000_000,
                 ("core.animation.particles", "MAX_PARTICLES"): 20_000,
                 ("core.animation.particles", "MAX_PER_FRAME"): 5_000,
                 ("core.animation.draw", "MAX_SPLAT_PIXELS"): 2_000_000,
                 ("core.texture.image", "MAX_SCENE_TEXELS"): 4 * 256 * 256}
TIMES = 3                    # moments of an animated scene drawn: 0, the middle, the end


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
    with small_budgets():
        try:
            result = read(data)
        except ReaderError as error:
            assert str(error).strip() and error.reason.strip(), "an empty message"
            assert "\n" not in str(error) and "\x1b" not in str(error), "an unescaped message"
            return "refused"
        for message in getattr(result, "messages", []):      # textures drawn without
            assert "\n" not in message and "\x1b" not in message, "an unescaped message"
        return renders(result)


class small_budgets:
    """The SMALL_BUDGETS while inside, the real ones again after."""

    def __enter__(self):
        import importlib
        self.saved = []
        for (module, name), value in SMALL_BUDGETS.items():
            target = importlib.import_module(module)
            self.saved.append((target, name, getattr(target, name)))
            setattr(target, name, value)

    def __exit__(self, *exc):
        for target, name, value in self.saved:
            setattr(target, name, value)


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
            # opaque: the transparent pass composites polygon by polygon (minutes for a
            # fuzzed mesh of thousands of k_t > 0 triangles); its own tests draw it
            settings = RenderSettings.for_scene(scene, projection=projection, size=FRAME,
                                                transparency="off")
            frame = render(scene, view, settings)
            if frame.message:      # only a view the rules refuse for this projection
                assert problems(view, projection), frame.message
    return animates(scene)


def animates(scene) -> str:
    """An animated scene is also drawn at TIMES moments, particles included: a
    frame may come back with a message only for a view the rules refuse or for the particle
    budget, and the simulation may stop only with its budget's message."""
    from core.animation.frames import render_at
    from core.animation.keys import animation_of
    from core.animation.particles import ParticleBudgetError
    animation = animation_of(scene)
    if animation is None:
        return "rendered"
    settings = RenderSettings.for_scene(scene, size=FRAME)
    for k in range(TIMES):
        t = animation.duration * k / max(TIMES - 1, 1)
        try:
            frame = render_at(animation, t, settings)
        except ParticleBudgetError as error:
            assert "particle-steps" in str(error) and "\n" not in str(error)
            return "budget"
        if frame.message:
            view = animation.scene_at(t).views[0]
            assert problems(view, settings.projection) or "particles would cover" in frame.message, \
                frame.message
    return "animated"


# ---------------------------------------------------------------------------- value mutation

# Byte edits of a TOML file mostly break its syntax (the reader refuses it at once); the
# systems' keys are reached by editing the parsed values instead and writing the file back.
NASTY_VALUES = [float("nan"), float("inf"), float("-inf"), 1e308, -1e308, 1e-320, -1e-320, 0,
                -1, 1, 2, 0.5, 8.5, 99, 10**6, 4096, 1024, 200_000, 86_400, 2**63, -(2**63),
                10**30, True, False, "", "x", "\n\x1b[2J\u202e", "a" * 5000, "/dev/zero",
                "..", [], [1], [0, 0, 0], [0, 1e-320, 0], [1e308, 1e308, 1e308],
                [float("nan")] * 3, [0.5] * 1000, ["x", "y", "z"], {}, {"x": 1}, [[1, 2], [3]]]


def mutate_values(rng: random.Random, base: bytes) -> bytes:
    """``base`` (TOML) parsed, 1 to 4 values replaced by NASTY_VALUES, keys dropped or added,
    tables repeated, and written back as TOML."""
    import copy
    import tomllib
    doc = tomllib.loads(base.decode())
    for _ in range(rng.randint(1, 4)):
        parent, key = _pick(rng, doc)
        kind = rng.random()
        if kind < 0.35:                   # a plausible value: a number scaled or flipped
            parent[key] = _perturbed(rng, parent[key] if isinstance(parent, list) or key in parent
                                     else 1.0)
        elif kind < 0.6 or not isinstance(parent, dict):
            parent[key] = copy.deepcopy(rng.choice(NASTY_VALUES))
        elif kind < 0.75:
            parent.pop(key, None)
        elif kind < 0.85:
            parent[rng.choice(["zz", "time", "file", "procedural", "child", "view", "key"])] = \
                copy.deepcopy(rng.choice(NASTY_VALUES))
        elif isinstance(parent, list) or key in parent:
            value = parent[key]
            if isinstance(value, list) and value:        # a table array: one more of them
                value.append(copy.deepcopy(rng.choice(value)))
            else:
                parent[key] = copy.deepcopy(value)
    return toml_text(doc).encode("utf-8", "surrogatepass")


def _perturbed(rng: random.Random, value):
    if isinstance(value, bool) or not isinstance(value, (int, float, list)):
        return value
    if isinstance(value, list):
        return [_perturbed(rng, v) if rng.random() < 0.5 else v for v in value]
    factor = rng.choice([-1, 0.5, 2, 10, 0.1, 1e3, 1e-3, 0])
    result = value * factor + rng.choice([0, 0, 1, -1, 0.25])
    return int(result) if isinstance(value, int) and rng.random() < 0.5 else result


def _pick(rng: random.Random, doc: dict):
    """A random (container, key) pair of ``doc``, any depth."""
    parent, key = doc, rng.choice(list(doc)) if doc else "zz"
    while True:
        value = parent.get(key) if isinstance(parent, dict) else parent[key]
        inner = (list(value) if isinstance(value, dict) else
                 list(range(len(value))) if isinstance(value, list) else [])
        if not inner or rng.random() < 0.35:
            return parent, key
        parent, key = value, rng.choice(inner)


def toml_text(doc: dict) -> str:
    """``doc`` as TOML: plain keys first, then ``[table]`` and ``[[array]]`` blocks."""
    lines, blocks = [], []
    for key, value in doc.items():
        if isinstance(value, dict) and value:
            blocks.append(f"[{_key(key)}]\n" + "".join(f"{_key(k)} = {_value(v)}\n"
                                                         for k, v in value.items()))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for table in value:
                blocks.append(f"[[{_key(key)}]]\n" + "".join(f"{_key(k)} = {_value(v)}\n"
                                                             for k, v in table.items()))
        else:
            lines.append(f"{_key(key)} = {_value(value)}\n")
    return "".join(lines) + "\n".join(blocks)


def _key(key) -> str:
    import json
    return json.dumps(str(key))


def _value(value) -> str:
    import json
    import math
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if value != value else ("inf" if value > 0 else "-inf")
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


def mutate_any(rng: random.Random, name: str, base: bytes) -> bytes:
    """A case for target ``name``: the systems' targets get value edits two times in three."""
    if name in SYSTEMS and rng.random() < 2 / 3:
        return mutate_values(rng, base)
    return mutate(rng, base)


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


