"""Malformed and degenerate meshes: what used to load silently wrong is refused
with its line, and a mesh of many copies of one triangle costs what one triangle costs."""

from __future__ import annotations

import struct

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.render import render
from core.scene.formats import ReaderError, load_scene, read_mesh, read_tri
from core.scene.formats.mesh import drop_repeated_triangles, merge_vertices
from core.settings import RenderSettings

PLY_HEAD = (b"ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
            b"property float z\nelement face %d\nproperty list uchar int vertex_indices\n"
            b"end_header\n")
PLY_ROWS = b"0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n"
TRIANGLE_V = b"v 0 0 0\nv 1 0 0\nv 0 1 0\n"


def refused(data: bytes, ext: str) -> ReaderError:
    with pytest.raises(ReaderError) as info:
        read_mesh(data, "bad" + ext, ext)
    return info.value


@pytest.mark.parametrize("data, line, reason", [
    (PLY_HEAD % (5, 2) + PLY_ROWS, 14, "element 'vertex' row 4: its properties take 3 numbers, "
                                       "the line holds 4"),
    (PLY_HEAD % (4, 5) + PLY_ROWS, 16, "the file ends after 2 rows of element 'face'; the "
                                       "header (line 7) says 5"),
    (PLY_HEAD % (4, 1) + PLY_ROWS, 15, "more rows than the header's elements say"),
    (PLY_HEAD % (4, 2) + PLY_ROWS.replace(b"3 0 2 3", b"4 0 2 3"), 15,
     "element 'face' row 1: its properties take 5 numbers, the line holds 4"),
    (PLY_HEAD % (4, 2) + PLY_ROWS.replace(b"3 0 2 3", b"x 0 2 3"), 15,
     "a list count must be a whole number"),
])
def test_ply_rows_must_match_the_header(data, line, reason):
    error = refused(data, ".ply")
    assert error.line == line and reason in error.reason


_TOKENS = ["0", "1", "2", "3", "4", "12", "x", "-1", "1e3", "0" * 11, "é"]
_GAPS = [" ", "  ", "\t", "\r", "\n", "\n\n", "\x0b", "\x1c"]


@settings(max_examples=400, deadline=None)
@given(st.lists(st.tuples(st.sampled_from(_TOKENS), st.sampled_from(_GAPS)), max_size=40),
       st.integers(0, 5), st.integers(0, 5))
def test_the_quick_ply_row_check_agrees_with_the_row_by_row_one(pairs, vertices, faces):
    """Consistency check between our two checks (the row-by-row one, which names the bad
    row, is the reference): whatever the numpy check accepts, the row-by-row one accepts too,
    and on ASCII text they agree."""
    from core.scene.formats.mesh.ply import _check_ply_ascii_rows_one_by_one, _ply_ascii_layout
    body = "".join(token + gap for token, gap in pairs)
    elements = [["vertex", vertices, 3, 0, [False] * 3], ["face", faces, 7, 0, [True]]]
    try:
        _check_ply_ascii_rows_one_by_one(body, elements, 10, "f.ply")
        fits = True
    except ReaderError:
        fits = False
    quick = _ply_ascii_layout(body, elements) is not None
    assert not quick or fits
    if body.isascii() and not any("0" * 10 in token for token, _ in pairs):
        assert quick == fits


def test_a_valid_ascii_ply_still_loads():
    mesh = read_mesh(PLY_HEAD % (4, 2) + PLY_ROWS, "ok.ply", ".ply")
    assert mesh.triangles.tolist() == [[0, 1, 2], [0, 2, 3]]


OFF_V = b"0 0 0\n1 0 0\n0 1 0\n"


@pytest.mark.parametrize("data, line, reason", [
    (b"OFF\n3 1 0\n" + OFF_V + b"1000000000 0 1 2\n", 6,
     "face 0: the row says 1000000000 corners but holds 3 numbers"),
    (b"OFF\n3 1 0\n" + OFF_V + b"4 0 1 2\n", 6, "face 0: the row says 4 corners but holds 3"),
    (b"OFF\n3 1 0\n" + OFF_V + b"2 0 1 0 0\n", 6, "a face needs at least 3 corners, got 2"),
    (b"garbageOFF\n3 1 0\n" + OFF_V + b"3 0 1 2\n", 1, "not an OFF file"),
    (b"OFF\n3 1 0\n" + OFF_V + b"3 0 1 2\n3 0 1 2\n", 7, "more rows than the counts say"),
    (b"OFF\n3 1 0\n0 0\n1 0 0 5\n0 1 0\n3 0 1 2\n3 0 1 2\n", 3, "a vertex row is 3 coordinates"),
])
def test_off_rows_must_match_their_counts(data, line, reason):
    error = refused(data, ".off")
    assert error.line == line and reason in error.reason


def test_off_with_colours_still_loads():
    mesh = read_mesh(b"COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n"
                     b"3 0 1 2 255 0 0\n", "c.off", ".off")
    assert mesh.triangles.tolist() == [[0, 1, 2]]


