"""numba for every kernel of the core: ``from core.jit import njit, prange``.

One place that knows how the kernels are compiled and loaded. It changes two things about
numba's on-disk cache: loading a kernel no longer imports numba's whole library first, and a
cached kernel goes stale when any kernel file changes, not only its own. It also sets each
kernel's cache up at its first call rather than at import, and stops numba timing each call
into LLVM.

Before the first kernel of a process is loaded from the cache, numba refreshes its target
context: it imports every implementation module it has (arrays, linalg, random, typed
containers, unicode, …) and installs their registries, which a compile needs and loading
compiled code does not. Measured on a warm start (``scenes/sphere.toml``, CLI render): the
first frame took 0.27 s, of which the refresh was about 0.1 s; without it, 0.18 s. Here a
cache load initialises only numba's runtime (NRT: the allocator the kernels call) and reads
the cached code; a kernel that has to be compiled still gets the full refresh (numba's
compiler does it itself), so what a compile sees is unchanged.

A cached kernel is also tied to the source of every kernel module (``KERNEL_ROOTS``), not
only to its own file. numba checks a cached kernel against its own file alone, but a kernel
carries inside it the code of the kernels it inlines from other files: after
``core/raytrace/intersect.py`` changed, the cached ray-tracing kernels of ``whitted.py`` ran
the old triangle test until their cache was deleted. Now a change to any file that defines
kernels makes every kernel compile again when next used (``python -m app warmup`` does them
all at once).

Setting up a kernel's cache (``@njit(cache=True)``) costs ~0.4 ms even when the kernel is
never called: numba finds its cache folder, writes and deletes a file there to see that it
can, and reads its source's stamp. The first frame's modules define ~130 kernels and use
nine: ~50 ms at every start. :func:`njit` sets a kernel's cache up at its first call instead.

numba also wraps every call into LLVM in a pair of "numba:llvm_lock" events, which feed
only its compile-time statistics (``metadata["timers"]``); loading the first frame's nine
cached kernels makes about 2,500 such calls, ~40 ms of events. Those two callbacks are
removed (llvmlite's own lock stays).

If numba's cache classes do not have the shape this expects (another numba version),
nothing is changed: the kernels load as numba loads them.

Two processes may compile the same kernel at once (``python -m app warmup`` compiles on every
core; the window compiles what it needs while a warm-up runs). numba writes each file of the
cache atomically (a temporary file, then ``os.replace``) but saves a new signature as
read-index, pick-a-free-data-number, write-index, write-data without a lock: two processes
saving two signatures of one kernel at once both pick ``….1.nbc``, one signature drops out
of the index and the other's entry can name the data of the first (the wrong machine code
for its argument types). :func:`serialised_cache_saves` holds an exclusive lock on
``<index>.lock`` (``fcntl.flock``, released by the OS if the process dies) over the whole
save, and writes the data before the index, so that no index names a file not yet written.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import itertools
import os
from pathlib import Path

import numba
from llvmlite.binding import ffi as llvm_ffi
from numba import config, prange  # noqa: F401  (re-exported: the kernels' imports)
from numba.core import caching
from numba.core.runtime import nrt

__all__ = ["config", "njit", "prange", "quick_cache_loads", "serialised_cache_saves",
           "stamp_with_kernel_sources", "untimed_llvm_calls"]

# The packages whose kernels may inline one another: a change to any file of theirs that
# defines kernels (imports this module) makes every cached kernel of theirs stale.
JIT_FILE = Path(__file__).resolve()
KERNEL_ROOTS = [JIT_FILE.parent, JIT_FILE.parent.parent / "app"]
# A file that defines no kernel but shapes compiled code says so with these words (the
# lighting models' registrations: the kernels' dispatch is generated from them).
GENERATES_KERNELS = b"kernels are generated from this file"


def njit(*args, **options):
    """``numba.njit``; with ``cache=True`` (and no signature) the kernel's on-disk cache is
    set up when the kernel is first compiled or loaded, not when its module is imported (see
    the module)."""
    if args or not options.get("cache") or not hasattr(numba.core.dispatcher.Dispatcher,
                                                       "enable_caching"):
        return numba.njit(*args, **options)
    options["cache"] = False

    def decorate(function):
        dispatcher = numba.njit(**options)(function)
        dispatcher._cache = _CacheOnFirstUse(function)
        return dispatcher
    return decorate


class _CacheOnFirstUse:
    """numba's ``FunctionCache`` for a kernel, made the first time the dispatcher asks it
    anything (what ``enable_caching`` would have made at import)."""

    def __init__(self, function):
        self._function = function
        self._cache = None

    def __getattr__(self, name):
        if self._cache is None:
            self._cache = caching.FunctionCache(self._function)
        return getattr(self._cache, name)


def quick_cache_loads() -> bool:
    """Load cached kernels without the full context refresh (see the module). Returns whether
    the change is in place."""
    cache = caching.Cache
    if getattr(cache.load_overload, "_quick", False):
        return True
    needed = ("_load_overload", "_guard_against_spurious_io_errors")
    if not all(hasattr(cache, name) for name in needed) or not hasattr(nrt, "rtsys"):
        return False

    def load_overload(self, sig, target_context):
        nrt.rtsys.initialize(target_context)         # the allocator the cached code calls
        with self._guard_against_spurious_io_errors():
            return self._load_overload(sig, target_context)
        return None                                  # the guard swallowed an I/O error

    load_overload._quick = True
    load_overload.__doc__ = cache.load_overload.__doc__
    cache.load_overload = load_overload
    return True


@functools.lru_cache(maxsize=None)
def kernel_sources_digest(roots: tuple[Path, ...]) -> str:
    """SHA-256 of every file under ``roots`` that defines kernels, names and contents, in
    order (about 40 files: a few milliseconds, once per process)."""
    digest = hashlib.sha256()
    for root in roots:
        for path in _python_files(root):
            text = path.read_bytes()
            if b"core.jit import" in text or GENERATES_KERNELS in text or path == JIT_FILE:
                digest.update(str(path.relative_to(root.parent)).encode() + b"\0" + text)
    return digest.hexdigest()


def _python_files(root: Path) -> list[Path]:
    """The .py files under ``root``, sorted; ``__pycache__`` (thousands of cached kernels) is
    not walked."""
    found = []
    for folder, subfolders, files in os.walk(root):
        subfolders[:] = [d for d in subfolders if d != "__pycache__" and not d.startswith(".")]
        found += [Path(folder) / name for name in files if name.endswith(".py")]
    return sorted(found)


@functools.lru_cache(maxsize=None)   # asked once per kernel (~130 at start-up): resolve is slow
def _inside(path: str, roots) -> bool:
    try:
        resolved = Path(path).resolve()
    except OSError:
        return False
    return any(root == resolved or root in resolved.parents for root in roots)


def stamp_with_kernel_sources() -> bool:
    """Tie each cached kernel under ``KERNEL_ROOTS`` to the kernel sources' digest as well as
    to its own file (see the module). Returns whether the change is in place."""
    mixin = getattr(caching, "_SourceFileBackedLocatorMixin", None)
    if mixin is None or not hasattr(mixin, "get_source_stamp"):
        return False
    own_stamp = mixin.get_source_stamp
    if getattr(own_stamp, "_with_kernel_sources", False):
        return True

    def get_source_stamp(self):
        stamp = own_stamp(self)
        roots = tuple(KERNEL_ROOTS)
        if _inside(getattr(self, "_py_file", ""), roots):
            return stamp, kernel_sources_digest(roots)
        return stamp

    get_source_stamp._with_kernel_sources = True
    mixin.get_source_stamp = get_source_stamp
    return True


def untimed_llvm_calls() -> bool:
    """Drop numba's timing of each call into LLVM (see the module). Returns whether it did."""
    lock = getattr(getattr(llvm_ffi, "lib", None), "_lock", None)
    callbacks = getattr(lock, "_cblist", None)
    if not isinstance(callbacks, list) or not hasattr(llvm_ffi, "unregister_lock_callback"):
        return False
    for acquire, release in list(callbacks):
        if getattr(acquire, "__module__", "") == "numba.core.base":   # its llvm_lock events
            llvm_ffi.unregister_lock_callback(acquire, release)
    return True


