"""The scene file and every file it names (meshes, view files, textures), shipped with a job.

A worker on another machine has the package but not the user's files. :func:`load_recorded`
loads the scene here and records every file the readers opened while doing it; the
:class:`Bundle` carries their bytes, content-addressed (a file is stored once under its
SHA-256, whatever its name). :func:`unpack` writes them on the worker into a folder named for
the bundle's digest, under the same relative names, and the worker loads the scene from
there: nothing need be at the user's path, and a second job with the same files writes
nothing.

Files are named relative to the folder that holds them all (the scene's folder, or above it
for ``../`` names). A scene that names a file by an absolute path still reads that path on
the worker.
"""

from __future__ import annotations

import hashlib
import os
import sys
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path

# What the recorder ignores: the interpreter's and the package's own code, numba's cache, and
# what libraries read about the machine.
_CODE_SUFFIXES = (".py", ".pyc", ".so", ".pth", ".nbi", ".nbc")
_PACKAGE = Path(__file__).resolve().parents[2]
_NOT_INPUT = ("/proc/", "/sys/", "/dev/", sys.prefix, sys.base_prefix,
              str(_PACKAGE / "core"), str(_PACKAGE / "app"))
_recording = threading.local()
_hook_installed = False


@dataclass(frozen=True)
class Bundle:
    scene: str                                           # the scene's relative name
    files: dict[str, str] = field(default_factory=dict)  # relative name -> sha256
    blobs: dict[str, bytes] = field(default_factory=dict, repr=False)   # sha256 -> bytes

    @property
    def digest(self) -> str:
        """One hash of the names and contents: the bundle's identity (and its folder's name)."""
        h = hashlib.sha256(self.scene.encode())
        for name in sorted(self.files):
            h.update(b"\0" + name.encode() + b"\0" + self.files[name].encode())
        return h.hexdigest()

    @property
    def nbytes(self) -> int:
        return sum(len(b) for b in self.blobs.values())


def _audit(event: str, args) -> None:
    """Python's ``open`` audit event: note a regular file opened for reading."""
    files = getattr(_recording, "files", None)
    if files is None or event != "open":
        return
    path, mode, flags = args
    if not isinstance(path, (str, bytes, os.PathLike)):
        return                                          # an open file descriptor
    reading = (not any(c in mode for c in "wax+")) if isinstance(mode, str) \
        else not flags & (os.O_WRONLY | os.O_RDWR)
    name = os.fsdecode(path)
    if reading and not name.endswith(_CODE_SUFFIXES) and not name.startswith(_NOT_INPUT):
        files.append(name)


def load_recorded(path: str | Path, load):
    """``(load(path), Bundle)``: the scene, and the files its readers opened to make it.

    The readers open files in several places (meshes, view files, textures); watching
    Python's ``open`` audit event records exactly those they read, whatever their kind,
    without each reader keeping a list.
    """
    global _hook_installed
    if not _hook_installed:
        sys.addaudithook(_audit)            # (cannot be removed: it is idle when not recording)
        _hook_installed = True
    _recording.files = []
    try:
        result = load(path)
        opened = list(_recording.files)
    finally:
        _recording.files = None
    if result is None:                      # the loader refused it (and said why)
        return None, None
    scene = Path(path).resolve()
    names = {scene} | {Path(p).resolve() for p in opened if os.path.isfile(p)}
    return result, bundle_of(scene, names)


def bundle_of(scene: Path, paths) -> Bundle:
    """The bundle of ``scene`` and the files ``paths`` (absolute), by content."""
    root = Path(os.path.commonpath([str(p.parent) for p in paths]))
    files, blobs = {}, {}
    for p in sorted(paths):
        data = p.read_bytes()
        digest = hashlib.sha256(data).hexdigest()
        files[p.relative_to(root).as_posix()] = digest
        blobs[digest] = data
    return Bundle(scene=scene.relative_to(root).as_posix(), files=files, blobs=blobs)


def unpack(bundle: Bundle, cache: Path | None = None) -> Path:
    """Write the bundle's files under ``cache/<digest>/`` (once; written to a temporary folder
    and renamed, so a half-written bundle is never used) and return the scene's path there."""
    cache = Path(cache or Path(tempfile.gettempdir()) / f"fvd-bundles-{os.getuid()}")
    home = cache / bundle.digest
    if not home.is_dir():
        cache.mkdir(parents=True, exist_ok=True)
        work = Path(tempfile.mkdtemp(prefix=".unpacking-", dir=cache))
        for name, digest in bundle.files.items():
            target = work / name
            if not target.resolve().is_relative_to(work.resolve()):
                raise ValueError(f"the bundle names a file outside its folder: {name!r}")
            data = bundle.blobs[digest]
            if hashlib.sha256(data).hexdigest() != digest:
                raise ValueError(f"the bundle's copy of {name!r} is damaged (its hash differs)")
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        try:
            os.rename(work, home)
        except OSError:                     # another worker on this machine was first
            import shutil
            shutil.rmtree(work, ignore_errors=True)
    return home / bundle.scene
