"""The ASCII PLY fast path (numpy alone, no trimesh) reads exactly what trimesh reads: the
bunny, generated files of every shape it takes, and files it must leave to trimesh."""

from __future__ import annotations

import re
import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import ROOT
from core.scene.formats import ReaderError, read_mesh
from core.scene.formats.mesh import ply, read


def _read(data: bytes, fast: bool):
    """read_mesh's Mesh, or its ReaderError's text, with the fast path on or off."""
    was = ply.FAST_ASCII_PLY
    ply.FAST_ASCII_PLY = fast
    try:
        return read_mesh(data, "g.ply", ".ply")
    except ReaderError as error:
        return str(error)
    finally:
        ply.FAST_ASCII_PLY = was


def _fast_part(data: bytes):
    """What the fast path makes of ``data`` (None: it leaves the file to trimesh)."""
    rows = ply.check_ply(data, "g.ply", 10 ** 9)
    return None if rows is None else ply.fast_ascii_ply(data, rows)


def _same(a, b) -> bool:
    """Bit for bit (-0.0 is not 0.0), shape and type; or both None."""
    if a is None or b is None:
        return a is None and b is None
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _assert_same_reading(data: bytes) -> None:
    fast, slow = _read(data, True), _read(data, False)
    if isinstance(slow, str) or isinstance(fast, str):
        assert fast == slow
        return
    for field in ("positions", "triangles", "normals", "uv"):
        assert _same(getattr(fast, field), getattr(slow, field)), field
    assert fast.closed == slow.closed


# ----------------------------------------------------------------------------- the bunny

def test_the_bunny_reads_as_trimesh_reads_it(bunny_path):
    data = bunny_path.read_bytes()
    part = _fast_part(data)
    assert part is not None, "the bunny must take the fast path"
    _assert_same_parts(part, data)
    _assert_same_reading(data)


def test_reading_the_bunny_does_not_import_trimesh(bunny_path):
    _assert_no_trimesh(bunny_path)


def test_reading_a_small_ascii_ply_does_not_import_trimesh(tmp_path):
    path = tmp_path / "square.ply"
    path.write_bytes(_ply([("x", "float"), ("y", "float"), ("z", "float")],
                          [["0", "0", "0"], ["1", "0", "0"], ["1", "1", "0"], ["0", "1", "0"]],
                          [[0, 1, 2, 3]]))
    _assert_no_trimesh(path)


def _assert_no_trimesh(path) -> None:
    code = ("import sys; from core.scene.formats import read_mesh; "
            f"m = read_mesh(open({str(path)!r}, 'rb').read(), 'f.ply', '.ply'); "
            "print(len(m.triangles), 'trimesh' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    triangles, imported = done.stdout.split()
    assert int(triangles) > 0 and imported == "False"


# ----------------------------------------------------------------------------- numbers

_DECIMAL = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?")


def _numbers(tokens: list[str]):
    body = " ".join(tokens) + "\n"
    rows = ply._ply_ascii_layout(body, [["vertex", 1, 0, 0, [False] * len(tokens)]])
    numbers = ply._ply_numbers(rows, 1)
    return None if numbers is None else numbers[0].reshape(-1)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.text("0123456789+-.eE", min_size=1, max_size=20)
                | st.from_regex(_DECIMAL, fullmatch=True).filter(lambda t: len(t) < 40)
                | st.floats(allow_nan=False, allow_infinity=False).map(repr)
                | st.integers(-10 ** 20, 10 ** 20).map(str),
                min_size=1, max_size=30))
def test_numbers_are_read_as_strtod_reads_them(tokens):
    """Every token of the form [+-]digits[.digits][e[+-]digits] is read, bit for bit as
    float() (and trimesh's np.fromstring) reads it; any other token, or one too large for a
    float64 (inf: the library's reading then names the vertex), refuses the lot."""
    values = _numbers(tokens)
    if not all(_DECIMAL.fullmatch(t) for t in tokens):
        assert values is None
        return
    expected = np.array([float(t) for t in tokens])
    if not np.all(np.isfinite(expected)):
        assert values is None
        return
    assert _same(values, expected)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        assert _same(np.fromstring(" ".join(tokens), sep=" "), expected)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.lists(st.sampled_from(["0", "-1.5", "12", "x", "1e3"]), min_size=2,
                         max_size=2), max_size=12),
       st.lists(st.sampled_from([" ", "\t", " \r", "\x0b", "\x1c"]), min_size=24, max_size=24),
       st.lists(st.sampled_from(["\n", "\r\n", "\n\n", "\n \t\n", " \n"]), min_size=13,
                max_size=13))
def test_the_row_check_finds_every_token_and_row_line(rows, gaps, breaks):
    """Where the quick row check says the tokens and rows are: str.split()'s tokens, and
    the lines of body.split("\n") that hold any."""
    body = breaks[-1] + "".join(gaps[2 * i] + a + gaps[2 * i + 1] + b + breaks[i]
                                for i, (a, b) in enumerate(rows))
    layout = ply._ply_ascii_layout(body, [["vertex", len(rows), 0, 0, [False] * 2]])
    assert layout is not None
    assert [body[a:].split(maxsplit=1)[0] for a in layout.starts] == body.split()
    filled = [k for k, line in enumerate(body.split("\n")) if line.split()]
    assert layout.lines.tolist() == filled and layout.sizes.tolist() == [2] * len(rows)


