"""The stamp that says the kernel cache is warm: written by ``python -m app warmup`` when every
step has succeeded, read by :func:`is_warm`.

The stamp is a small JSON file beside the cached kernels (``core/__pycache__/warm.json``, or
``fvd-warm.json`` in ``NUMBA_CACHE_DIR`` when that is set; git ignores ``__pycache__/``). It
holds the kernel sources' digest (:func:`core.jit.kernel_sources_digest`: the cached kernels
go stale when any kernel file changes), the numba and Python versions (numba's cache is
keyed by both), when it was written, and how many kernel index files (``*.nbi``) the cache
held. :func:`is_warm` compares the first three with the running code and counts the index
files again: a cache from another version of the code, of numba or of Python is not warm,
nor is one whose files were deleted since (``find core app -name '*.nbi' -delete``), nor is
a missing or unreadable stamp.

The stamp is written atomically (a temporary file in the same folder, then ``os.replace``): a
warm-up killed at any moment leaves either the old stamp or the new one, never half of one.
"""

from __future__ import annotations

import contextlib
import json
import os
import platform
import tempfile
import time
from pathlib import Path

NAME = "warm.json"


def stamp_path() -> Path:
    """Where the stamp lives: beside the kernels' cache."""
    cache_dir = os.environ.get("NUMBA_CACHE_DIR")
    if cache_dir:
        return Path(cache_dir) / "fvd-warm.json"
    from core.paths import ROOT
    return ROOT / "core" / "__pycache__" / NAME


def current() -> dict:
    """What a stamp written now would say about the code (everything but the time)."""
    import numba

    from core import jit
    return {"digest": jit.kernel_sources_digest(tuple(jit.KERNEL_ROOTS)),
            "numba": numba.__version__,
            "python": platform.python_version(),
            "implementation": platform.python_implementation()}


def cache_indexes() -> int:
    """How many kernel index files (``*.nbi``) the cache holds now (a few ms: the walk skips
    everything but ``__pycache__`` folders' names)."""
    cache_dir = os.environ.get("NUMBA_CACHE_DIR")
    if cache_dir:
        return sum(name.endswith(".nbi") for _, _, names in os.walk(cache_dir) for name in names)
    from core import jit
    count = 0
    for root in jit.KERNEL_ROOTS:
        for folder, subfolders, names in os.walk(root):
            subfolders[:] = [d for d in subfolders if not d.startswith(".")]
            if os.path.basename(folder) == "__pycache__":
                count += sum(name.endswith(".nbi") for name in names)
    return count


def read(path: Path | None = None) -> dict | None:
    """The stamp's contents, or None when it is missing or is not a JSON object."""
    try:
        stamp = json.loads((path or stamp_path()).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return stamp if isinstance(stamp, dict) else None


def is_warm(path: Path | None = None) -> bool:
    """Whether the last complete warm-up was of this code, numba and Python."""
    stamp = read(path)
    if stamp is None or any(stamp.get(key) != value for key, value in current().items()):
        return False
    indexes = stamp.get("indexes")
    return isinstance(indexes, int) and cache_indexes() >= indexes


def write(seconds: float, steps: int, path: Path | None = None) -> Path:
    """Write the stamp for the running code, atomically; returns its path."""
    path = path or stamp_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    stamp = {**current(), "written": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
             "seconds": round(seconds, 1), "steps": steps, "indexes": cache_indexes()}
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            json.dump(stamp, out, indent=1)
            out.flush()
            os.fsync(out.fileno())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise
    return path


def remove(path: Path | None = None) -> None:
    """Delete the stamp (a warm-up whose steps did not all succeed)."""
    with contextlib.suppress(OSError):
        (path or stamp_path()).unlink()
