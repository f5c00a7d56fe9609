"""Fuzzing the readers: mutated valid files and random bytes give a Scene or a ReaderError.

Nothing else may escape (no IndexError, no FloatingPointError, no MemoryError), every
ReaderError has a message, and no input makes a reader allocate much: the counts written in a
file are never trusted. Example counts stay modest so that the suite stays fast.
"""

from __future__ import annotations

import re
import struct
import tracemalloc

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import trimesh.exchange.load  # noqa: F401  (imported before tracing: importing allocates)

from core.scene.formats import ReaderError, read_mesh, read_scene_file, read_tri
from core.paths import SCENES_DIR

# Peak memory a reader may take for these small inputs (the inputs are a few KB).
MEMORY_LIMIT = 32_000_000

NASTY = [b"nan", b"inf", b"-inf", b"-1", b"0", b"1e308", b"-1e308", b"1e-320", b"1e40",
         b"99999999999999999999", b"1000000000000", b"abc", b"#", b"\x00", b"", b"3.5", b"+",
         b"-0", b"0x10", b"1_0", "\u0661".encode(), b"\xff\xfe", b"[", b"]", b"{", b"}", b"=",
         b'"', b"'", b"[[geometry]]", b"true", b"1e999", b"-", b"/", b"//", b"f", b"v",
         b"9" * 400, b"vn 1e200 0 0", b"1e200"]

FUZZ = settings(max_examples=60, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@st.composite
def mutated(draw, base: bytes) -> bytes:
    """``base`` with a few byte-level and token-level edits."""
    data = bytearray(base)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["byte", "insert", "delete", "truncate", "token", "repeat"]))
        at = draw(st.integers(0, max(len(data) - 1, 0)))
        if kind == "byte" and data:
            data[at] = draw(st.integers(0, 255))
        elif kind == "insert":
            data[at:at] = draw(st.binary(max_size=8))
        elif kind == "delete":
            del data[at:at + draw(st.integers(1, 24))]
        elif kind == "truncate":
            del data[at:]
        elif kind == "repeat":
            data[at:at] = data[at:at + draw(st.integers(1, 60))]
        else:
            spans = [m.span() for m in re.finditer(rb"[^\s,=\[\]{}]+", bytes(data))]
            if spans:
                a, b = spans[draw(st.integers(0, len(spans) - 1))]
                data[a:b] = draw(st.sampled_from(NASTY))
    return bytes(data)


def only_reader_errors(read, data: bytes) -> None:
    """``read(data)`` returns something or raises ReaderError with a message; memory stays low."""
    tracemalloc.start()
    try:
        try:
            result = read(data)
        except ReaderError as error:
            assert str(error).strip() and error.reason.strip()
        else:
            assert result is not None
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < MEMORY_LIMIT, f"{peak} bytes for a {len(data)}-byte input"


TRI = (SCENES_DIR / "interpenetrating.tri").read_bytes()
OBJ = b"""# a cube: quads, a triangle pair with negative indices, normals
v -1 -1 -1
v 1 -1 -1
v 1 1 -1
v -1 1 -1
v -1 -1 1
v 1 -1 1
v 1 1 1
v -1 1 1
vn 0 0 1
f 5 6 7 8
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
OFF = b"OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"
STL_ASCII = (b"solid fuzz\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
             b"vertex 1 1 0\nendloop\nendfacet\nendsolid fuzz\n")
STL_BINARY = (b"\0" * 80 + struct.pack("<I", 1)
              + struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 1, 0, 0))
SEEDS = {".ply": PLY, ".off": OFF, ".stl": STL_ASCII}
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
"""


def test_the_seeds_are_valid():
    assert read_tri(TRI, "seed.tri").triangle_count == 5
    assert len(read_mesh(OBJ, "seed.obj", ".obj").triangles) == 12
    assert len(read_mesh(PLY, "seed.ply", ".ply").triangles) == 2
    assert read_scene_file(TOML, "seed.toml", SCENES_DIR).triangle_count == 12 + 2 * 8 * 4


@FUZZ
@given(mutated(TRI))
def test_fuzz_tri_mutated(data):
    only_reader_errors(lambda d: read_tri(d, "fuzz.tri"), data)


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_tri_random_bytes(data):
    only_reader_errors(lambda d: read_tri(d, "fuzz.tri"), data)


@FUZZ
@given(mutated(OBJ))
def test_fuzz_obj_mutated(data):
    only_reader_errors(lambda d: read_mesh(d, "fuzz.obj", ".obj"), data)


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_obj_random_bytes(data):
    only_reader_errors(lambda d: read_mesh(d, "fuzz.obj", ".obj"), data)


@settings(FUZZ, max_examples=40)
@given(st.data(), st.sampled_from([".ply", ".off", ".stl"]))
def test_fuzz_other_mesh_formats(data, ext):
    # each format mutated from a valid file of its own, so the fuzz gets past the header
    only_reader_errors(lambda d: read_mesh(d, f"fuzz{ext}", ext), data.draw(mutated(SEEDS[ext])))


@settings(FUZZ, max_examples=40)
@given(st.binary(max_size=60).map(lambda tail: STL_BINARY[:84] + tail))
def test_fuzz_binary_stl(data):
    only_reader_errors(lambda d: read_mesh(d, "fuzz.stl", ".stl"), data)


@pytest.mark.parametrize("ext, seed", [(".off", OFF), (".stl", STL_ASCII), (".stl", STL_BINARY)])
def test_the_fuzz_seeds_are_valid_files(ext, seed):
    assert len(read_mesh(seed, f"seed{ext}", ext).triangles) >= 1


@FUZZ
@given(mutated(TOML))
def test_fuzz_toml_mutated(data):
    only_reader_errors(lambda d: read_scene_file(d, "fuzz.toml", SCENES_DIR), data)


@FUZZ
@given(st.binary(max_size=400))
def test_fuzz_toml_random_bytes(data):
    only_reader_errors(lambda d: read_scene_file(d, "fuzz.toml", SCENES_DIR), data)


@pytest.mark.parametrize("count", [b"1000000000000", b"18446744073709551617", b"999999999999999999999999"])
def test_huge_counts_in_headers_take_no_memory(count):
    only_reader_errors(lambda d: read_tri(d, "x.tri"), TRI.replace(b"\n5\n", b"\n" + count + b"\n"))
    only_reader_errors(lambda d: read_mesh(d, "x.ply", ".ply"), PLY.replace(b"vertex 4", b"vertex " + count))
    only_reader_errors(lambda d: read_mesh(d, "x.off", ".off"), b"OFF\n" + count + b" 1 0\n0 0 0\n3 0 0 0\n")
    stl = b"\0" * 80 + (int(count) % 2 ** 32).to_bytes(4, "little") + b"\0" * 100
    only_reader_errors(lambda d: read_mesh(d, "x.stl", ".stl"), stl)