# ----------------------------------------------------------------------------- whole files

_TYPES = ["char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8",
          "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"]
_INTEGER = {"char", "uchar", "short", "ushort", "int", "uint", "int8", "uint8", "int16",
            "uint16", "int32", "uint32"}
_FORMS = ["{:g}", "{:.6f}", "{!r}", "{:.3e}", "{:E}", "{:.0f}."]


def _ply(properties, vertex_rows, faces, extra_lines="", gap=" ", end="\n",
         corners="vertex_indices", corner_type="int") -> bytes:
    head = ["ply", "format ascii 1.0", "comment made by a test",
            f"element vertex {len(vertex_rows)}"]
    head += [f"property {kind} {name}" for name, kind in properties]
    head += [f"element face {len(faces)}", f"property list uchar {corner_type} {corners}"]
    head += [line for line in extra_lines.split("\n") if line] + ["end_header"]
    rows = [gap.join(row) for row in vertex_rows]
    rows += [gap.join([str(len(f))] + [str(i) for i in f]) for f in faces]
    return ("\n".join(head) + "\n" + end.join(rows) + end).encode()


@st.composite
def _coordinate(draw):
    """A float in a random written form, or one of the odd forms numbers take."""
    if draw(st.booleans()):
        return draw(st.sampled_from(["1e-3", "-0", ".5", "5.", "+2", "-0.0", "0", "+.25",
                                     "-7.", "1E+2", "2.5e-01", "0000.125", "-1234.5678"]))
    value = draw(st.floats(-1e4, 1e4, allow_nan=False) | st.sampled_from([0.0, -0.0, 1e-30]))
    return draw(st.sampled_from(_FORMS)).format(value)


@st.composite
def _ply_file(draw):
    """``(data, fast)``: an ASCII PLY of a mesh, and whether the fast path must take it."""
    count = draw(st.integers(3, 12))
    names = ["x", "y", "z"]
    if draw(st.booleans()):
        names += ["nx", "ny", "nz"]
    texture = draw(st.sampled_from([None, *ply._PLY_TEXTURE_NAMES]))
    names += list(texture or [])
    extras = draw(st.lists(st.sampled_from(["confidence", "intensity", "red", "w"]),
                           unique=True, max_size=3))
    names = draw(st.permutations(names + extras))
    properties = [(n, draw(st.sampled_from(_TYPES))) for n in names]
    rows = [[_value(draw, kind) for _, kind in properties] for _ in range(count)]
    k = draw(st.sampled_from([3, 3, 4, 5]))
    faces = [draw(st.lists(st.integers(0, count - 1), min_size=k, max_size=k))
             for _ in range(draw(st.integers(1, 8)))]
    gap = draw(st.sampled_from([" ", "  ", "\t", " \t "]))
    end = draw(st.sampled_from(["\n", "\r\n", " \n", "\t\r\n"]))
    corners = draw(st.sampled_from(ply._PLY_CORNER_NAMES))
    return _ply(properties, rows, faces, gap=gap, end=end, corners=corners), texture is None


def _value(draw, kind: str) -> str:
    if kind in _INTEGER:
        low, high = (0, 127) if kind in ("uchar", "uint8", "char", "int8") else (-1000, 1000)
        low = 0 if kind.startswith("u") else low
        return str(draw(st.integers(low, high)))
    return draw(_coordinate())


@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_ply_file())
def test_generated_files_read_as_trimesh_reads_them(made):
    data, fast = made
    part = _fast_part(data)
    assert (part is not None) == fast
    if part is not None:
        _assert_same_parts(part, data)
    _assert_same_reading(data)


_XYZ = [("x", "float"), ("y", "float"), ("z", "float")]
_SQUARE = [["0", "0", "0"], ["1", "0", "0"], ["1", "1", "0"], ["0", "1", "0"], ["1", "0", "1"]]
_QUADS = [[0, 1, 2, 3], [1, 2, 3, 0]]
_BASE = _ply(_XYZ, _SQUARE, _QUADS)


def _with_token(token: str, row: int = 1, column: int = 0) -> bytes:
    rows = [list(r) for r in _SQUARE]
    rows[row][column] = token
    return _ply(_XYZ, rows, _QUADS)