@contextlib.contextmanager
def _exclusive(lock_path: str):
    """An exclusive ``flock`` on ``lock_path`` (created empty) for the ``with`` block."""
    import fcntl
    with open(lock_path, "a+b") as lock:
        fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock.fileno(), fcntl.LOCK_UN)


def serialised_cache_saves() -> bool:
    """One process at a time saves a kernel's cache entry, data before index (see the
    module). Returns whether the change is in place (not on Windows: no ``fcntl``)."""
    try:
        import fcntl  # noqa: F401
    except ImportError:
        return False
    cache_file = getattr(caching, "IndexDataCacheFile", None)
    needed = ("save", "flush", "_load_index", "_save_index", "_save_data", "_data_name")
    if cache_file is None or not all(hasattr(cache_file, name) for name in needed):
        return False
    if getattr(cache_file.save, "_serialised", False):
        return True

    def save(self, key, data):
        with _exclusive(self._index_path + ".lock"):
            overloads = self._load_index()          # as it is now, not when this compile began
            data_name = overloads.get(key)
            if data_name is None:
                taken = set(overloads.values())
                data_name = next(name for name in map(self._data_name, itertools.count(1))
                                 if name not in taken)
                overloads[key] = data_name
            self._save_data(data_name, data)
            self._save_index(overloads)

    def flush(self):
        with _exclusive(self._index_path + ".lock"):
            self._save_index({})

    save._serialised = True
    save.__doc__ = cache_file.save.__doc__
    cache_file.save = save
    cache_file.flush = flush
    return True


QUICK_CACHE_LOADS = quick_cache_loads()
SERIALISED_CACHE_SAVES = serialised_cache_saves()
UNTIMED_LLVM_CALLS = untimed_llvm_calls()
STAMPED_WITH_KERNEL_SOURCES = stamp_with_kernel_sources()
