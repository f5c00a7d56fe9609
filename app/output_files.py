"""One rule for every file a command writes (``render``'s PNG, ``animate``'s MP4 or GIF).

- The name says the format (``.png``, ``.mp4``, ``.gif``), and its folder must already exist:
  no folder is ever created for an output.
- The output is never the input (also through links or another name).
- An existing file is replaced only when it already is a file of that format (a PNG, an MP4,
  a GIF: what the command writes); anything else is kept unless ``--force``.
- The new file is written to a temporary name beside it and renamed over it when complete:
  a failure (a full disk, an interrupted encoder) leaves whatever was there untouched and
  nothing behind.
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _is_gif(head: bytes) -> bool:
    return head[:6] in (b"GIF87a", b"GIF89a")


def _is_mp4(head: bytes) -> bool:
    return head[4:8] == b"ftyp"


FORMATS = {".png": ("a PNG", lambda head: head[:8] == PNG_SIGNATURE),
           ".gif": ("a GIF", _is_gif),
           ".mp4": ("an MP4", _is_mp4)}


def out_problem(out: Path, source: str, force: bool, suffixes=(".png",)) -> str | None:
    """Why ``out`` must not be written, or None (the rule in the module's docstring)."""
    suffix = out.suffix.lower()
    if suffix not in suffixes:
        kinds = " or ".join(s[1:].upper() for s in suffixes)
        return (f"only {kinds} is written: the name must end in {' or '.join(suffixes)} "
                f"(got {out.suffix or 'no extension'!r})")
    parent = out.parent
    if not parent.is_dir():
        return f"the folder {str(parent)!r} does not exist (it is not created)"
    if source != "-" and same_file(out, Path(source)):
        return f"it is the input {source!r}: writing would destroy it"
    if os.path.lexists(out):
        if out.is_dir():
            return "it is a folder"
        if not out.is_file():
            return "it exists and is not a regular file"
        kind, looks_like = FORMATS[suffix]
        if not force and not looks_like(_head(out)):
            return f"it exists and is not {kind}: it is kept (--force replaces it)"
    return None


def same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _head(path: Path) -> bytes:
    try:
        with open(path, "rb") as f:
            return f.read(12)
    except OSError:
        return b""


def write_beside(out: Path, write) -> None:
    """``write(temp_path)`` fills a temporary file beside ``out`` (same folder, same suffix,
    so that encoders see the format), which is then renamed over ``out``; on any failure the
    temporary file is removed and ``out`` is left as it was."""
    with beside(out) as temp:
        write(temp)


@contextmanager
def beside(out: Path):
    """:func:`write_beside` as a ``with`` block, for a file written bit by bit (a movie
    encoded as its frames come): the block fills the temporary path it is given."""
    fd, temp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=".tmp" + out.suffix, dir=out.parent)
    os.close(fd)
    try:
        yield Path(temp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temp, 0o666 & ~umask)         # mkstemp made it private; an output is not
        os.replace(temp, out)
    except BaseException:
        if os.path.lexists(temp):
            os.unlink(temp)
        raise
