"""Wavefront OBJ: the line-precise check made before the mesh library reads the file.

trimesh reads some malformed OBJ silently wrong (a face index 0 becomes vertex 1; one vertex
line with two numbers makes it drop or shift the coordinates of the others; a negative index
before a later record resolves against the final lists), so :func:`check_obj` passes over
every line first: ``v`` (3 numbers, plus an optional w or RGB), ``vt`` (1 to 3) and ``vn``
(exactly 3) records of finite numbers, and faces of at least 3 corners ``v``, ``v/vt``,
``v//vn`` or ``v/vt/vn`` whose indices exist when the face is read. The triangles the faces
fan into are held to the budget as they come.

Its messages name the line: "a vertex needs 3 coordinates, got 2", "vertex coordinate 'x' is
not a number", "... is NaN or infinite", "a face needs at least 3 vertices, got 2", "face
vertex '1/2/3/4' is not v, v/vt, v//vn or v/vt/vn", "face index 0 is out of range: 3 vertices
are defined before this line (indices run 1..3 or -1..-3)", the same for a ``vt`` or ``vn``
index, "a record defined after the negative (relative) index on line N ...", and the budget's.
"""

from __future__ import annotations

import re

import numpy as np

from core.scene.formats.errors import ReaderError, decode_text, over_budget, short, whole_number

_OBJ_INDEX = re.compile(r"[+-]?\d+")

# The records an OBJ face may refer to, with the numbers each takes: a vertex 3 (plus an
# optional w, or RGB, or both), a texture coordinate 1 to 3 (u [v [w]]), a normal exactly 3.
_OBJ_RECORDS = {"v": ("vertex", (3, 4, 6, 7)), "vt": ("texture coordinate", (1, 2, 3)),
                "vn": ("normal", (3,))}
_OBJ_SLOTS = ("v", "vt", "vn")           # the parts of a face corner v/vt/vn


def check_obj(text: str, file: str, budget: int) -> None:
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
                raise over_budget(file, "the faces up to here make", triangles, budget, number)
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


def checked_obj(data: bytes, file: str, budget: int) -> tuple[bytes, None]:
    """The OBJ pre-check of :func:`~core.scene.formats.mesh.read.read_mesh`: ``(the bytes for
    the mesh library, None)`` (OBJ has no reading of its own here)."""
    text = decode_text(data, file)
    check_obj(text, file, budget)
    if "\t" in text or "\v" in text or "\f" in text:
        # OBJ separates by any white space; the mesh library splits on spaces only
        data = text.replace("\t", " ").replace("\v", " ").replace("\f", " ").encode()
    return data, None
