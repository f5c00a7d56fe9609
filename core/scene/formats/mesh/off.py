"""OFF (Object File Format): the line-precise check made before the mesh library reads it.

:func:`check_off` checks the keyword (``OFF`` or ``COFF``), the counts line ``V F [E]``, that
the numbers after it can hold the rows the counts promise (before any row is read), the face
count against the budget, and every row: V vertex rows of 3 coordinates and F face rows
``k i_1 .. i_k`` whose k matches its indices (each row followed only by an optional colour),
and nothing after them.

Its messages name the line: "not an OFF file: it must start with 'OFF' (or 'COFF'), not ...",
"the file ends before the vertex and face counts", "the counts line must hold whole numbers
'V F [E]', got ...", "the counts say V vertices and F faces (at least N numbers), but only M
numbers follow", "vertex k: a vertex row is 3 coordinates (plus an optional colour), got n
numbers", "face k: a face needs at least 3 corners, got n", "face k: the row says n corners but
holds m numbers after the count", "more rows than the counts say ...", and the budget's.
"""

from __future__ import annotations

from core.scene.formats.errors import ReaderError, decode_text, over_budget, short, whole_number

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


def check_off(text: str, file: str, budget: int) -> None:
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
        raise over_budget(file, f"the counts say {faces} faces: at least", faces, budget, number)
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


def checked_off(data: bytes, file: str, budget: int) -> tuple[bytes, None]:
    """The OFF pre-check of :func:`~core.scene.formats.mesh.read.read_mesh`: ``(data, None)``."""
    check_off(decode_text(data, file), file, budget)
    return data, None
