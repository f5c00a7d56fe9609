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

A cached kernel is tied to what its machine code is made from (:func:`kernel_digest`): its
own code, the code of every kernel it calls or inlines, in any file, followed through their
globals to the end, and the values of the global constants they read (numba freezes those
into the code). numba alone checks a cached kernel against its own file's time and size, but
a kernel carries inside it the code of the kernels it calls: after
``core/raytrace/intersect.py`` changed, the cached ray-tracing kernels of ``whitted.py`` ran
the old triangle test until their cache was deleted. Tying every kernel to every kernel file
instead (as we first did) made any edit recompile all of them; now an edit recompiles the
kernels whose code it changed and those that call them, and nothing else: a comment, or a
change to a kernel the torus never calls, leaves the torus's kernels cached. The digest is
of the code this process compiled, not of the file on disk, so a file edited while a window
runs cannot tie the old code to the new source.

Setting up a kernel's cache (``@njit(cache=True)``) costs ~0.4 ms even when the kernel is
never called: numba finds its cache folder, writes and deletes a file there to see that it
can, and reads its source's stamp. The first frame's modules define ~130 kernels and use
nine: ~50 ms at every start. :func:`njit` sets a kernel's cache up at its first call instead.

numba also wraps every call into LLVM in a pair of "numba:llvm_lock" events, which feed
only its compile-time statistics (``metadata["timers"]``); loading the first frame's nine
cached kernels makes about 2,500 such calls, ~40 ms of events. Those two callbacks are
removed (llvmlite's own lock stays).

numba copies an inlined callee's IR block by block, each block with its own deep copy of the
callee's whole variable scope: quadratic in the callee's size. For a large inlined helper
(``shade_sample`` with both lighting models inside) that was 10 of the 57 s of the volume
renderer's compile, and 9 of the 19 s of ``whitted.trace``. :func:`shared_scope_copies` makes
the blocks of one such copy share one copy of their scope (what one deep copy of all the
blocks together would give); numba's renaming then walks one scope instead of one per block.

numba compiles the implementation of an ``@overload`` (``np.empty``'s, ``min``'s, …) anew
for each literal argument and each set of its caller's flags: ``np.empty(3)`` and
``np.empty(4)`` each compiled the ``(int64, …)`` form, and so did a ``nogil`` kernel beside a
plain one, though that code depends only on the implementation's own code and closed-over
values and on the four flags a callee takes from its caller (error model, fastmath,
forceinline, NRT). :func:`shared_overload_impls` hands numba one dispatcher for each of those.

Two of numba's analyses grow with a kernel's size times its variables. Its liveness
(``numba.core.analysis.compute_live_map``, run after each inlining and dead-code pass)
unites Python sets of thousands of names block by block until nothing changes;
:func:`bitset_live_maps` takes the same two fixed points over integers whose bits are the
variables (1.9 → 0.2 s in ``whitted.trace``'s compile). Its SSA reconstruction rewrites every
block twice for each variable assigned more than once; :func:`ssa_by_blocks_named` runs the
same handlers over the blocks that name that variable (0.9 → 0.1 s). Both give numba's own
result: the same live sets and the same IR, checked call by call over the whole warm-up.
Two more of its hot paths, over a whole warm-up in one process: its compile flags are hashed
and compared as a dict of every option read through a property, 650,000 times (a cache key
of each overload's typing) — :func:`quick_compile_flags` builds that dict from the defaults
and the options set; and an IR statement's variables are gathered by joining a new list at
each level of a recursion, three million times — :func:`listed_vars_in_one_list` appends to
one. Together 3.5 % of the warm-up's CPU, with numba's values, hashes and lists (checked
call by call over a whole warm-up).

If numba's cache classes (or the analyses above) do not have the shape this expects
(another numba version), nothing is changed: the kernels load and compile as numba's do.

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
import enum
import functools
import hashlib
import inspect
import itertools
import logging
import os
import pickle
from pathlib import Path

import numba
import numpy as np
from llvmlite.binding import ffi as llvm_ffi
from numba import config, prange  # noqa: F401  (re-exported: the kernels' imports)
from numba.core import caching, ir, types
from numba.core.runtime import nrt

__all__ = ["SimplifiedCompiler", "config", "kernel_digest", "njit", "prange",
           "quick_cache_loads", "reuse_plain_overloads", "serialised_cache_saves",
           "shared_overload_impls", "untimed_llvm_calls"]

# The packages whose kernel files the warm-up's stamp digests (app/distribution/warm_stamp.py:
# after any change to one of them the warm-up runs again and compiles what went stale).
JIT_FILE = Path(__file__).resolve()
KERNEL_ROOTS = [JIT_FILE.parent, JIT_FILE.parent.parent / "app"]
# A file that defines no kernel but shapes compiled code says so with these words (the
# lighting models' registrations: the kernels' dispatch is generated from them).
GENERATES_KERNELS = b"kernels are generated from this file"


@numba.core.compiler_machinery.register_pass(mutates_CFG=True, analysis_only=False)
class _Simplify(numba.core.compiler_machinery.FunctionPass):
    """Copies propagated and dead variables removed, twice (numba's ``simplify``, as its
    parallel pipeline runs it on every parallel kernel before lowering)."""

    _name = "fvd_simplify"

    def __init__(self):
        numba.core.compiler_machinery.FunctionPass.__init__(self)

    def run_pass(self, state):
        from numba.core import ir_utils
        renamed: dict = {}
        for _ in range(2):
            ir_utils.simplify(state.func_ir, state.typemap, state.calltypes, renamed)
        state.func_ir._definitions = ir_utils.build_definitions(state.func_ir.blocks)
        return True


class SimplifiedCompiler(numba.core.compiler.CompilerBase):
    """numba's nopython pipeline with :class:`_Simplify` after its typed rewrites, for a
    serial kernel that does a parallel loop's work (``@njit(pipeline_class=...)``).

    After numba inlines a helper (``inline="always"``) a plain kernel keeps the copies its
    arrays were passed through, and each copy of an array is a reference count taken and
    given back, atomically, in the loop that inlined it. numba's parallel pipeline removes
    them (its fusion pass simplifies first); its plain one does not. The BVH walk over the
    bunny's 640,000 rays on one thread: 113-117 ms as a plain kernel, 84-96 ms as a parallel
    loop's body, 92 ms as a plain kernel simplified. Not every kernel gains (the path
    tracer's did not) and each costs more to compile: used where measured."""

    def define_pipelines(self):
        from numba.core.typed_passes import NopythonRewrites
        pipeline = numba.core.compiler.DefaultPassBuilder.define_nopython_pipeline(self.state)
        pipeline.add_pass_after(_Simplify, NopythonRewrites)
        pipeline.finalize()
        return [pipeline]


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
        dispatcher._cache = _CacheOnFirstUse(function, dispatcher)
        reuse_plain_overloads(dispatcher)
        return dispatcher
    return decorate


def reuse_plain_overloads(dispatcher):
    """Type a call from one kernel to ``dispatcher`` so that it reuses the kernel compiled for
    plain arguments, where numba would compile the callee once more (40 of the 42 kernels
    with more than one compiled form had one of these two kinds of twin):

    - a constant argument (``Literal[int](0)``: ``_push(rays, 0, ...)`` beside
      ``_push(rays, top, ...)``) is typed as its plain type; the caller's constant is cast,
      and LLVM still sees it when it inlines the call;
    - a ``prange`` index is ``int64`` when numba first types the loop and ``uint64`` in the
      parallel body it makes of it: an unsigned argument is typed ``int64`` where that form
      is compiled already, and only for a kernel that declares numpy's error model. The
      form compiled for a parallel body takes numpy's model from it (a division by zero
      gives inf, not an exception), so a kernel of Python's model keeps its twin there; the
      path tracer's unsigned random state has no signed form and stays as it is."""
    typed_for = dispatcher.get_call_template
    numpy_errors = dispatcher.targetoptions.get("error_model") == "numpy"

    def get_call_template(args, kws):
        args = tuple(types.unliteral(a) for a in args)
        signed = tuple(types.int64 if a == types.uint64 else a for a in args)
        if numpy_errors and signed != args and signed in dispatcher.overloads:
            args = signed
        return typed_for(args, {k: types.unliteral(v) for k, v in kws.items()})
    dispatcher.get_call_template = get_call_template
    return dispatcher


class _CacheOnFirstUse:
    """numba's ``FunctionCache`` for a kernel, made the first time the dispatcher asks it
    anything (what ``enable_caching`` would have made at import)."""

    def __init__(self, function, dispatcher=None):
        self._function = function
        self._dispatcher = dispatcher
        self._cache = None

    def __getattr__(self, name):
        if self._cache is None:
            try:
                cache = caching.FunctionCache(self._function)
            except RuntimeError as error:           # no folder it may write (numba's words)
                _say_once("kernels are compiled but not kept on disk: %s", error)
                cache = _NoCache()
            stamp_with_callees(cache, self._function, self._dispatcher)
            self._cache = cache
        return getattr(self._cache, name)


class _NoCache:
    """A kernel's cache where there is no folder to keep it in: every process compiles it."""

    def load_overload(self, sig, target_context):
        return None

    def save_overload(self, sig, data):
        pass


_said = set()


def _say_once(message: str, *args) -> None:
    """One warning line per kind of cache trouble a process meets, not one per kernel."""
    if message not in _said:
        _said.add(message)
        logging.getLogger("fvd").warning(message, *args)


def tolerant_cache_files() -> bool:
    """A kernel cache file that cannot be read back (truncated by a full disk or a copy cut
    short, or written by something else) is a cache miss, said once, not an exception in
    the middle of a frame: the kernel compiles
    and its files are written anew. A cache folder that refuses a write (read-only, full)
    leaves the kernel compiled in memory, said once. Returns whether the change is in place."""
    cache_file = getattr(caching, "IndexDataCacheFile", None)
    if cache_file is None or not all(hasattr(cache_file, name)
                                     for name in ("_load_index", "_load_data", "save")):
        return False
    if getattr(cache_file._load_index, "_tolerant", False):
        return True
    load_index, load_data, save = cache_file._load_index, cache_file._load_data, cache_file.save
    unreadable = (EOFError, pickle.UnpicklingError, ValueError, TypeError, AttributeError,
                  ImportError, IndexError, OSError)

    def _load_index(self):
        try:
            return load_index(self)
        except unreadable as error:
            _say_once("a kernel cache file could not be read (%s: %s); its kernel compiles "
                      "again: %s", type(error).__name__, error, self._index_path)
            return {}

    def _load_data(self, name):
        try:
            return load_data(self, name)
        except FileNotFoundError:
            raise                                   # numba's own miss
        except unreadable as error:
            _say_once("a kernel cache file could not be read (%s: %s); its kernel compiles "
                      "again: %s", type(error).__name__, error, self._data_path(name))
            raise OSError(str(error)) from None      # numba's load treats OSError as a miss

    def tolerant_save(self, key, data):
        try:
            save(self, key, data)
        except OSError as error:
            _say_once("kernels are compiled but not kept on disk: %s", error)

    _load_index._tolerant = True
    cache_file._load_index, cache_file._load_data = _load_index, _load_data
    cache_file.save = tolerant_save
    return True


def stamp_with_callees(cache, function, dispatcher=None) -> bool:
    """Tie ``cache`` (numba's cache of kernel ``function``, compiled by ``dispatcher``) to
    :func:`kernel_digest` instead of to its own file's time and size (see the module).
    Returns whether it could."""
    cache_file = getattr(cache, "_cache_file", None)
    if not hasattr(cache_file, "_source_stamp"):
        return False
    cache_file._source_stamp = ("kernel digest", kernel_digest(function, dispatcher))
    return True


def _options_bytes(dispatcher) -> bytes:
    """A dispatcher's numba options and compiler pipeline: what, beside the code, decides the
    machine code (``_nrt``, ``error_model``, ``fastmath``, ``parallel``, ...)."""
    pipeline = getattr(getattr(dispatcher, "_compiler", None), "pipeline_class", None)
    return repr((sorted(dispatcher.targetoptions.items()),
                 getattr(pipeline, "__qualname__", None))).encode()


def kernel_digest(function, dispatcher=None) -> str:
    """SHA-256 of what kernel ``function``'s machine code is made from: its code and that of
    every kernel it reaches through its globals and closure, each one's numba options (its
    own from ``dispatcher``, when given: a kernel whose options change compiles again), and
    the global constants they read. Line numbers and file names are left out, so a comment
    or a moved function changes nothing. About 0.1 ms a function reached."""
    digest = hashlib.sha256()
    if dispatcher is not None:
        digest.update(_options_bytes(dispatcher))
    seen, todo = set(), [function]
    while todo:
        f = todo.pop()
        if f in seen:
            continue
        seen.add(f)
        digest.update(_code_bytes(f.__code__) + _value_bytes(f.__defaults__))
        for name, value in _globals_read(f):
            digest.update(name.encode() + b"=")
            if isinstance(value, numba.core.dispatcher.Dispatcher):
                digest.update(_options_bytes(value))
                todo.append(value.py_func)
            else:
                digest.update(_value_bytes(value))
    return digest.hexdigest()


@functools.lru_cache(maxsize=None)
def _code_bytes(code) -> bytes:
    """A code object's instructions, constants and names (nested code objects included),
    without its line numbers and file name."""
    consts = tuple(_code_bytes(c) if hasattr(c, "co_code") else c for c in code.co_consts)
    return repr((code.co_code, consts, code.co_names, code.co_varnames, code.co_freevars,
                 code.co_cellvars, code.co_argcount, code.co_posonlyargcount,
                 code.co_kwonlyargcount, code.co_flags)).encode()


def _names_read(code) -> set[str]:
    names = set(code.co_names)
    for c in code.co_consts:
        if hasattr(c, "co_code"):
            names |= _names_read(c)
    return names


def _globals_read(f):
    """``(name, value)`` of each global, closure cell and module attribute ``f`` may read."""
    names = sorted(_names_read(f.__code__))
    found = [(name, f.__globals__[name]) for name in names if name in f.__globals__]
    for module_name, module in [(n, v) for n, v in found if inspect.ismodule(v)]:
        found += [(f"{module_name}.{name}", getattr(module, name)) for name in names
                  if name in vars(module)]
    cells = zip(f.__code__.co_freevars, f.__closure__ or ())
    found += [(f"<cell {name}>", _cell(cell)) for name, cell in cells]
    return [(name, value) for name, value in found if not inspect.ismodule(value)]


def _cell(cell):
    try:
        return cell.cell_contents
    except ValueError:                    # an empty cell
        return None


def _value_bytes(value) -> bytes:
    """What a global read by a kernel contributes to its digest: a constant's value (numba
    freezes it into the code), anything else its kind and name (library functions: numba's
    version keys the cache already)."""
    if isinstance(value, (bool, int, float, complex, str, bytes, type(None), np.generic)):
        return repr(value).encode()
    if isinstance(value, enum.Enum):
        return repr(value).encode()
    if isinstance(value, (tuple, list)):
        return b"(" + b",".join(_value_bytes(v) for v in value) + b")"
    if isinstance(value, np.ndarray):
        return repr((value.dtype.str, value.shape)).encode() + value.tobytes()
    if isinstance(value, type):
        return repr((value.__module__, value.__qualname__,
                     getattr(value, "_fields", None))).encode()
    if hasattr(value, "_defn") and hasattr(value._defn, "__code__"):   # an @intrinsic
        # and our own functions it calls: call_compiled's type key is frozen into the code
        helpers = [v for _, v in _globals_read(value._defn)
                   if inspect.isfunction(v) and v.__module__.split(".")[0] in ("core", "app")]
        return _code_bytes(value._defn.__code__) + b"".join(_code_bytes(h.__code__)
                                                            for h in helpers)
    return repr((type(value).__module__, type(value).__qualname__,
                 getattr(value, "__qualname__", None))).encode()


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


class _BlockCopier:
    """``copy`` as numba's inliner sees it: a deep copy of an IR block shares its memo with the
    copies of the blocks before it that have the same scope, so that the scope and its
    variables are copied once per IR, not once per block (see the module)."""

    def __init__(self, module):
        self._module = module
        self._scope, self._memo = None, {}

    def __getattr__(self, name):
        return getattr(self._module, name)

    def deepcopy(self, x, memo=None):
        if memo is not None or not isinstance(x, ir.Block):
            return self._module.deepcopy(x, memo)
        if x.scope is not self._scope or id(x) in self._memo:    # another IR, or a 2nd copy
            self._scope, self._memo = x.scope, {}
        return self._module.deepcopy(x, self._memo)


def shared_scope_copies() -> bool:
    """Copy an inlined callee's blocks with one copy of their scope (see the module). Returns
    whether the change is in place."""
    import copy

    from numba.core import inline_closurecall
    if getattr(inline_closurecall, "copy", None) is not copy or \
            not hasattr(inline_closurecall.InlineWorker, "inline_ir"):
        return isinstance(getattr(inline_closurecall, "copy", None), _BlockCopier)
    inline_closurecall.copy = _BlockCopier(copy)
    return True


def _live_map(cfg, blocks, var_use_map, var_def_map):
    """``numba.core.analysis.compute_live_map``'s result (the variables live at each block's
    entry), its two fixed points taken over integers whose bits are variables: a union of
    two sets of thousands of names is then one machine-word loop, not a hash per name."""
    names = list({name for usage in (var_use_map, var_def_map) for block in usage.values()
                  for name in block})
    bit = {name: 1 << i for i, name in enumerate(names)}

    def bits(block_names):
        return sum(bit[name] for name in block_names)
    order = cfg.topo_order()             # the blocks reachable from the entry
    use = {b: bits(var_use_map[b]) for b in order}
    defined = {b: bits(var_def_map[b]) for b in blocks}
    reach = dict.fromkeys(order, 0)      # definitions that reach each block's entry
    changed = True
    while changed:
        changed = False
        for b in order:
            here = reach[b] | defined[b] | use[b]
            reach[b] = here
            for after, _ in cfg.successors(b):
                if reach[after] | here != reach[after]:
                    reach[after] |= here
                    changed = True
    live = {b: bits(var_use_map[b]) for b in blocks}
    changed = True
    while changed:
        changed = False
        for b in reversed(order):
            for before, _ in cfg.predecessors(b):
                more = live[b] & reach.get(before, 0) & ~defined[before]
                if live[before] | more != live[before]:
                    live[before] |= more
                    changed = True
    return {b: _names_of(v, names) for b, v in live.items()}


def _names_of(value: int, names: list) -> set:
    """The names whose bits are set in ``value``."""
    digits = bin(value)[:1:-1]           # bit i is digits[i]
    found, i = set(), digits.find("1")
    while i >= 0:
        found.add(names[i])
        i = digits.find("1", i + 1)
    return found


def _is_known_source(function, digest: str) -> bool:
    """Is ``function``'s source the one a replacement was checked against (numba 0.68.1)?
    Another numba keeps its own code: faster is not worth a different result."""
    try:
        return hashlib.sha256(inspect.getsource(function).encode()).hexdigest()[:16] == digest
    except (OSError, TypeError):
        return False


def bitset_live_maps() -> bool:
    """numba's liveness analysis on bit sets (see the module). Returns whether the change is
    in place."""
    from numba.core import analysis, ir_utils
    if getattr(analysis.compute_live_map, "__wrapped__", None) is not None:
        return True
    original = analysis.compute_live_map
    if not _is_known_source(original, "713c4c094977e93b"):
        return False
    live_map = functools.wraps(original)(_live_map)
    analysis.compute_live_map = live_map
    if getattr(ir_utils, "compute_live_map", None) is original:
        ir_utils.compute_live_map = live_map
    return True


def _ssa_blocks(blocks):
    """``numba.core.ssa._run_ssa`` (SSA reconstruction, one variable assigned more than once
    at a time) with each variable's two rewrites run over the blocks that name it, not over
    every block: numba's own handlers, in the same order, so the same IR comes out."""
    from collections import defaultdict

    from numba.core import errors, ssa
    if not blocks:
        return {}
    given = dict(blocks)
    cfg = ssa.compute_cfg_from_blocks(blocks)
    df_plus = ssa._iterated_domfronts(cfg)
    violators = ssa._find_defs_violators(blocks, cfg)
    cache_list_vars = ssa._CacheListVars()
    scope = ssa._get_scope(blocks)
    naming = defaultdict(list)              # variable -> the labels of the blocks naming it
    for label, block in blocks.items():
        for name in {var.name for stmt in block.body for var in stmt.list_vars()}:
            naming[name].append(label)
    for varname in violators:
        labels = naming[varname]
        defmap = defaultdict(list)
        states = {"scope": scope, "varname": varname, "defmap": defmap}
        blocks = {**blocks, **ssa._run_block_rewrite({b: blocks[b] for b in labels}, states,
                                                     ssa._FreshVarHandler())}
        phimap = defaultdict(list)
        states = {"scope": scope, "varname": varname, "defmap": defmap, "phimap": phimap,
                  "cfg": cfg, "phi_locations": ssa._compute_phi_locations(df_plus, defmap)}
        fixed = ssa._run_block_rewrite({b: blocks[b] for b in labels}, states,
                                       ssa._FixSSAVars(cache_list_vars))
        blocks = {**blocks, **fixed}
        for label, phis in phimap.items():      # numba prepends them to a new block too
            if label not in fixed:
                blocks[label] = _block_copy(blocks[label])
            blocks[label].body = phis + blocks[label].body
    if ssa.compute_cfg_from_blocks(blocks) != cfg:
        raise errors.CompilerError("CFG mutated in SSA pass")
    return {label: _block_copy(block) if block is given[label] else block
            for label, block in blocks.items()}     # new blocks throughout, as numba's


def _block_copy(block):
    copied = ir.Block(scope=block.scope, loc=block.loc)
    copied.body = list(block.body)
    return copied


def ssa_by_blocks_named() -> bool:
    """numba's SSA reconstruction over the blocks that name each variable (see the module).
    Returns whether the change is in place."""
    from numba.core import ssa
    if getattr(ssa._run_ssa, "__wrapped__", None) is not None:
        return True
    if not _is_known_source(ssa._run_ssa, "c497422bcf049990"):
        return False
    ssa._run_ssa = functools.wraps(ssa._run_ssa)(_ssa_blocks)
    return True


def _option_defaults(cls):
    """``{option: default}`` of a ``TargetConfig`` class whose options all read through the
    properties numba's metaclass made (``_values.get(name, default)``), else None."""
    defaults = {}
    for name, option in cls.options.items():
        read = getattr(getattr(cls, name, None), "fget", None)
        if not getattr(read, "__qualname__", "").endswith("make_prop.<locals>.getter"):
            return None
        defaults[name] = option.default
    return defaults


def quick_compile_flags() -> bool:
    """numba's compile flags (``TargetConfig``) hashed and compared without reading each
    option through its property (see the module). Returns whether the change is in place."""
    from numba.core import targetconfig
    config = targetconfig.TargetConfig
    if getattr(config.values, "quick", False):
        return True
    if not (_is_known_source(config.values, "12a29dc810f6a91b")
            and _is_known_source(config.__hash__, "4d15a6c75137a983")):
        return False
    known, slow = {}, config.values

    def values(self):
        cls = type(self)
        if cls not in known:
            known[cls] = _option_defaults(cls)
        defaults = known[cls]
        if defaults is None or not self._values.keys() <= defaults.keys():
            return slow(self)
        out = dict(defaults)              # in the options' order, as numba's
        out.update(self._values)
        return out

    def hash_of(self):
        # numba's hash(tuple(sorted(self.values()))) sorts the dict's keys: the options
        return hash(tuple(sorted(self.options)))
    values.quick, values.__wrapped__ = True, slow
    config.values, config.__hash__ = values, hash_of
    return True


def _vars_into(value, out: list) -> None:
    """numba's ``Inst._rec_list_vars``, appending to one list instead of joining lists."""
    if isinstance(value, ir.Var):
        out.append(value)
    elif isinstance(value, ir.Inst):
        out.extend(value.list_vars())
    elif isinstance(value, (list, tuple)):
        for item in value:
            _vars_into(item, out)
    elif isinstance(value, dict):
        for item in value.values():
            _vars_into(item, out)


def _rec_list_vars(self, value):
    out = []
    _vars_into(value, out)
    return out


def listed_vars_in_one_list() -> bool:
    """numba's IR ``list_vars`` without its intermediate lists (see the module). Returns
    whether the change is in place."""
    if ir.Inst._rec_list_vars is _rec_list_vars:
        return True
    if not _is_known_source(ir.Inst._rec_list_vars, "054700e9100b6299"):
        return False
    _rec_list_vars.__wrapped__ = ir.Inst._rec_list_vars       # numba's, for the tests
    ir.Inst._rec_list_vars = _rec_list_vars
    return True


# The flags a callee takes from the kernel that calls it (numba.core.cpu.CPUTargetOptions)
INHERITED_FLAGS = ("error_model", "fastmath", "forceinline", "nrt")


def _impl_key(pyfunc, options):
    """What an ``@overload`` implementation compiles from: its code, the values it closes
    over, its defaults, its jit options and the caller's inherited flags (None: a function
    whose parts cannot be compared)."""
    from numba.core import targetconfig
    flags = targetconfig.ConfigStack.top_or_none()
    try:
        # each value with its type: 1, 1.0 and True are equal, and numba types them apart
        cells = tuple((type(c.cell_contents), c.cell_contents) for c in pyfunc.__closure__ or ())
        defaults = tuple((type(v), v) for v in pyfunc.__defaults__ or ())
        key = (pyfunc.__code__, cells, defaults,
               tuple(sorted((k, type(v), v) for k, v in (pyfunc.__kwdefaults__ or {}).items())),
               tuple(sorted(options.items())),
               None if flags is None else tuple(repr(getattr(flags, name, None))
                                                for name in INHERITED_FLAGS))
        hash(key)
    except (TypeError, ValueError):      # an unhashable value, or an empty cell
        return None
    return key


def shared_overload_impls() -> bool:
    """One compiled ``@overload`` implementation per code, closed-over values and inherited
    flags (see the module). Returns whether the change is in place."""
    from numba.core.typing import templates
    template = getattr(templates, "_OverloadFunctionTemplate", None)
    if template is None or not hasattr(template, "_get_jit_decorator"):
        return False
    if getattr(template._get_jit_decorator, "shared", False):
        return True
    jit_decorator = template._get_jit_decorator
    made = {}

    def _get_jit_decorator(self):
        jitter = jit_decorator(self)

        def shared_jitter(**options):
            decorate = jitter(**options)

            def dispatcher(pyfunc):
                key = _impl_key(pyfunc, options)
                if key is None:
                    return decorate(pyfunc)
                if key not in made:
                    made[key] = decorate(pyfunc)
                return made[key]
            return dispatcher
        return shared_jitter
    _get_jit_decorator.shared = True
    template._get_jit_decorator = _get_jit_decorator
    return True


QUICK_CACHE_LOADS = quick_cache_loads()
SERIALISED_CACHE_SAVES = serialised_cache_saves()
TOLERANT_CACHE_FILES = tolerant_cache_files()    # after it: wraps its save
UNTIMED_LLVM_CALLS = untimed_llvm_calls()
SHARED_SCOPE_COPIES = shared_scope_copies()
SHARED_OVERLOAD_IMPLS = shared_overload_impls()
BITSET_LIVE_MAPS = bitset_live_maps()
SSA_BY_BLOCKS_NAMED = ssa_by_blocks_named()
QUICK_COMPILE_FLAGS = quick_compile_flags()
LISTED_VARS_IN_ONE_LIST = listed_vars_in_one_list()


# --------------------------------------------------------------------------------------------
# Calls by address


def _types_key(argtypes) -> int:
    """A number for a kernel's argument types, the same in every process."""
    import zlib
    return zlib.crc32(repr(tuple(argtypes)).encode())


@numba.extending.intrinsic
def call_compiled(typingctx, at, callee, *args):
    """``callee(*args)``, through its machine code at ``at`` (:func:`compiled_at`).

    A plain call links the callee's code into the caller, where LLVM optimises all of it
    again: the parallel loop over ``whitted.trace`` took 10 s of compile for that, beside the
    20 s of ``trace`` itself. Called by its address, the callee is compiled once, on its own,
    and runs the same code. numba types the callee here as for a plain call (compiling it if
    it must). ``at`` carries its argument types' key: code compiled for other types is never
    called (the call raises ValueError instead, and is skipped in a parallel loop, where numba
    drops exceptions).

    For calls that each do much work (a run of rays, a core's share): LLVM cannot inline the
    callee, so each call pays what inlining removed. The z-buffer's tile loop (about twenty
    arrays a call, 425 tiles a frame at 1580 x 1080) ran 3.5-4 % slower through it, and keeps
    its plain call."""
    from numba.core import cgutils
    from numba.core.typing import signature
    argtypes = tuple(args)
    declared = _DECLARED_RETURNS.get(callee.dispatcher.py_func)
    if declared is not None:            # typed as called, not compiled here (compiled_apart)
        typed = signature(declared, *(types.unliteral(a) for a in argtypes))
    else:
        typed = typingctx.resolve_function_type(callee, argtypes, {})
    if typed is None:
        raise numba.core.errors.TypingError(f"{callee} cannot take {argtypes}")
    key = _types_key(typed.args)

    def codegen(context, builder, sig, values):
        address, given_key = cgutils.unpack_tuple(builder, values[0], 2)
        with builder.if_then(builder.icmp_signed("!=", given_key, given_key.type(key)),
                             likely=False):
            context.call_conv.return_user_exc(
                builder, ValueError, (f"machine code for other argument types than "
                                      f"{callee.dispatcher.py_func.__qualname__}'s here",))
        given = cgutils.unpack_tuple(builder, values[2], len(argtypes))
        cast = [context.cast(builder, v, a, b) for v, a, b in zip(given, argtypes, typed.args)]
        fnty = context.call_conv.get_function_type(typed.return_type, typed.args)
        function = builder.inttoptr(address, fnty.as_pointer())
        status, result = context.call_conv.call_function(builder, function, typed.return_type,
                                                         typed.args, cast)
        with cgutils.if_unlikely(builder, status.is_error):
            context.call_conv.return_status_propagate(builder, status)
        return result
    return signature(typed.return_type, at, callee,
                     types.StarArgTuple.from_types(argtypes)), codegen


_COMPILED_AT: dict = {}


_DECLARED_RETURNS: dict = {}     # Python function -> numba type (compiled_apart)


def compiled_apart(returns):
    """Declare what a kernel returns, so that :func:`call_compiled` types a call to it from
    the arguments alone: the caller compiles without compiling the callee, which is compiled
    (by :func:`compiled_at`) only where it is called. For a branch that most frames never
    take: the ray tracer's textured surfaces cost an untextured scene 3.3 s of compile.
    :func:`compiled_at` checks the declaration against the compiled return type."""
    def declare(dispatcher):
        _DECLARED_RETURNS[dispatcher.py_func] = returns
        return dispatcher
    return declare


NOT_COMPILED = (0, -1)   # an address for a compiled_apart callee that the frame never calls


def compiled_at(dispatcher, arguments) -> tuple[int, int]:
    """``(address, key)`` of ``dispatcher``'s machine code for the types of ``arguments``
    (values, typed as a call from Python types them; compiled or loaded first), for
    :func:`call_compiled`. Remembered by the arguments' fingerprints (numba's dispatcher's
    own fast key: 0.1 µs an argument, against 12 µs for typing an array)."""
    from numba._dispatcher import compute_fingerprint
    try:
        memo = (dispatcher, tuple(compute_fingerprint(a) for a in arguments))
    except (ValueError, TypeError):         # a value numba has no fingerprint for
        memo = None
    if memo in _COMPILED_AT:
        return _COMPILED_AT[memo]
    argtypes = tuple(types.unliteral(dispatcher.typeof_pyval(a)) for a in arguments)
    result = dispatcher.overloads.get(argtypes)
    if result is None:
        dispatcher.compile(argtypes)
        result = dispatcher.overloads[argtypes]
    declared = _DECLARED_RETURNS.get(dispatcher.py_func)
    if declared is not None and result.signature.return_type != declared:
        raise TypeError(f"{dispatcher.py_func.__qualname__} returns "
                        f"{result.signature.return_type}, not the {declared} it declares")
    address = result.library.get_pointer_to_function(result.fndesc.llvm_func_name)
    at = address, _types_key(result.signature.args)
    if memo is not None:
        _COMPILED_AT[memo] = at
    return at
