"""numba for every kernel of the core: ``from core.jit import njit, prange``.

One place that knows how the kernels are compiled and loaded. What it changes: loading a
kernel from numba's on-disk cache no longer imports numba's whole library first.

Before the first kernel of a process is loaded from the cache, numba refreshes its target
context: it imports every implementation module it has (arrays, linalg, random, typed
containers, unicode, …) and installs their registries, which a compile needs and loading
compiled code does not. Measured on a warm start (``scenes/sphere.toml``, CLI render): the
first frame took 0.27 s, of which the refresh was about 0.1 s; without it, 0.18 s. Here a
cache load initialises only numba's runtime (NRT: the allocator the kernels call) and reads
the cached code; a kernel that has to be compiled still gets the full refresh (numba's
compiler does it itself), so what a compile sees is unchanged.

If numba's cache class does not have the shape this expects (another numba version), nothing
is changed: the kernels load as numba loads them.
"""

from __future__ import annotations

import numba
from numba import config, njit, prange  # noqa: F401  (re-exported: the kernels' imports)
from numba.core import caching
from numba.core.runtime import nrt

__all__ = ["config", "njit", "prange", "quick_cache_loads"]


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


QUICK_CACHE_LOADS = quick_cache_loads()
NUMBA_VERSION = numba.__version__
