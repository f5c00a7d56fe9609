"""Mesh files (Wavefront OBJ, PLY, OFF, STL) read through trimesh into a :class:`Mesh`; the
common ASCII PLY with numpy alone, as trimesh would read it.

Takes the bytes of a mesh file and returns a Mesh: positions (V, 3), triangles (T, 3),
vertex normals when the file has them, and ``closed`` when every edge is shared by exactly two
triangles of opposite orientation and the enclosed volume is positive (CCW seen from outside),
so that back faces may be culled (FvDFH 15.2.4).

Why trimesh and not a parser of our own: it is well kept and already handles the corners of
these formats that a hand parser gets wrong: OBJ polygons fanned into triangles, negative
(relative) indices, ``v/vt/vn`` triplets unmerged into vertices that carry their own normal;
PLY in ASCII and both binary byte orders with any property types; binary and ASCII STL; OFF.
We call its format loaders (``trimesh.exchange.load.mesh_loaders``) directly instead of
``trimesh.load(..., force="mesh")``, because turning the loaded scene into one mesh drops the
normals the file carries (trimesh 4.x); faces that are all k-gons come back from a loader
untriangulated (trimesh's mesh constructor would fan them), so :func:`fan` does that here.
trimesh does not validate everything, and some
malformed input goes through silently (an OBJ face index 0 becomes vertex 1; one vertex line with
two numbers makes it drop or shift the coordinates of the others; an ASCII PLY whose header
over-counts its vertices loads the faces as vertices). So a short linear pass checks each
format's structure first and reports the line, and the result is checked for NaN, infinities,
coordinates beyond 1e30 and indices out of range.
Every trimesh exception becomes a :class:`ReaderError` naming the file. Vertices that are equal
are merged into one by hashing (``np.unique`` on rows), as the course's ``.tri`` reader does.

ASCII PLY fast path: trimesh reads an ASCII PLY a line at a time (``np.fromstring`` per line,
then a stack of the rows: 0.33-0.39 s for the Stanford bunny's 105k lines) and importing it
costs another 0.13-0.25 s, so the bunny took 0.5-0.7 s. The common file (a ``vertex`` element of
scalars with x, y, z and no texture coordinates, a ``face`` element of one list of integer
corners, as many on every row) is read by :func:`_fast_ascii_ply` with numpy alone: the row
check has already found where the vertex rows end, and each block is parsed in one call of
numpy's C text reader (``np.loadtxt``, correctly rounded as trimesh's parser rounds), then
cast to the declared types as trimesh casts them. The result is trimesh's, bit for bit
(``tests/test_ply_fast.py`` compares); any other file goes to trimesh. The bunny's
``read_mesh`` now takes 0.2 s (its check 30-40 ms, the parse ~60 ms, merging, repeats and
closedness the rest), trimesh never imported.
"""

from __future__ import annotations

import contextlib
import gc
import io
import logging
import re
import struct
from typing import NamedTuple

import numpy as np

from core.scene.formats.errors import (MAX_COORDINATE, ReaderError, decode_text, file_stem, short,
                                 tolerant_of_underflow, whole_number)
from core.transforms import unit_rows
from core.scene.model import Mesh

MESH_EXTENSIONS = (".obj", ".ply", ".off", ".stl")
_QUIET = logging.NullHandler()            # added once: a logger keeps a set-like list


# ----------------------------------------------------------------------------- mesh helpers