@pytest.mark.parametrize("data, line, reason", [
    (TRIANGLE_V + b"f 1//9 2//9 3//9\n", 4, "normal index 9 is out of range: 0 normals (vn)"),
    (TRIANGLE_V + b"f 1/5 2/5 3/5\n", 4, "texture coordinate index 5 is out of range"),
    (TRIANGLE_V + b"vn 0 0 1\nf 1//1 2//1 3//2\n", 5, "normal index 2 is out of range: 1 normals"),
    (TRIANGLE_V + b"vn 1 0 0 7\nf 1//1 2//1 3//1\n", 4, "a normal (vn) has exactly 3 coordinates"),
    (TRIANGLE_V + b"vt 0 0 0 0\nf 1/1 2/1 3/1\n", 4, "a texture coordinate (vt) has 1 to 3"),
    (TRIANGLE_V + b"f 1/ 2 3\n", 4, "is not v, v/vt, v//vn or v/vt/vn"),
    (TRIANGLE_V + b"f 1/1/1/1 2 3\n", 4, "is not v, v/vt, v//vn or v/vt/vn"),
    (TRIANGLE_V + b"vn 0 0 1\nf 1//-1 2//-1 3//-1\nvn 0 0 1\n", 6,
     "a record defined after the negative (relative) index on line 5"),
])
def test_obj_references_must_exist(data, line, reason):
    error = refused(data, ".obj")
    assert error.line == line and reason in error.reason


def test_a_tab_separated_obj_reads_like_a_spaced_one():
    spaced = TRIANGLE_V + b"vn 0 0 1\nf 1//1 2//1 3//1\n"
    tabbed = spaced.replace(b" ", b"\t")
    a, b = read_mesh(spaced, "s.obj", ".obj"), read_mesh(tabbed, "t.obj", ".obj")
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.triangles, b.triangles)
    assert np.array_equal(a.normals, b.normals)


# ----------------------------------------------------------------------------- repeats

def old_merge(points):
    """The former merge_vertices (np.unique on rows), the oracle for the column sort."""
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3) + 0.0
    unique, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    return unique[order], rank[inverse.reshape(-1)]


@settings(max_examples=60, deadline=None, derandomize=True)
@given(st.lists(st.tuples(*[st.sampled_from([0.0, -0.0, 1.0, 2.5, -1e300, 5e-324])] * 3),
                min_size=1, max_size=40))
def test_merge_vertices_agrees_with_hashing_by_unique(rows):
    got, inverse = merge_vertices(np.array(rows))
    want, want_inverse = old_merge(np.array(rows))
    assert np.array_equal(got, want) and np.array_equal(inverse, want_inverse)
    assert np.array_equal(got[inverse], np.array(rows) + 0.0)


def test_repeats_are_dropped_and_the_other_winding_kept():
    t = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1], [0, 2, 1], [3, 4, 5], [0, 1, 2], [1, 0, 2]])
    assert drop_repeated_triangles(t).tolist() == [[0, 1, 2], [0, 2, 1], [3, 4, 5]]


def _copies_stl(count: int) -> bytes:
    record = struct.pack("<12fH", 0, 0, 1, -1, -1, 0, 1, -1, 0, 0, 1, 0, 0)
    return b"\0" * 80 + struct.pack("<I", count) + record * count


def test_many_copies_of_one_triangle_render_as_one(tmp_path):
    """200,000 copies of one triangle (a reported 4.2M-triangle STL, scaled down): one triangle after
    loading, and the same picture as a file with one copy."""
    (tmp_path / "many.stl").write_bytes(_copies_stl(200_000))
    (tmp_path / "one.stl").write_bytes(_copies_stl(1))
    many, one = load_scene(tmp_path / "many.stl"), load_scene(tmp_path / "one.stl")
    assert many.triangle_count == 1 and len(many.meshes[0].positions) == 3
    for shading in ("flat", "phong"):
        settings = RenderSettings.for_scene(many, shading=shading, size=(64, 64))
        a = render(many, many.views[0], settings)
        b = render(one, one.views[0], settings)
        assert a.message is None and np.array_equal(a.color, b.color)
        assert (a.color != a.color[0, 0]).any()            # the triangle is in the picture


def test_repeats_in_a_tri_file_are_dropped():
    text = "0 0 10\n-1 1 0\n0.01 0 0\n0 -0.01 0\n3\n" + "0 0 0 1 0 0 0 1 0\n" * 2 + \
           "0 0 0 0 1 0 1 0 0\n"
    scene = read_tri(text, "r.tri")
    assert scene.meshes[0].triangles.tolist() == [[0, 1, 2], [0, 2, 1]]


def test_a_closed_mesh_with_a_repeated_face_is_closed():
    cube = read_mesh(b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                     b"f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"
                     b"f 5 6 7 8\n", "cube.obj", ".obj")
    assert cube.closed and len(cube.triangles) == 12
