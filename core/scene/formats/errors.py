"""The readers' error type and the text helpers every reader shares.

Every reader of ``core.scene.formats`` turns bad input into a :class:`ReaderError` whose message
names the file, the line (where the problem has one) and the reason, in the form compilers use:
``scenes/bad.tri:7: expected 9 numbers for triangle 3, got 5``. Nothing else escapes a reader.
"""

from __future__ import annotations

import functools
import os
import re
from pathlib import Path

import numpy as np

from core.camera.view import MAX_WORLD

# Coordinates beyond this are refused by every reader: products of a few of them (cross
# products, volumes, the normalizing transforms) must stay finite in float64.
MAX_COORDINATE = MAX_WORLD          # the views' validity rules assume this bound


# A message is one line of at most this many characters (a 1 MB value once made a 2 MB message).
MAX_MESSAGE = 400
MAX_TEXTURE_SIDE = 16384          # texels on a side; larger images are refused, not read


def printable(text: str, limit: int = MAX_MESSAGE) -> str:
    """``text`` safe to print on a terminal, on one line: control characters (newlines, escape
    sequences), bidirectional overrides and other invisible format characters become escapes
    (``\\n``, ``\\x1b``, ``\\u202e``), and the result is cut to ``limit`` characters."""
    text = str(text)
    if not text.isprintable():
        text = "".join(c if c.isprintable() else _escape(c) for c in text)
    if len(text) > limit:
        cut = len(text) - limit
        text = f"{text[:limit]}... ({cut} more characters)"
    return text


def _escape(c: str) -> str:
    code = ord(c)
    if c in "\n\r\t":
        return {"\n": "\\n", "\r": "\\r", "\t": "\\t"}[c]
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


class ReaderError(ValueError):
    """A file that cannot be read; ``str(error)`` is ``FILE:LINE: REASON`` (or ``FILE: REASON``).

    The file name and the reason are made :func:`printable`: both may hold text from the input.
    """

    def __init__(self, file: str, reason: str, line: int | None = None) -> None:
        self.file = printable(file, 200)
        self.line = line
        self.reason = printable(reason)
        where = self.file if line is None else f"{self.file}:{line}"
        super().__init__(f"{where}: {self.reason}")


# A count or index is at most this many digits (10^18 > anything 64-bit memory can hold). Python's
# int() refuses strings over 4300 digits with a ValueError, and a long one is slow to convert:
# the digits are counted before any conversion.
MAX_WHOLE_DIGITS = 18
_WHOLE = re.compile(r"[+-]?[0-9]+")       # ASCII digits only (str.isdigit() takes '²' and '١')


def whole_number(token: str, file: str, line: int | None, what: str,
                 signed: bool = False) -> int:
    """``token`` as an int: ASCII digits with an optional ``+`` (or ``-`` when ``signed``), at
    most MAX_WHOLE_DIGITS significant digits; otherwise a ReaderError naming ``what``."""
    if not _WHOLE.fullmatch(token) or (token[0] == "-" and not signed):
        kind = "a whole number" if signed else "a whole number >= 0"
        raise ReaderError(file, f"{what} must be {kind}, got {short(token)}", line)
    digits = token.lstrip("+-").lstrip("0")
    if len(digits) > MAX_WHOLE_DIGITS:
        raise ReaderError(file, f"{what} has {len(digits)} digits: more than any file can hold "
                                f"(at most {MAX_WHOLE_DIGITS})", line)
    return int(token)


def decode_text(data: bytes, file: str) -> str:
    """``data`` as UTF-8 text (a leading BOM dropped), or a ReaderError at the first bad byte.

    A NUL byte is refused too: no text format we read contains one, and binary junk usually does.
    """
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        line = data.count(b"\n", 0, error.start) + 1
        raise ReaderError(file, f"not a text file: byte 0x{data[error.start]:02x} at offset "
                                f"{error.start} is not UTF-8", line) from None
    nul = text.find("\0")
    if nul >= 0:
        raise ReaderError(file, f"not a text file: NUL byte at offset {nul}",
                          text.count("\n", 0, nul) + 1)
    return text


def over_budget(file: str, what: str, count: int, budget: int,
                line: int | None = None) -> ReaderError:
    """``{what} {count} triangles; the limit is {budget} (the triangle budget of a scene)``:
    what every mesh format says when a file holds more triangles than a scene may."""
    return ReaderError(file, f"{what} {count} triangles; the limit is {budget} (the triangle "
                             f"budget of a scene)", line)


