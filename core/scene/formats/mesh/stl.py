"""STL, binary or ASCII: which of the two a file is, and its triangle count held to the budget
before the mesh library reads it.

A file is binary when its size is exactly what the header's triangle count makes (84 bytes and
50 a triangle); else ASCII when it starts with ``solid`` (and is UTF-8 text, counted by its
``endfacet`` lines). Messages: "not an STL file: as binary STL its header says N triangles (B
bytes) but the file has M bytes; as ASCII STL it would start with 'solid'", "not an STL file: N
bytes, too short for binary STL, and it does not start with 'solid'", and the budget's.
"""

from __future__ import annotations

import struct

from core.scene.formats.errors import ReaderError, decode_text, over_budget


def stl_kind(data: bytes, file: str, budget: int) -> str:
    """'binary' when the size matches the binary header's triangle count, else 'ascii'; the
    count (binary: the header's; ASCII: the facets) is held to ``budget``."""
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        if len(data) == 84 + 50 * count:
            if count > budget:
                raise over_budget(file, f"the binary STL header says {count} triangles:",
                                  count, budget)
            return "binary"
    if data.lstrip()[:5].lower() == b"solid":
        decode_text(data, file)
        count = data.count(b"endfacet")
        if count > budget:
            raise over_budget(file, f"the file has {count} facets:", count, budget)
        return "ascii"
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        raise ReaderError(file, f"not an STL file: as binary STL its header says {count} "
                                f"triangles ({84 + 50 * count} bytes) but the file has "
                                f"{len(data)} bytes; as ASCII STL it would start with 'solid'")
    raise ReaderError(file, f"not an STL file: {len(data)} bytes, too short for binary STL, "
                            f"and it does not start with 'solid'")


def checked_stl(data: bytes, file: str, budget: int) -> tuple[bytes, None]:
    """The STL pre-check of :func:`~core.scene.formats.mesh.read.read_mesh`: ``(data, None)``."""
    stl_kind(data, file, budget)
    return data, None
