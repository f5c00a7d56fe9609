"""PLY: the header and row checks made before any reading, and the common ASCII PLY read with
numpy alone, to trimesh's numbers bit for bit.

Checks (:func:`check_ply`): the header (``ply``, a known ``format`` line, ``element NAME COUNT``
lines with whole counts, ``property TYPE NAME`` and ``property list TYPE TYPE NAME`` lines of
known types, nothing else but comments); the counts against the data: the smallest possible row
of each element is known from its properties (binary: the bytes of the scalars and of each
list's count; ASCII: two characters per value), so a header that promises more rows than the
bytes that follow can hold is refused before any reading; the face count against the budget;
and, for ASCII, that every element has exactly its count of rows, each holding its scalars and
its lists (without this trimesh silently loads an over-counted vertex element's excess from the
face rows). Messages name the line: "not a PLY file: it must start with 'ply' and have an
'end_header' line", "unknown PLY format ...", "an element line is 'element NAME COUNT' ...", "a
property before any element", "malformed property line ...", "unknown PLY header keyword ...",
"the PLY header has no 'format' line", "the header says element 'vertex' has N rows, but only B
bytes of data follow the header (at least M needed)", "the file ends after k rows of element
...", "element 'face' row k: its properties take n numbers, the line holds m ...", "more rows
than the header's elements say ...", and the budget's.

ASCII PLY fast path: trimesh reads an ASCII PLY a line at a time (``np.fromstring`` per line,
then a stack of the rows: 0.33-0.39 s for the Stanford bunny's 105k lines) and importing it
costs another 0.13-0.25 s, so the bunny took 0.5-0.7 s. The common file (a ``vertex`` element of
scalars with x, y, z and no texture coordinates, a ``face`` element of one list of integer
corners, as many on every row) is read by :func:`fast_ascii_ply` with numpy alone: the row
check has already found where the vertex rows end, and each block is parsed in one call of
numpy's C text reader (``np.loadtxt``, correctly rounded as trimesh's parser rounds), then
cast to the declared types as trimesh casts them. The result is trimesh's, bit for bit
(``tests/core/scene/test_ply_fast.py`` compares, switching :data:`FAST_ASCII_PLY` off); any
other file goes to trimesh. The bunny's ``read_mesh`` now takes 0.2 s (its check 30-40 ms, the parse
~60 ms, merging, repeats and closedness the rest), trimesh never imported.
"""

from __future__ import annotations

import io
from typing import NamedTuple

import numpy as np

from core.scene.formats.errors import ReaderError, decode_text, over_budget, short, whole_number

# The PLY property types we read, as numpy types (the mesh library's names for them).
_PLY_DTYPES = {"char": "i1", "uchar": "u1", "int8": "i1", "uint8": "u1", "short": "i2",
               "ushort": "u2", "int16": "i2", "uint16": "u2", "int": "i4", "uint": "u4",
               "int32": "i4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
               "float64": "f8"}
_PLY_SIZES = {name: np.dtype(code).itemsize for name, code in _PLY_DTYPES.items()}


def check_ply(data: bytes, file: str, budget: int) -> AsciiRows | None:
    """Check a PLY header and that the data after it can hold the element counts it declares.

    The smallest possible row of each element is known from its properties (binary: the bytes
    of the scalars and of each list's count; ASCII: two characters per value), so a header that
    promises more rows than the bytes that follow can hold is refused before any reading.
    Returns where the numbers of an ASCII file are when its rows passed the quick check (for
    :func:`fast_ascii_ply`), else None.
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
            raise over_budget(file, f"the header says {count} faces: at least", count, budget,
                              number)
        needed += count * row
        if needed > body:
            raise ReaderError(file, f"the header says element '{name}' has {count} rows, but "
                                    f"only {body} bytes of data follow the header (at least "
                                    f"{needed} needed)", number)


def _check_ply_ascii_rows(body: str, elements: list, first_line: int,
                          file: str) -> AsciiRows | None:
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


class AsciiRows(NamedTuple):
    """Where the numbers of an ASCII PLY body are: its bytes, where each token starts, and
    per row the number of its line (0: the line after end_header) and of tokens."""
    body: bytes
    starts: np.ndarray
    lines: np.ndarray
    sizes: np.ndarray


def _ply_ascii_layout(body: str, elements: list) -> AsciiRows | None:
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
    return AsciiRows(data, starts, lines, lengths)


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


# ----------------------------------------------------------------------------- fast ASCII PLY

FAST_ASCII_PLY = True        # False: every PLY through the mesh library (the tests compare)
# The mesh library's names for texture coordinates of PLY vertices, and for a face's corners.
_PLY_TEXTURE_NAMES = (("texture_u", "texture_v"), ("u", "v"), ("s", "t"))
_PLY_CORNER_NAMES = ("vertex_indices", "vertex_index")
# Line breaks for str.splitlines() (the library's rows) and not for our rows' check, or
# white space for str.split() and not for np.fromstring (the library's numbers); lone \r too.
_PLY_ODD_WHITE = (b"\x0b", b"\x0c", b"\x1c", b"\x1d", b"\x1e", b"\x1f")


def fast_ascii_ply(data: bytes, rows: AsciiRows) -> dict | None:
    """The mesh library's reading of a common ASCII PLY (``vertices``, ``faces``,
    ``vertex_normals``), made with numpy alone; None for any other file, which the library
    then reads.

    Common: a header the library reads as :func:`check_ply` does, a ``vertex`` element of
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
    a header (already checked by :func:`check_ply`) that the mesh library reads as we do and
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


def _plain_ascii_body(rows: AsciiRows) -> bool:
    """Do the mesh library's rows (the lines of str.splitlines(), each row's numbers by
    np.fromstring) match ours? Rows from the first line on, none blank between them; lines
    ended by \\n or \\r\\n; spaces and tabs apart."""
    body = rows.body
    return (not any(c in body for c in _PLY_ODD_WHITE)
            and body.count(b"\r") == body.count(b"\r\n")
            and np.array_equal(rows.lines, np.arange(len(rows.lines))))


def _ply_numbers(rows: AsciiRows, vertices: int) -> tuple[np.ndarray, np.ndarray] | None:
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


def checked_ply(data: bytes, file: str, budget: int) -> tuple[bytes, dict | None]:
    """The PLY pre-check of :func:`~core.scene.formats.mesh.read.read_mesh`: ``(data, the mesh
    library's reading made without it, or None)``; :data:`FAST_ASCII_PLY` is read at each
    call, so that a test may switch the fast path off."""
    rows = check_ply(data, file, budget)
    fast = None
    if rows is not None and FAST_ASCII_PLY:
        fast = fast_ascii_ply(data, rows)
    return data, fast