def merge_vertices(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equal rows of ``points`` ``(N, k)`` (positions, or positions with more columns such as
    (u, v)) become one vertex, numbered in order of first appearance.

    Returns ``(positions, inverse)`` with ``positions[inverse] == points``. ``-0.0`` and
    ``0.0`` are equal, as they are for the C ``==`` of the startup code.
    """
    points = np.asarray(points, dtype=np.float64)
    points = (points.reshape(-1, 3) if points.ndim != 2 else points) + 0.0    # -0.0 -> 0.0
    first, inverse = _first_of_equal_rows(points)
    return points[first], inverse


def _first_of_equal_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(first, inverse)``: the index of the first of each set of equal rows, in order of
    appearance, and for every row the number of its set (``rows[first][inverse] == rows``).

    Hashing by sorting, O(N log N) whatever the data (never the startup code's O(N^2) scan):
    a stable sort by the columns (``np.lexsort``; ``np.unique(axis=0)`` sorts rows as opaque
    records, 9 s for a million copies of one triangle), then a new set wherever a row differs
    from the one before it.
    """
    n = len(rows)
    if n == 0:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    order = np.lexsort(rows.T[::-1])                    # stable: equal rows keep file order
    ordered = rows[order]
    starts = np.ones(n, dtype=bool)
    starts[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    group = np.cumsum(starts) - 1                       # set number, in sorted order
    first = order[starts]                               # stable: the first of each set
    by_appearance = np.argsort(first, kind="stable")
    rank = np.empty_like(by_appearance)
    rank[by_appearance] = np.arange(len(first))
    inverse = np.empty(n, dtype=np.int64)
    inverse[order] = rank[group]
    return first[by_appearance], inverse


def drop_repeated_triangles(triangles: np.ndarray) -> np.ndarray:
    """The triangles without exact repeats (the same three vertices in the same cyclic order),
    the first of each kept, in file order.

    A repeat draws nothing: it covers the pixels of its first copy at the same depth, and the
    z-buffer keeps the first (FvDFH's strict depth test). But it costs the raster its area
    again, so a file of a million copies of one large triangle would cost a million times its
    pixels; without repeats a frame costs at most its distinct triangles plus the pixels. The
    opposite winding (b, a, c) is not a repeat: it is the other face of the triangle.
    """
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) < 2:
        return t
    lowest = np.argmin(t, axis=1)                       # rotate the smallest index first
    turn = (lowest[:, None] + np.arange(3)) % 3
    canonical = np.take_along_axis(t, turn, axis=1)
    first, _ = _first_of_equal_rows(canonical)
    return t if len(first) == len(t) else t[first]


def fan(polygons: np.ndarray) -> np.ndarray:
    """``(F, k)`` polygons as ``(F (k - 2), 3)`` triangles fanned from each first corner."""
    k = polygons.shape[1]
    if k == 3:
        return polygons
    corners = np.arange(1, k - 1)
    return np.stack([np.repeat(polygons[:, :1], k - 2, axis=1), polygons[:, corners],
                     polygons[:, corners + 1]], axis=-1).reshape(-1, 3)


def edge_problem(triangles: np.ndarray) -> str | None:
    """Why the triangles are not a closed, consistently wound surface; None when they are.

    Closed and consistent means every directed edge (a, b) occurs exactly once and its
    opposite (b, a) occurs exactly once too (two neighbours, opposite orientation).
    """
    t = np.asarray(triangles, dtype=np.int64).reshape(-1, 3)
    if len(t) == 0:
        return "the mesh has no triangles"
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    if np.any(directed[:, 0] == directed[:, 1]):
        return "a triangle repeats a vertex"
    # One int64 key per directed edge (a, b): sorting keys is the hash here.
    base = int(t.max()) + 1
    keys, counts = np.unique(directed[:, 0] * base + directed[:, 1], return_counts=True)
    if np.any(counts > 1):
        key = int(keys[np.argmax(counts > 1)])
        return (f"edge ({key // base}, {key % base}) is used twice in the same direction "
                f"(inconsistent winding)")
    reverse = (keys % base) * base + keys // base
    found = np.isin(reverse, keys, assume_unique=True)
    if not np.all(found):
        key = int(keys[np.argmin(found)])
        return f"edge ({key // base}, {key % base}) has no neighbour across it (the surface has a border)"
    return None


def signed_volume(positions: np.ndarray, triangles: np.ndarray) -> float:
    """Volume enclosed by the triangles, positive when they are wound CCW seen from outside."""
    p = np.asarray(positions, dtype=np.float64)[np.asarray(triangles, dtype=np.int64)]
    return float(np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0)


def is_closed(positions: np.ndarray, triangles: np.ndarray) -> bool:
    """Closed, consistently wound and outward facing (positive signed volume)."""
    return edge_problem(triangles) is None and signed_volume(positions, triangles) > 0.0


# ----------------------------------------------------------------------------- pre-checks

_OBJ_INDEX = re.compile(r"[+-]?\d+")


def _over_budget(file: str, what: str, count: int, budget: int, line: int | None = None):
    return ReaderError(file, f"{what} {count} triangles; the limit is {budget} (the triangle "
                             f"budget of a scene)", line)


# The records an OBJ face may refer to, with the numbers each takes: a vertex 3 (plus an
# optional w, or RGB, or both), a texture coordinate 1 to 3 (u [v [w]]), a normal exactly 3.
_OBJ_RECORDS = {"v": ("vertex", (3, 4, 6, 7)), "vt": ("texture coordinate", (1, 2, 3)),
                "vn": ("normal", (3,))}
_OBJ_SLOTS = ("v", "vt", "vn")           # the parts of a face corner v/vt/vn


def _check_obj(text: str, file: str, budget: int) -> None:
    """Line-precise structure check of an OBJ: vertex, texture and normal records, and faces.

    Every index of a face corner ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn`` must refer to a
    record that exists (positive indices count from 1, negative ones back from the last record
    defined so far); index 0 does not exist in OBJ. A reference to a missing ``vt`` or ``vn``
    is refused, not dropped. The triangles the faces fan into are counted against ``budget``
    as they come.
    """
    defined = {"v": 0, "vt": 0, "vn": 0}
    triangles = 0
    negative_at = None
    for number, line in enumerate(text.split("\n"), start=1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        key = fields[0]
        if key in _OBJ_RECORDS:
            if negative_at is not None:
                raise ReaderError(file, f"a record defined after the negative (relative) index "
                                        f"on line {negative_at}: the mesh library resolves "
                                        f"relative indices against the final lists, so this "
                                        f"file would be misread", number)
            _check_obj_record(key, fields[1:], file, number)
            defined[key] += 1
        elif key == "f":
            if len(fields) < 4:
                raise ReaderError(file, f"a face needs at least 3 vertices, got {len(fields) - 1}",
                                  number)
            triangles += len(fields) - 3
            if triangles > budget:
                raise _over_budget(file, "the faces up to here make", triangles, budget, number)
            for ref in fields[1:]:
                if _check_obj_corner(ref, defined, file, number) and negative_at is None:
                    negative_at = number


def _check_obj_record(key: str, numbers: list[str], file: str, line: int) -> None:
    what, counts = _OBJ_RECORDS[key]
    if len(numbers) not in counts:
        if key != "vt" and len(numbers) < 3:
            raise ReaderError(file, f"a {what} needs 3 coordinates, got {len(numbers)}", line)
        wanted = {"v": "3 coordinates (plus an optional w, or RGB)",
                  "vt": "1 to 3 coordinates (u [v [w]])", "vn": "exactly 3 coordinates"}[key]
        raise ReaderError(file, f"a {what} ({key}) has {wanted}, got {len(numbers)} numbers",
                          line)
    for token in numbers:
        try:
            value = float(token)
        except ValueError:
            raise ReaderError(file, f"{what} coordinate {short(token)} is not a number",
                              line) from None
        if not np.isfinite(value):
            raise ReaderError(file, f"{what} coordinate {short(token)} is NaN or infinite", line)


def _check_obj_corner(ref: str, defined: dict, file: str, line: int) -> bool:
    """Check one face corner; True when it uses a negative (relative) index."""
    parts = ref.split("/")
    if len(parts) > 3 or not parts[0] or (len(parts) == 3 and not parts[2]) \
            or (len(parts) == 2 and not parts[1]):
        raise ReaderError(file, f"face vertex {short(ref)} is not v, v/vt, v//vn or v/vt/vn",
                          line)
    negative = False
    for slot, index in zip(_OBJ_SLOTS, parts):
        if not index:
            continue                                # v//vn: no texture coordinate
        if not _OBJ_INDEX.fullmatch(index):
            raise ReaderError(file, f"face vertex {short(ref)}: {short(index)} is not an index",
                              line)
        what = _OBJ_RECORDS[slot][0]
        name = "a face index" if slot == "v" else f"a face's {what} index"
        k = whole_number(index, file, line, name, signed=True)
        n = defined[slot]
        if k == 0 or k > n or -k > n:
            runs = f" (indices run 1..{n} or -1..-{n})" if n else ""
            if slot == "v":
                raise ReaderError(file, f"face index {k} is out of range: {n} vertices are "
                                        f"defined before this line{runs}", line)
            raise ReaderError(file, f"face vertex {short(ref)}: {what} index {k} is out of "
                                    f"range: {n} {what}s ({slot}) are defined before this "
                                    f"line{runs}", line)
        negative |= k < 0
    return negative


# The PLY property types we read, as numpy types (the mesh library's names for them).
_PLY_DTYPES = {"char": "i1", "uchar": "u1", "int8": "i1", "uint8": "u1", "short": "i2",
               "ushort": "u2", "int16": "i2", "uint16": "u2", "int": "i4", "uint": "u4",
               "int32": "i4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
               "float64": "f8"}
_PLY_SIZES = {name: np.dtype(code).itemsize for name, code in _PLY_DTYPES.items()}


def _check_ply(data: bytes, file: str, budget: int) -> _AsciiRows | None:
    """Check a PLY header and that the data after it can hold the element counts it declares.

    The smallest possible row of each element is known from its properties (binary: the bytes
    of the scalars and of each list's count; ASCII: two characters per value), so a header that
    promises more rows than the bytes that follow can hold is refused before any reading.
    Returns where the numbers of an ASCII file are when its rows passed the quick check (for
    :func:`_fast_ascii_ply`), else None.
    """
    end = data.find(b"end_header")
    if not data.startswith(b"ply") or end < 0:
        raise ReaderError(file, "not a PLY file: it must start with 'ply' and have an "
                                "'end_header' line", 1)
    newline = data.find(b"\n", end)
    body = len(data) - (newline + 1 if newline >= 0 else len(data))
    header = decode_text(data[:end], file)
    fmt, elements = _ply_header(header, file)
    _check_ply_counts(elements, body, budget, file)
    if fmt != "ascii":
        return None
    first_line = header.count("\n") + 2               # the line after end_header
    return _check_ply_ascii_rows(decode_text(data[newline + 1:], file) if newline >= 0 else "",
                                 elements, first_line, file)


def _ply_header(header: str, file: str) -> tuple[str, list[list]]:
    """The header's format and its elements, each ``[name, count, line, min_row, lists]``:
    the smallest row in bytes (binary; ASCII: two characters a value) and, per property,
    whether it is a list."""
    fmt = None
    elements: list[list] = []                 # [name, count, line, min_row_bytes_or_values]
    for number, line in enumerate(header.split("\n"), start=1):
        fields = line.split()
        if not fields or fields[0] in ("comment", "obj_info", "ply"):
            continue
        if fields[0] == "format":
            if len(fields) < 2 or fields[1] not in ("ascii", "binary_little_endian",
                                                    "binary_big_endian"):
                raise ReaderError(file, f"unknown PLY format {' '.join(fields[1:])!r}", number)
            fmt = fields[1]
        elif fields[0] == "element":
            if len(fields) != 3:
                raise ReaderError(file, "an element line is 'element NAME COUNT' with a whole "
                                        "number COUNT", number)
            count = whole_number(fields[2], file, number, f"the count of element {short(fields[1])}")
            elements.append([fields[1], count, number, 0, []])
        elif fields[0] == "property":
            if not elements:
                raise ReaderError(file, "a property before any element", number)
            types = fields[2:4] if len(fields) >= 5 and fields[1] == "list" else fields[1:2]
            if len(fields) < 3 or any(t not in _PLY_SIZES for t in types):
                raise ReaderError(file, f"malformed property line {line.strip()!r}", number)
            # smallest row: a scalar, or a list with zero items (just its count)
            elements[-1][3] += _PLY_SIZES[types[0]] if fmt != "ascii" else 2
            elements[-1][4].append(fields[1] == "list")
        else:
            raise ReaderError(file, f"unknown PLY header keyword {short(fields[0])}", number)
    if fmt is None:
        raise ReaderError(file, "the PLY header has no 'format' line", 1)
    return fmt, elements


def _check_ply_counts(elements: list, body: int, budget: int, file: str) -> None:
    """Refuse more faces than the budget, or more rows than ``body`` bytes can hold."""
    needed = 0
    for name, count, number, row, _ in elements:
        if name == "face" and count > budget:
            raise _over_budget(file, f"the header says {count} faces: at least", count, budget,
                               number)
        needed += count * row
        if needed > body:
            raise ReaderError(file, f"the header says element '{name}' has {count} rows, but "
                                    f"only {body} bytes of data follow the header (at least "
                                    f"{needed} needed)", number)


def _check_ply_ascii_rows(body: str, elements: list, first_line: int,
                          file: str) -> _AsciiRows | None:
    """Every element has exactly its count of rows, one a line, each holding its scalars and
    its lists (a count, then that many items); nothing follows the last row. Without this an
    over-counted element takes the next element's rows as its own.

    The common file (scalars, and at most one list, first in its row) is checked with numpy,
    and then where its numbers are is returned; any other, or a file that fails that check,
    row by row, which finds and names the first bad row (None returned)."""
    rows = _ply_ascii_layout(body, elements)
    if rows is None:
        _check_ply_ascii_rows_one_by_one(body, elements, first_line, file)
    return rows


# What str.split() splits ASCII at: tab, newline, vertical tab, form feed, carriage
# return, the four separators 0x1c-0x1f, space.
_WHITE = np.zeros(256, np.bool_)
_WHITE[[9, 10, 11, 12, 13, 28, 29, 30, 31, 32]] = True


class _AsciiRows(NamedTuple):
    """Where the numbers of an ASCII PLY body are: its bytes, where each token starts, and
    per row the number of its line (0: the line after end_header) and of tokens."""
    body: bytes
    starts: np.ndarray
    lines: np.ndarray
    sizes: np.ndarray


def _ply_ascii_layout(body: str, elements: list) -> _AsciiRows | None:
    """Where the rows' numbers are, if the rows fit the elements; None where they do not, or
    where this quick check cannot tell.

    Works on the bytes with numpy: how many numbers each line holds (what line.split() of
    body.split("\n") would give), and the first number of each row of a list element where
    it is all digits. No Python object per line: 105k small lists made Python's garbage
    collector pass over everything the process holds, again and again (the bunny's check:
    22 ms alone, 160-200 ms inside a viewer's start)."""
    if not body.isascii():
        return None                              # row by row, which names what is wrong
    data = body.encode("ascii")
    text = np.frombuffer(data, np.uint8)
    edges = np.flatnonzero(np.diff(_WHITE[text], prepend=True, append=True))
    starts, ends = edges[0::2], edges[1::2]                     # of each token
    newlines = np.flatnonzero(text == 10)
    first = np.concatenate(([0], np.searchsorted(starts, newlines)))   # each line's, if any
    filled = first < len(starts)
    filled[filled] = starts[first[filled]] < np.append(newlines, len(text))[filled]
    lines = np.flatnonzero(filled)                              # the non-empty lines
    first = first[lines]
    lengths = np.diff(np.append(first, len(starts)))            # numbers on each
    start = 0
    for _, count, _, _, lists in elements:
        rows = lengths[start:start + count]
        if len(rows) != count or any(lists[1:]):
            return None
        expected = len(lists)
        if lists and lists[0]:
            a = starts[first[start:start + count]]
            size = ends[first[start:start + count]] - a
            if np.any(size >= 10):
                return None                      # what whole_number would say, row by row
            items = np.zeros(count, np.int64)
            for k in range(9):                   # the digits, most significant first
                more = k < size
                digit = text[a[more] + k] - np.uint8(48)    # not a digit: wraps past 9
                if np.any(digit > 9):
                    return None
                items[more] = items[more] * 10 + digit
            expected = expected + items
        if not np.array_equal(rows, np.broadcast_to(expected, rows.shape)):
            return None
        start += count
    if start != len(first):
        return None
    return _AsciiRows(data, starts, lines, lengths)


def _check_ply_ascii_rows_one_by_one(body: str, elements: list, first_line: int,
                                     file: str) -> None:
    rows = ((n, line.split()) for n, line in enumerate(body.split("\n"), start=first_line))
    rows = ((n, fields) for n, fields in rows if fields)
    for name, count, header_line, _, lists in elements:
        for k in range(count):
            line, fields = next(rows, (None, None))
            if fields is None:
                raise ReaderError(file, f"the file ends after {k} rows of element '{name}'; "
                                        f"the header (line {header_line}) says {count}",
                                  first_line + body.count("\n"))
            used = 0
            for is_list in lists:
                if is_list and used < len(fields):
                    used += 1 + whole_number(fields[used], file, line,
                                             f"element '{name}' row {k}: a list count")
                else:
                    used += 1
            if used != len(fields):
                raise ReaderError(file, f"element '{name}' row {k}: its properties take {used} "
                                        f"numbers, the line holds {len(fields)} (the header, "
                                        f"line {header_line}, says {count} rows)", line)
    extra = next(rows, None)
    if extra is not None:
        raise ReaderError(file, f"more rows than the header's elements say "
                                f"({', '.join(f'{e[0]} {e[1]}' for e in elements)})", extra[0])


_OFF_KEYWORDS = ("OFF", "COFF")           # what the mesh library reads (COFF: colours)
_OFF_COLOURS = (0, 1, 3, 4)               # trailing values after a row: none, an index, RGB(A)


def _off_rows(text: str):
    """``(line number, fields)`` of every line with numbers, made as they are needed: the rows
    of a large file are never all held at once (millions of small lists also make Python's
    garbage collector pass over them again and again)."""
    for number, line in enumerate(text.split("\n"), start=1):
        fields = line.split("#", 1)[0].split()
        if fields:
            yield number, fields


def _check_off(text: str, file: str, budget: int) -> None:
    """Check the OFF keyword, the counts, and every row: V vertex rows of 3 coordinates and
    F face rows ``k i_1 .. i_k`` whose k matches its indices (each followed only by an
    optional colour), and nothing after them."""
    rows = _off_rows(text)
    number, fields = next(rows, (1, None))
    if fields is None or fields[0] not in _OFF_KEYWORDS:
        raise ReaderError(file, f"not an OFF file: it must start with 'OFF' (or 'COFF'), not "
                                f"{short(fields[0]) if fields else 'nothing'}", number)
    fields = fields[1:]
    header_rows = 1                        # the keyword's row, and the counts' if apart
    if not fields:
        header_rows = 2
        counts_line = next(rows, None)
        if counts_line is None:
            raise ReaderError(file, "the file ends before the vertex and face counts", number)
        number, fields = counts_line
    if len(fields) < 2:
        raise ReaderError(file, "the counts line must hold whole numbers 'V F [E]', got "
                                f"{short(' '.join(fields))}", number)
    vertices, faces, *_ = (whole_number(f, file, number, what)
                           for f, what in zip(fields, ("the vertex count", "the face count",
                                                       "the edge count")))
    available = sum(len(f) for k, (_, f) in enumerate(_off_rows(text)) if k >= header_rows)
    if 3 * vertices + 4 * faces > available:
        raise ReaderError(file, f"the counts say {vertices} vertices and {faces} faces (at "
                                f"least {3 * vertices + 4 * faces} numbers), but only "
                                f"{available} numbers follow", number)
    if faces > budget:
        raise _over_budget(file, f"the counts say {faces} faces: at least", faces, budget, number)
    _check_off_rows(rows, vertices, faces, file)


def _check_off_rows(rows, vertices: int, faces: int, file: str) -> None:
    for k, (line, fields) in enumerate(rows):
        if k < vertices:
            if len(fields) - 3 not in _OFF_COLOURS:
                raise ReaderError(file, f"vertex {k}: a vertex row is 3 coordinates (plus an "
                                        f"optional colour), got {len(fields)} numbers", line)
            continue
        face = k - vertices
        if face >= faces:
            raise ReaderError(file, f"more rows than the counts say ({vertices} vertices and "
                                    f"{faces} faces): this row would be face {face}", line)
        corners = whole_number(fields[0], file, line, f"face {face}: the corner count")
        if corners < 3:
            raise ReaderError(file, f"face {face}: a face needs at least 3 corners, got "
                                    f"{corners}", line)
        if len(fields) - 1 - corners not in _OFF_COLOURS:
            raise ReaderError(file, f"face {face}: the row says {corners} corners but holds "
                                    f"{len(fields) - 1} numbers after the count", line)


def _stl_kind(data: bytes, file: str, budget: int) -> str:
    """'binary' when the size matches the binary header's triangle count, else 'ascii'; the
    count (binary: the header's; ASCII: the facets) is held to ``budget``."""
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        if len(data) == 84 + 50 * count:
            if count > budget:
                raise _over_budget(file, f"the binary STL header says {count} triangles:",
                                   count, budget)
            return "binary"
    if data.lstrip()[:5].lower() == b"solid":
        decode_text(data, file)
        count = data.count(b"endfacet")
        if count > budget:
            raise _over_budget(file, f"the file has {count} facets:", count, budget)
        return "ascii"
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        raise ReaderError(file, f"not an STL file: as binary STL its header says {count} "
                                f"triangles ({84 + 50 * count} bytes) but the file has "
                                f"{len(data)} bytes; as ASCII STL it would start with 'solid'")
    raise ReaderError(file, f"not an STL file: {len(data)} bytes, too short for binary STL, "
                            f"and it does not start with 'solid'")


# ----------------------------------------------------------------------------- fast ASCII PLY

_FAST_ASCII_PLY = True        # False: every PLY through the mesh library (the tests compare)
# The mesh library's names for texture coordinates of PLY vertices, and for a face's corners.
_PLY_TEXTURE_NAMES = (("texture_u", "texture_v"), ("u", "v"), ("s", "t"))
_PLY_CORNER_NAMES = ("vertex_indices", "vertex_index")
# Line breaks for str.splitlines() (the library's rows) and not for our rows' check, or
# white space for str.split() and not for np.fromstring (the library's numbers); lone \r too.
_PLY_ODD_WHITE = (b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\x1f")


def _fast_ascii_ply(data: bytes, rows: _AsciiRows) -> dict | None:
    """The mesh library's reading of a common ASCII PLY (``vertices``, ``faces``,
    ``vertex_normals``), made with numpy alone; None for any other file, which the library
    then reads.

    Common: a header the library reads as :func:`_check_ply` does, a ``vertex`` element of
    scalars with x, y, z and no texture coordinates (the library cuts the mesh along its
    texture seams), a ``face`` element of one list of integer corners, the same number on
    every row, and numbers one row a line, apart by spaces or tabs. The numbers are then
    those of the library: parsed to float64 (:func:`_ply_numbers`), cast to the declared
    type column by column as it casts them (``float``: rounded to float32)."""
    header = _plain_ply_mesh(data)
    if header is None or not _plain_ascii_body(rows):
        return None
    properties, vertices, faces, corner_type = header
    if (rows.sizes[vertices] < 4                                         # 3 corners or more
            or np.any(rows.sizes[vertices:] != rows.sizes[vertices])):
        return None
    numbers = _ply_numbers(rows, vertices)
    if numbers is None:
        return None
    table, lists = numbers
    try:
        columns = {name: table[:, j].astype(dtype) for j, (name, dtype) in enumerate(properties)}
        corners = lists[:, 1:].astype(corner_type)
    except FloatingPointError:             # numpy set to raise: the library says it, its way
        return None
    part = {"vertices": np.column_stack([columns[c] for c in "xyz"]), "faces": corners}
    if {"nx", "ny", "nz"} <= columns.keys():
        part["vertex_normals"] = np.column_stack([columns[c] for c in ("nx", "ny", "nz")])
    return part


def _plain_ply_mesh(data: bytes) -> tuple[list, int, int, str] | None:
    """``(vertex properties [(name, numpy type)], vertex count, face count, corner type)`` of
    a header (already checked by :func:`_check_ply`) that the mesh library reads as we do and
    that holds a common mesh; None for any other.

    The library takes line 2 as the format line, fails on a blank line, ends the header at
    the first line holding the word end_header and ignores a scalar property line of more
    than 3 words; a repeated element or property name replaces the first."""
    end = data.find(b"end_header")
    newline = data.find(b"\n", end)
    lines = data[:end].decode("utf-8").split("\n")
    if (newline < 0 or data[end:newline].strip() != b"end_header" or lines[-1].strip()
            or len(lines) < 3 or lines[0].strip() != "ply"
            or lines[1].split()[:2] != ["format", "ascii"]):
        return None
    elements = []                                # (name, count, [(name, type, is a list)])
    for fields in (line.split() for line in lines[2:-1]):
        if fields[:1] in (["comment"], ["obj_info"]):
            continue
        if len(fields) == 3 and fields[0] == "element":
            elements.append((fields[1], int(fields[2]), []))
        elif len(fields) == 3 and fields[0] == "property":
            elements[-1][2].append((fields[2], _PLY_DTYPES[fields[1]], False))
        elif len(fields) == 5 and fields[:2] == ["property", "list"]:
            elements[-1][2].append((fields[4], _PLY_DTYPES[fields[3]], True))
        else:
            return None                          # a blank line, another format line, ...
    if [name for name, _, _ in elements] != ["vertex", "face"]:
        return None
    (_, vertices, properties), (_, faces, corners) = elements
    names = {name for name, _, _ in properties}
    if (vertices == 0 or len(names) < len(properties) or not {"x", "y", "z"} <= names
            or any(is_list for _, _, is_list in properties)
            or any({u, v} <= names for u, v in _PLY_TEXTURE_NAMES)):
        return None
    if (faces == 0 or len(corners) != 1 or corners[0][0] not in _PLY_CORNER_NAMES
            or not corners[0][2] or np.dtype(corners[0][1]).kind not in "iu"):
        return None
    return [(name, kind) for name, kind, _ in properties], vertices, faces, corners[0][1]


def _plain_ascii_body(rows: _AsciiRows) -> bool:
    """Do the mesh library's rows (the lines of str.splitlines(), each row's numbers by
    np.fromstring) match ours? Rows from the first line on, none blank between them; lines
    ended by \\n or \\r\\n; spaces and tabs apart."""
    body = rows.body
    return (not any(c in body for c in _PLY_ODD_WHITE)
            and body.count(b"\r") == body.count(b"\r\n")
            and np.array_equal(rows.lines, np.arange(len(rows.lines))))


def _ply_numbers(rows: _AsciiRows, vertices: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The vertex rows and the face rows as float64 tables, read by numpy's text reader
    (np.loadtxt: C, correctly rounded like the strtod behind the library's np.fromstring);
    None if it refuses a token, or reads inf or nan (the library's reading then says what is
    wrong). The bunny: ~60 ms, against 0.3-0.5 s of np.fromstring a line."""
    tokens = int(rows.sizes[:vertices].sum())
    split = rows.starts[tokens] if tokens < len(rows.starts) else len(rows.body)  # a face row's
    try:
        tables = tuple(np.loadtxt(io.StringIO(block.decode("ascii")), dtype=np.float64,
                                  comments=None, ndmin=2) if block.strip() else np.zeros((0, 0))
                       for block in (rows.body[:split], rows.body[split:]))
    except ValueError:
        return None
    return tables if all(np.all(np.isfinite(t)) for t in tables) else None


# ----------------------------------------------------------------------------- reader

@contextlib.contextmanager
def _collector_paused():
    """Python's cyclic garbage collector paused while the mesh library parses: its ASCII
    loaders build a small list per row, and the collector, passing over all of them again as
    they pile up, made reading grow faster than the file (16k to 64k OFF rows: x6 with it,
    x4.5 without). The lists hold no cycles; reference counting frees them either way."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def _library_parts(data: bytes, ext: str, file: str) -> list[dict]:
    """The per-geometry kwargs (vertices, faces, ...) that trimesh's loader for ``ext`` reads."""
    from trimesh.exchange.load import mesh_loaders       # slow import: only when needed
    # trimesh logs what it could not read, with a traceback, as a warning; with no logging
    # set up Python prints that on stderr. What went wrong reaches the user as our message.
    logging.getLogger("trimesh").addHandler(_QUIET)
    try:
        with _collector_paused():
            return _loaded_parts(mesh_loaders[ext[1:]](io.BytesIO(data)))
    except Exception as error:           # trimesh raises many types; each becomes ours
        raise ReaderError(file, f"the mesh library could not read it: "
                                f"{type(error).__name__}: {error}") from None


def _loaded_parts(loaded: dict) -> list[dict]:
    """The per-geometry kwargs in what a trimesh format loader returns (one mesh or several)."""
    if "geometry" in loaded:
        return [g for g in loaded["geometry"].values() if isinstance(g, dict)]
    return [loaded]


@tolerant_of_underflow
def read_mesh(data: bytes, file: str, ext: str, budget: int | None = None) -> Mesh:
    """The mesh in ``data``, a file of type ``ext`` (``.obj``, ``.ply``, ``.off``, ``.stl``).

    ``budget`` (default: ``generators.MAX_TRIANGLES``, what a scene may hold) bounds the
    triangles; it is checked from the header, or in the pre-check's pass, before the mesh
    library reads any data.
    """
    from core.scene.generators import MAX_TRIANGLES
    budget = MAX_TRIANGLES if budget is None else budget
    ext = ext.lower()
    if ext not in MESH_EXTENSIONS:
        raise ReaderError(file, f"not a mesh file type we read ({', '.join(MESH_EXTENSIONS)})")
    if not data.strip():
        raise ReaderError(file, "the file is empty")
    data, fast = _checked(data, file, ext, budget)
    parts = [fast] if fast is not None else _library_parts(data, ext, file)
    positions, triangles, normals, uvs = _gathered(parts, file)
    if not triangles:
        raise ReaderError(file, "the file holds no triangles")
    positions = np.concatenate(positions)
    triangles = np.concatenate(triangles)
    _check_vertices(positions, triangles, file, budget)
    vertex_normals = _unit_normals(normals)
    # Closed or not is a property of the surface, so it is decided on merged positions even
    # where the file's per-corner normals keep its vertices apart (a flat-shaded OBJ).
    uv = np.concatenate(uvs) if all(u is not None for u in uvs) else None
    merged, inverse = merge_vertices(positions)
    if vertex_normals is None and uv is None:
        # the file's vertices may repeat (STL always does): one mesh vertex per position
        positions, triangles = merged, inverse[triangles]
    elif vertex_normals is None:
        # ... but a texture seam keeps its copies apart: merge equal (position, uv) pairs
        rows, seams = merge_vertices(np.concatenate([positions, uv], axis=1))
        positions, uv, triangles = rows[:, :3], rows[:, 3:], seams[triangles]
    triangles = drop_repeated_triangles(triangles)
    surface = (triangles if vertex_normals is None and uv is None
               else drop_repeated_triangles(inverse_of(positions, merged, inverse, triangles)))
    closed = is_closed(merged, surface)
    return Mesh(positions=positions, triangles=triangles, normals=vertex_normals, uv=uv,
                closed=closed, name=file_stem(file))


def _checked(data: bytes, file: str, ext: str, budget: int):
    """The format's pre-check (refusing bad files and too many triangles before the mesh
    library reads them): ``(data to read, the mesh read without the library or None)``."""
    fast = None                   # what the mesh library would read, read without it
    if ext == ".obj":
        text = decode_text(data, file)
        _check_obj(text, file, budget)
        if "\t" in text or "\v" in text or "\f" in text:
            # OBJ separates by any white space; the mesh library splits on spaces only
            data = text.replace("\t", " ").replace("\v", " ").replace("\f", " ").encode()
    elif ext == ".ply":
        rows = _check_ply(data, file, budget)
        if rows is not None and _FAST_ASCII_PLY:
            fast = _fast_ascii_ply(data, rows)
    elif ext == ".off":
        _check_off(decode_text(data, file), file, budget)
    else:
        _stl_kind(data, file, budget)
    return data, fast


def _gathered(parts, file: str) -> tuple[list, list, list, list]:
    """Each part's positions, triangles (fanned, indexed into the parts joined), normals and
    (u, v), or None for normals or (u, v) a part lacks."""
    positions, triangles, normals, uvs = [], [], [], []
    offset = 0
    for part in parts:
        try:
            v = np.asarray(part.get("vertices", np.zeros((0, 3))), dtype=np.float64)
            f = np.asarray(part.get("faces", np.zeros((0, 3))))
            if len(f) == 0:
                continue
            if v.ndim != 2 or v.shape[1] != 3:
                raise ValueError(f"vertices have shape {v.shape}, not (V, 3)")
            if f.ndim != 2 or f.shape[1] < 3 or f.dtype.kind not in "iu":
                raise ValueError(f"faces have shape {f.shape} and type {f.dtype}, not (T, k) "
                                 f"integers with k >= 3")
            f = fan(f)
        except (TypeError, ValueError) as error:
            raise ReaderError(file, f"unexpected result from the mesh library: {error}") from None
        n = part.get("vertex_normals")
        n = np.asarray(n, dtype=np.float64) if n is not None else None
        positions.append(v)
        triangles.append(f.astype(np.int64) + offset)
        normals.append(n if n is not None and n.shape == v.shape else None)
        uvs.append(_texture_coordinates(part, len(v)))
        offset += len(v)
    return positions, triangles, normals, uvs


def _check_vertices(positions, triangles, file: str, budget: int) -> None:
    """Refuse too many triangles, vertices not finite or too far out, and indices out of range."""
    if len(triangles) > budget:                # polygons fanned into more than the header said
        raise _over_budget(file, "the faces make", len(triangles), budget)
    bad = ~np.all(np.isfinite(positions), axis=1)
    if np.any(bad):
        raise ReaderError(file, f"vertex {int(np.argmax(bad))} has a NaN or infinite coordinate")
    bad = np.any(np.abs(positions) > MAX_COORDINATE, axis=1)
    if np.any(bad):
        raise ReaderError(file, f"vertex {int(np.argmax(bad))} has a coordinate beyond "
                                f"{MAX_COORDINATE:g}")
    if triangles.min() < 0 or triangles.max() >= len(positions):
        k = int(np.argmax((triangles < 0).any(axis=1) | (triangles >= len(positions)).any(axis=1)))
        raise ReaderError(file, f"triangle {k} refers to vertex {triangles[k].tolist()}, but "
                                f"there are {len(positions)} vertices")


def _unit_normals(normals: list):
    """The file's normals joined and of unit length, or None when a part has none or one is
    unusable (they are computed from the faces instead)."""
    if not all(n is not None for n in normals):
        return None
    vertex_normals = np.concatenate(normals)
    if np.all(np.isfinite(vertex_normals)):
        # scaled first, so that a normal of length 1e200 neither overflows nor underflows
        vertex_normals, lengths = unit_rows(vertex_normals)
    if not np.all(np.isfinite(vertex_normals)) or np.any(lengths == 0.0):
        return None                                # unusable: computed from the faces instead
    return vertex_normals


def inverse_of(positions, merged, inverse, triangles):
    """``triangles`` over ``positions`` re-indexed onto ``merged`` (one vertex per position)."""
    if len(positions) == len(inverse):
        return inverse[triangles]
    _, where = merge_vertices(np.concatenate([merged, positions]))
    return where[len(merged):][triangles]


def _texture_coordinates(part: dict, count: int) -> np.ndarray | None:
    """The (u, v) per vertex that the mesh library found (OBJ ``vt``; PLY ``s t``/``u v``
    /``texture_u texture_v``), or None; finite values only."""
    uv = getattr(part.get("visual"), "uv", None)
    if uv is None:
        return None
    uv = np.asarray(uv, dtype=np.float64)
    if uv.shape != (count, 2) or not np.all(np.isfinite(uv)):
        return None
    return uv