def short(token: str, limit: int = 40) -> str:
    """``repr`` of a token from a file, cut to ``limit`` characters so that messages stay short."""
    return repr(token if len(token) <= limit else token[:limit] + "...")


# The most bytes read from one input, by kind. A file or a stream is refused beyond its limit
# before it is read (a file by its size, a stream by reading one byte more than the limit), so
# that `/dev/zero`, `yes |` or a sparse 6 GB file end in a message, not in MemoryError. The
# limits sit well above the largest input each kind can usefully hold: a mesh or .tri is held
# to the 4M-triangle budget anyway (a binary STL of 4M triangles is 200 MB).
MiB = 1 << 20
MAX_INPUT_BYTES = {"scene": 16 * MiB, "views": 16 * MiB, "tri": 256 * MiB, "mesh": 512 * MiB,
                   "texture": 256 * MiB, "motion": 64 * MiB}


def _too_big(shown: str, size: int | str, kind: str) -> ReaderError:
    limit = MAX_INPUT_BYTES[kind]
    return ReaderError(shown, f"the input is {size} bytes; a {kind} input may have at most "
                              f"{limit} bytes ({limit // MiB} MiB)")


def read_file(path: Path, shown: str, kind: str = "views") -> bytes:
    """The bytes of a regular file (never a device, a FIFO or a folder) of at most
    ``MAX_INPUT_BYTES[kind]`` bytes, or a ReaderError."""
    limit = MAX_INPUT_BYTES[kind]
    try:
        os.stat(path)                 # the reason it cannot be reached (a symlink loop …)
    except FileNotFoundError:
        pass                          # said below, as "no such file"
    except (OSError, ValueError) as error:
        raise ReaderError(shown, f"cannot read it: {getattr(error, 'strerror', None) or error}") from None
    try:
        if path.is_file():
            size = path.stat().st_size
            if size > limit:
                raise _too_big(shown, size, kind)
            with open(path, "rb") as stream:
                # read(n) allocates n bytes up front: ask for the size found, then for the
                # rest of the limit only if the file has grown since stat()
                data = stream.read(size + 1)
                if len(data) > size:
                    data += stream.read(limit + 1 - len(data))
            if len(data) > limit:
                raise _too_big(shown, f"more than {limit}", kind)
            return data
        exists = path.exists()
    except (OSError, ValueError) as error:        # ValueError: a NUL in the path
        if isinstance(error, ReaderError):
            raise
        raise ReaderError(shown, f"cannot read it: {getattr(error, 'strerror', None) or error}") from None
    raise ReaderError(shown, f"cannot read it: {'not a regular file' if exists else 'no such file'}")


def read_stream(stream, shown: str, kind: str = "views") -> bytes:
    """At most ``MAX_INPUT_BYTES[kind]`` bytes of a binary stream (standard input), or a
    ReaderError: the stream is closed, unreadable, or longer than the limit (one byte more
    than the limit is read to know, never the whole of an endless stream)."""
    limit = MAX_INPUT_BYTES[kind]
    if stream is None or getattr(stream, "closed", False):
        raise ReaderError(shown, "cannot read it: standard input is closed")
    try:
        data = stream.read(limit + 1)
    except (OSError, ValueError) as error:      # EBADF; ValueError: closed underneath us
        raise ReaderError(shown, f"cannot read it: {getattr(error, 'strerror', None) or error}") from None
    if isinstance(data, str):                   # a text stream (a test's StringIO)
        data = data.encode("utf-8", "surrogateescape")
    if len(data) > limit:
        raise _too_big(shown, f"more than {limit}", kind)
    return data


def file_stem(file: str) -> str:
    """``scenes/torus.toml`` -> ``torus``: the default name of what a file holds."""
    name = str(file).replace("\\", "/").rsplit("/", 1)[-1]
    return name.rsplit(".", 1)[0] or name


def tolerant_of_underflow(read):
    """Run a reader with numpy's underflow ignored: a tiny number in a file may underflow to
    zero on the way, which is harmless, and must not become a FloatingPointError where numpy
    is set to raise (the tests set ``np.seterr(all="raise")``). Overflow cannot happen: every
    reader bounds its numbers by MAX_COORDINATE first."""
    @functools.wraps(read)
    def guarded(*args, **kwargs):
        with np.errstate(under="ignore"):
            return read(*args, **kwargs)
    return guarded


def path_text(path: tuple) -> str:
    """``("geometry", 2, "material", "kd")`` -> ``"geometry[2].material.kd"``."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text
