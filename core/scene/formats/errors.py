"""The readers' error type and the text helpers every reader shares.

Every reader of ``core.scene.formats`` turns bad input into a :class:`ReaderError` whose message
names the file, the line (where the problem has one) and the reason, in the form compilers use:
``scenes/bad.tri:7: expected 9 numbers for triangle 3, got 5``. Nothing else escapes a reader.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np

# Coordinates beyond this are refused by every reader: products of a few of them (cross
# products, volumes, the normalizing transforms) must stay finite in float64.
MAX_COORDINATE = 1e30


class ReaderError(ValueError):
    """A file that cannot be read; ``str(error)`` is ``FILE:LINE: REASON`` (or ``FILE: REASON``)."""

    def __init__(self, file: str, reason: str, line: int | None = None) -> None:
        self.file = str(file)
        self.line = line
        self.reason = reason
        where = self.file if line is None else f"{self.file}:{line}"
        super().__init__(f"{where}: {reason}")


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


def short(token: str, limit: int = 40) -> str:
    """``repr`` of a token from a file, cut to ``limit`` characters so that messages stay short."""
    return repr(token if len(token) <= limit else token[:limit] + "...")


def read_file(path: Path, shown: str) -> bytes:
    """The bytes of a regular file (never a device, a FIFO or a folder), or a ReaderError."""
    try:
        if path.is_file():
            return path.read_bytes()
        exists = path.exists()
    except (OSError, ValueError) as error:        # ValueError: a NUL in the path
        raise ReaderError(shown, f"cannot read it: {getattr(error, 'strerror', None) or error}") from None
    raise ReaderError(shown, f"cannot read it: {'not a regular file' if exists else 'no such file'}")


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