_LEFT_TO_TRIMESH = {
    # a token that is not a number, or not one that strtod and float() agree on
    **{f"token {t!r}": _with_token(t) for t in ["abc", "inf", "nan", "1_0", "1e", "0x10",
                                                "1-2", "1.2.3", "--1", ".", "+"]},
    "mixed polygon sizes": _ply(_XYZ, _SQUARE, [[0, 1, 2, 3], [1, 2, 3]]),
    "triangles with a quad": _ply(_XYZ, _SQUARE, [[0, 1, 2], [1, 2, 3, 0]]),
    "two-corner faces": _ply(_XYZ, _SQUARE, [[0, 1], [1, 2]]),
    "another element": _ply(_XYZ, _SQUARE, _QUADS, "element edge 1\nproperty int vertex1\n"
                                                   "property int vertex2") + b"0 1\n",
    "a blank line between rows": _BASE.replace(b"\n0 1 0\n", b"\n\n0 1 0\n"),
    "a vertical tab": _BASE.replace(b"\n0 1 0\n", b"\n0\x0b1 0\n"),
    "a unit separator": _BASE.replace(b"\n0 1 0\n", b"\n0\x1f1 0\n"),
    "rows from the second line": _BASE.replace(b"end_header\n", b"end_header\n\n"),
    # headers that trimesh reads otherwise than our check does
    "a blank header line": _BASE.replace(b"comment made by a test\n",
                                         b"comment made by a test\n\n"),
    "a 4-word property": _BASE.replace(b"property float z\n", b"property float z extra\n"),
    "a repeated property": _BASE.replace(b"property float y\n", b"property float x\n"),
    "format on line 3": _BASE.replace(b"format ascii 1.0\ncomment made by a test",
                                      b"comment made by a test\nformat ascii 1.0"),
    "end_header inside a comment": _BASE.replace(b"comment made by a test",
                                                 b"comment xend_header"),
    "corners under another name": _ply(_XYZ, _SQUARE, _QUADS, corners="corners"),
    "float corners": _ply(_XYZ, _SQUARE, _QUADS, corner_type="float"),
    "no x": _ply([("w", "float"), ("y", "float"), ("z", "float")], _SQUARE, _QUADS),
    # texture coordinates: trimesh cuts the mesh along its seams
    **{f"texture {u} {v}": _ply(_XYZ + [(u, "float"), (v, "double")],
                                [r + ["0.5", "-.25"] for r in _SQUARE], _QUADS)
       for u, v in ply._PLY_TEXTURE_NAMES},
    # numbers that do not fit their declared type (numpy set to raise, as the tests set it)
    "a float32 overflow": _with_token("1e300"),
    "an int32 overflow": _ply(_XYZ, _SQUARE, [[0, 1, 2, 3000000000], [1, 2, 3, 0]]),
}

# Files the fast path reads, though they are odd: it must read them as trimesh does.
_TAKEN_ODD = {
    "a negative corner": _ply(_XYZ, _SQUARE, [[0, 1, 2, -3], [1, 2, 3, 0]]),
    "a corner past the vertices": _ply(_XYZ, _SQUARE, [[0, 1, 2, 9], [1, 2, 3, 0]]),
    "a fractional corner": _ply(_XYZ, _SQUARE, [[0, 1, 2, 2.5], [1, 2, 3, 0]]),
    "uchar corners": _ply(_XYZ, _SQUARE, _QUADS, corner_type="uchar"),
    "integer coordinates": _ply([("x", "int"), ("y", "uchar"), ("z", "short")],
                                [["1", "2", "3"], ["0", "0", "0"], ["7", "0", "1"],
                                 ["2.75", "-0", "1e2"], ["-4", "250", "+3"]], _QUADS),
    "a huge coordinate": _with_token("123456789012345.6"),
    "a long decimal": _with_token("0.1000000000000000055511151231257827"),
    "a NaN-free zero normal": _ply(_XYZ + [("nx", "float"), ("ny", "float"), ("nz", "float")],
                                   [r + ["0", "0", "0"] for r in _SQUARE], _QUADS),
    "pentagons": _ply(_XYZ, _SQUARE, [[0, 1, 2, 3, 4]]),
    "CRLF and tabs": _ply(_XYZ, _SQUARE, _QUADS, gap="\t", end="\r\n"),
    "vertex_index": _ply(_XYZ, _SQUARE, _QUADS, corners="vertex_index"),
    "only s of s t": _ply(_XYZ + [("s", "float")], [r + ["1"] for r in _SQUARE], _QUADS),
    "no trailing newline": _BASE.rstrip(b"\n"),
    "blank lines after the rows": _BASE + b"\n\n  \n",
}


@pytest.mark.parametrize("data", _LEFT_TO_TRIMESH.values(), ids=_LEFT_TO_TRIMESH.keys())
def test_files_left_to_trimesh_read_as_trimesh_reads_them(data):
    assert _fast_part(_BASE) is not None
    try:
        part = _fast_part(data)
    except ReaderError:                  # refused by our check: trimesh never sees it
        part = None
    assert part is None
    _assert_same_reading(data)


@pytest.mark.parametrize("data", _TAKEN_ODD.values(), ids=_TAKEN_ODD.keys())
def test_odd_files_the_fast_path_takes_read_as_trimesh_reads_them(data):
    part = _fast_part(data)
    assert part is not None
    _assert_same_parts(part, data)
    _assert_same_reading(data)


def _assert_same_parts(part: dict, data: bytes) -> None:
    """The fast path's kwargs are trimesh's, bit for bit and type for type."""
    library = read._library_parts(data, ".ply", "g.ply")[0]
    for key in ("vertices", "faces", "vertex_normals"):
        assert _same(part.get(key), library.get(key)), key
