"""core.jit: a kernel loaded from numba's cache without numba's full registry refresh, and a
cached kernel that goes stale when a kernel it inlines from another file changes.

Each case runs in a fresh Python process (the refresh happens once per process) with its own
kernel cache, on a kernel module written to a temporary folder: the first process compiles
and caches it, the second loads it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

from tests.conftest import ROOT

KERNELS = '''
import numpy as np
from core.jit import njit


@njit(cache=True)
def total(a):
    s = 0.0
    for x in a:
        s += x
    return s


@njit(cache=True)
def scaled(a, k):
    out = np.empty_like(a)
    for i in range(a.shape[0]):
        out[i] = a[i] * k
    return out
'''


def _run(tmp_path: Path, code: str) -> str:
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, cwd=ROOT,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout.strip()


def test_a_cached_kernel_loads_without_the_registry_refresh(tmp_path):
    (tmp_path / "kernels_for_jit_test.py").write_text(KERNELS)
    first = _run(tmp_path, """
        import numpy as np, kernels_for_jit_test as k
        print(k.total(np.arange(5.0)), k.scaled(np.arange(3.0), 2.0).tolist())
    """)
    assert first == "10.0 [0.0, 2.0, 4.0]"
    # a new process: both kernels come from the cache; numba's linear algebra registry (one
    # of the modules its refresh imports) stays unloaded, and nothing compiles
    second = _run(tmp_path, """
        import sys, numpy as np
        from numba.core import event
        compiled = []
        class Listener(event.Listener):
            def on_start(self, ev): compiled.append(ev.data["dispatcher"].py_func.__name__)
            def on_end(self, ev): pass
        event.register("numba:compile", Listener())
        import core.jit, kernels_for_jit_test as k
        print(core.jit.QUICK_CACHE_LOADS, k.total(np.arange(5.0)),
              k.scaled(np.arange(3.0), 2.0).tolist(), "numba.np.linalg" in sys.modules,
              compiled)
    """)
    assert second == "True 10.0 [0.0, 2.0, 4.0] False []"


def test_a_compile_after_a_quick_load_still_gets_the_whole_registry(tmp_path):
    """A kernel that is not in the cache compiles as before (numba's compiler refreshes its
    contexts itself), here one using numpy's median and a typed list after a quick load."""
    (tmp_path / "kernels_for_jit_test.py").write_text(KERNELS)
    _run(tmp_path, "import numpy as np, kernels_for_jit_test as k; k.total(np.ones(2))")
    out = _run(tmp_path, """
        import numpy as np, kernels_for_jit_test as k
        from core.jit import njit
        k.total(np.ones(2))                        # a quick load
        @njit
        def middle(a):
            seen = [x for x in a if x > 0.0]
            return np.median(a), len(seen)
        print(middle(np.array([3.0, -1.0, 2.0])))
    """)
    assert out == "(2.0, 2)"


HELPER = """
from core.jit import njit


@njit(cache=True, inline="always")
def step(x):
    return x + {step}
"""

USER = """
from core.jit import njit
from helper_for_jit_test import step


@njit(cache=True)
def twice(x):
    return step(step(x))
"""


OTHER = """
from core.jit import njit


@njit(cache=True)
def unrelated(x):
    return x * 3
"""

COUNTED = """
    from numba.core import event
    compiled = []
    class Listener(event.Listener):
        def on_start(self, ev): compiled.append(ev.data["dispatcher"].py_func.__name__)
        def on_end(self, ev): pass
    event.register("numba:compile", Listener())
    import user_for_jit_test as u, other_for_jit_test as o
    print(u.twice(10), o.unrelated(1), sorted(set(compiled)))
"""


def test_a_kernel_compiles_again_when_a_kernel_it_inlines_changes(tmp_path):
    """numba alone checks a cached kernel against its own file; ``twice`` keeps ``step``'s
    code inside it, so after ``step`` changes the cache would still answer with the old
    code. With ``core.jit`` a kernel is stamped with the code of every kernel it reaches."""
    (tmp_path / "helper_for_jit_test.py").write_text(HELPER.format(step=1))
    (tmp_path / "user_for_jit_test.py").write_text(USER)
    (tmp_path / "other_for_jit_test.py").write_text(OTHER)
    assert _run(tmp_path, COUNTED) == "12 3 ['twice', 'unrelated']"
    assert _run(tmp_path, COUNTED) == "12 3 []"                 # from the cache
    (tmp_path / "helper_for_jit_test.py").write_text(HELPER.format(step=5))
    assert _run(tmp_path, COUNTED) == "20 3 ['twice']"          # not the cached 12


def test_a_comment_or_an_edit_elsewhere_recompiles_nothing(tmp_path):
    """An edit to a kernel that ``twice`` never reaches, and a comment in the file of one it
    does (no code changes), leave ``twice`` cached; only the edited kernel compiles."""
    (tmp_path / "helper_for_jit_test.py").write_text(HELPER.format(step=1))
    (tmp_path / "user_for_jit_test.py").write_text(USER)
    (tmp_path / "other_for_jit_test.py").write_text(OTHER)
    assert _run(tmp_path, COUNTED) == "12 3 ['twice', 'unrelated']"
    (tmp_path / "other_for_jit_test.py").write_text(OTHER.replace("x * 3", "x * 4"))
    with (tmp_path / "helper_for_jit_test.py").open("a") as helper:
        helper.write("# a comment at the end\n")
    assert _run(tmp_path, COUNTED) == "12 4 ['unrelated']"


def test_a_kernel_compiles_again_when_its_own_options_change(tmp_path):
    """A kernel's numba options decide its machine code as its code does (``_nrt=False``
    leaves out the reference counts): changing them in its decorator must not load the code
    cached under the old ones. Only the changed kernel compiles."""
    (tmp_path / "helper_for_jit_test.py").write_text(HELPER.format(step=1))
    (tmp_path / "user_for_jit_test.py").write_text(USER)
    (tmp_path / "other_for_jit_test.py").write_text(OTHER)
    assert _run(tmp_path, COUNTED) == "12 3 ['twice', 'unrelated']"
    (tmp_path / "other_for_jit_test.py").write_text(
        OTHER.replace("@njit(cache=True)", "@njit(cache=True, _nrt=False)"))
    assert _run(tmp_path, COUNTED) == "12 3 ['unrelated']"
    assert _run(tmp_path, COUNTED) == "12 3 []"                 # and cached under the new


def test_the_digest_follows_calls_and_constants_not_line_numbers():
    """core.jit.kernel_digest: the same for the same code moved down a line; different for a
    changed constant the kernel reads, or a changed callee."""
    import numba

    from core.jit import kernel_digest

    def kernels(source: str) -> dict:
        scope = {"numba": numba}
        exec(compile(textwrap.dedent(source), "<test>", "exec"), scope)
        return scope

    base = """
        K = 2
        @numba.njit(inline="always")
        def callee(x):
            return x + K
        def caller(x):
            return callee(x) * 2
    """
    first = kernel_digest(kernels(base)["caller"])
    assert kernel_digest(kernels("\n\n" + base)["caller"]) == first
    assert kernel_digest(kernels(base.replace("K = 2", "K = 3"))["caller"]) != first
    assert kernel_digest(kernels(base.replace("x + K", "x - K"))["caller"]) != first


def test_a_kernel_cache_is_set_up_at_the_first_call_not_at_import(tmp_path):
    """Importing a module of kernels touches no cache (numba would find each kernel's cache
    folder and write a test file there, ~0.4 ms a kernel); the first call caches the kernel it
    compiles, and the next process loads that one from the cache. numba's llvm_lock timing
    events are gone (nothing listens to them but its compile statistics)."""
    (tmp_path / "kernels_for_jit_test.py").write_text(KERNELS)
    first = _run(tmp_path, """
        import os, numpy as np
        from numba.core import event
        locks = []
        class Listener(event.Listener):
            def on_start(self, ev): locks.append(ev)
            def on_end(self, ev): pass
        event.register("numba:llvm_lock", Listener())
        import kernels_for_jit_test as k
        cache = os.environ["NUMBA_CACHE_DIR"]
        before = os.path.exists(cache)
        k.total(np.arange(3.0))
        kernels = sorted({name.split("-")[0].split(".")[-1] for _, _, names in os.walk(cache)
                          for name in names})
        print(before, kernels, len(locks))
    """)
    assert first == "False ['total'] 0"
    second = _run(tmp_path, """
        import numpy as np, kernels_for_jit_test as k
        k.total(np.arange(3.0))
        print(sum(k.total.stats.cache_hits.values()), sum(k.total.stats.cache_misses.values()))
    """)
    assert second == "1 0"


def _cache_files(tmp_path: Path, suffix: str) -> list[Path]:
    return sorted((tmp_path / "cache").rglob(f"*{suffix}"))


CALL_TOTAL = """
    import numpy as np, kernels_for_jit_test as k
    print(k.total(np.arange(4.0)), sum(k.total.stats.cache_hits.values()))
"""


def test_a_half_written_or_foreign_cache_file_is_a_miss_said_once(tmp_path):
    """A truncated data file, a truncated index and an index written by another numba
    version: each is one warning line (or none, for the other version: numba's own miss),
    the kernel compiles, and the next process loads the files written anew."""
    import pickle
    (tmp_path / "kernels_for_jit_test.py").write_text(KERNELS)
    assert _run(tmp_path, CALL_TOTAL) == "6.0 0"
    for suffix in (".nbc", ".nbi"):
        victim, = _cache_files(tmp_path, suffix)
        victim.write_bytes(victim.read_bytes()[:40])        # killed half-way through a write
        env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
                   PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
        done = subprocess.run([sys.executable, "-c", textwrap.dedent(CALL_TOTAL)], env=env,
                              cwd=ROOT, capture_output=True, text=True, timeout=300)
        assert done.returncode == 0 and done.stdout.strip() == "6.0 0", done.stderr
        said = [line for line in done.stderr.splitlines() if "could not be read" in line]
        assert len(said) == 1 and victim.name in said[0], done.stderr
        assert _run(tmp_path, CALL_TOTAL) == "6.0 1"        # written anew, loaded
    index, = _cache_files(tmp_path, ".nbi")
    with index.open("rb") as f:
        pickle.load(f)
        rest = f.read()
    index.write_bytes(pickle.dumps("0.1.0") + rest)        # another numba's index
    assert _run(tmp_path, CALL_TOTAL) == "6.0 0"
    assert _run(tmp_path, CALL_TOTAL) == "6.0 1"


def test_a_kernel_file_edited_while_a_process_runs_keeps_the_code_it_compiled(tmp_path):
    """A window imports a kernel module, the file is then edited, and the window compiles the
    code it imported: the cache entry it writes names that code, so the next process (the new
    source) compiles the new code instead of loading the old."""
    (tmp_path / "kernels_for_jit_test.py").write_text(KERNELS)
    edited = KERNELS.replace("s += x", "s += 2 * x")
    assert _run(tmp_path, f"""
        import pathlib, numpy as np, kernels_for_jit_test as k
        pathlib.Path(k.__file__).write_text({edited!r})    # edited under the running window
        print(k.total(np.arange(4.0)))
    """) == "6.0"
    assert _run(tmp_path, CALL_TOTAL) == "12.0 0"
    assert _run(tmp_path, CALL_TOTAL) == "12.0 1"


RENDER_TORUS = """
    import json, time
    start = time.perf_counter()
    from numba.core import event
    compiled = []
    class Listener(event.Listener):
        def on_start(self, ev): compiled.append(ev.data["dispatcher"].py_func.__qualname__)
        def on_end(self, ev): pass
    event.register("numba:compile", Listener())
    from core.render import render
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    scene = load_scene("scenes/torus.toml")
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, size=(64, 48)))
    print(json.dumps({"compiled": sorted(set(compiled)), "lit": int((frame.color > 0).sum()),
                      "seconds": time.perf_counter() - start}))
"""


def test_an_edit_to_the_volume_ray_marcher_leaves_the_torus_cached(tmp_path):
    """A comment appended to ``core/volume/raymarch.py`` made every kernel compile
    again. In a copy of the code with a copy of its kernel cache (a cached kernel is keyed by
    its code, not its path), the torus is drawn (compiling what the cache lacks), the comment
    is appended, and the torus drawn again compiles nothing."""
    import json
    import shutil
    clone = tmp_path / "clone"
    for folder in ("app", "core", "scenes", "shaders"):
        shutil.copytree(ROOT / folder, clone / folder)          # with the dates: numba checks
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["PYTHONPATH"] = str(clone)

    def draw():
        done = subprocess.run([sys.executable, "-c", textwrap.dedent(RENDER_TORUS)], env=env,
                              cwd=clone, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr[-3000:]
        return json.loads(done.stdout.strip().splitlines()[-1])

    first = draw()
    assert first["lit"] > 0
    marcher = clone / "core" / "volume" / "raymarch.py"
    with marcher.open("a") as out:
        out.write("# an edit that changes no code the torus runs\n")
    again = draw()
    assert again["compiled"] == [] and again["lit"] == first["lit"]


def test_a_cache_folder_that_refuses_writes_is_said_once_and_the_kernels_still_run(tmp_path):
    """Read-only folders cannot be made as root (the tests' user on CI), so numba's own probe
    of a folder is made to fail, and then a save: each is one line, and the kernels run."""
    (tmp_path / "kernels_for_jit_test.py").write_text(KERNELS)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"),
               PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]))
    for refuse in ("caching._CacheLocator.ensure_cache_path",
                   "caching.IndexDataCacheFile._save_data"):
        owner, name = refuse.rsplit(".", 1)
        code = f"""
            import errno, numpy as np
            import core.jit
            from numba.core import caching
            def refuse(*args, **kwargs):
                raise OSError(errno.EROFS, "Read-only file system")
            setattr({owner}, {name!r}, refuse)
            import kernels_for_jit_test as k
            print(k.total(np.arange(4.0)), k.scaled(np.arange(3.0), 2.0).tolist())
        """
        done = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=env, cwd=ROOT,
                              capture_output=True, text=True, timeout=300)
        assert done.returncode == 0 and done.stdout.strip() == "6.0 [0.0, 2.0, 4.0]", done.stderr
        said = [line for line in done.stderr.splitlines() if "not kept on disk" in line]
        assert len(said) == 1, done.stderr


ADDRESSED = '''
import numpy as np
from core.jit import call_compiled, njit, prange


@njit(cache=True)
def dot(a, b, lo, hi):
    s = 0.0
    for i in range(lo, hi):
        s += a[i] * b[i]
    return s


@njit(cache=True)
def one(at, a, b):
    return call_compiled(at, dot, a, b, 2, 5)


@njit(cache=True, parallel=True)
def rows(at, a, b, out):
    for j in prange(out.shape[0]):
        out[j] = call_compiled(at, dot, a, b, 10 * j, 10 * j + 10)
'''


def test_a_kernel_called_by_its_address_gives_the_plain_calls_values_cached_or_not(tmp_path):
    (tmp_path / "addressed_for_jit_test.py").write_text(ADDRESSED)
    code = """
        import numpy as np, addressed_for_jit_test as k
        from core.jit import compiled_at
        a, b = np.arange(40.0), np.arange(40.0) ** 2
        at = compiled_at(k.dot, (a, b, 0, 0))
        out = np.empty(4)
        k.rows(at, a, b, out)
        print(k.one(at, a, b), k.dot(a, b, 2, 5), out.tolist() == [k.dot(a, b, 10 * j, 10 * j + 10)
                                                                   for j in range(4)])
        print(len(k.dot.signatures), len(k.one.signatures), len(k.rows.signatures))
    """
    # 2³ + 3³ + 4³ = 99, by hand; the second process loads all three kernels from the cache
    assert _run(tmp_path, code) == "99.0 99.0 True\n1 1 1"
    assert _run(tmp_path, code) == "99.0 99.0 True\n1 1 1"


def test_machine_code_for_other_argument_types_is_refused_not_called(tmp_path):
    (tmp_path / "addressed_for_jit_test.py").write_text(ADDRESSED)
    said = _run(tmp_path, """
        import numpy as np, addressed_for_jit_test as k
        from core.jit import compiled_at
        a = np.arange(40.0)
        wrong = compiled_at(k.dot, (a.astype(np.float32), a.astype(np.float32), 0, 0))
        try:
            k.one(wrong, a, a)
        except ValueError as error:
            print(error)
    """)
    assert said == "machine code for other argument types than dot's here"


def test_a_kernel_calling_by_address_is_tied_to_the_type_key_frozen_into_it(monkeypatch):
    """The key of the argument types is computed when the caller compiles and again at each
    call: another key function must make the cached caller stale, or its calls would be
    refused."""
    import core.jit as jit
    from core.raytrace import whitted
    def another_key(argtypes):
        return 0
    another_key.__module__ = "core.jit"         # as an edit of core/jit.py would make it
    before = jit.kernel_digest(whitted.trace_many.py_func)
    monkeypatch.setattr(jit, "_types_key", another_key)
    assert jit.kernel_digest(whitted.trace_many.py_func) != before
    monkeypatch.undo()
    assert jit.kernel_digest(whitted.trace_many.py_func) == before



APART = '''
from numba import types
from core.jit import call_compiled, compiled_apart, njit


@compiled_apart(returns=types.UniTuple(types.float64, 2))
@njit(cache=True)
def rare(a, i):
    return a[i] * 2.0, a[i] + 1.0


@compiled_apart(returns=types.float64)
@njit(cache=True)
def misdeclared(a, i):
    return i


@njit(cache=True)
def caller(at, a, use):
    if use:
        x, y = call_compiled(at, rare, a, 1)
        return x + y
    return -1.0
'''


def test_a_kernel_compiled_apart_is_compiled_where_it_is_called_not_by_its_caller(tmp_path):
    """The caller compiles (and loads from the cache) without compiling ``rare``; called by
    the address compiled_at gives, ``rare`` runs; NOT_COMPILED is refused if ever called, and
    a return type that is not the declared one is refused before any call."""
    (tmp_path / "apart_for_jit_test.py").write_text(APART)
    code = """
        import numpy as np, apart_for_jit_test as k
        from core.jit import NOT_COMPILED, compiled_at
        a = np.arange(4.0)
        print(k.caller(NOT_COMPILED, a, False), len(k.rare.signatures))
        try:
            k.caller(NOT_COMPILED, a, True)
        except ValueError as error:
            print(error)
        print(k.caller(compiled_at(k.rare, (a, 0)), a, True), len(k.rare.signatures))
        try:
            compiled_at(k.misdeclared, (a, 0))
        except TypeError as error:
            print(error)
    """
    # a[1] = 1.0: 2 * 1 + (1 + 1) = 4, by hand
    expected = ("-1.0 0\nmachine code for other argument types than rare's here\n4.0 1\n"
                "misdeclared returns int64, not the float64 it declares")
    assert _run(tmp_path, code) == expected
    assert _run(tmp_path, code) == expected       # the caller and rare loaded from the cache

OVERLOADED = '''
import numpy as np
from numba import types
from numba.extending import overload
from core.jit import njit


def filled(n):
    raise NotImplementedError("a kernel's helper: called from kernels only")


@overload(filled)
def _filled(n):
    kind = np.int64

    def impl(n):
        return np.full(n, 7, kind)
    return impl


@njit(cache=True)
def three():
    return filled(3).sum()


@njit(cache=True, nogil=True)
def four():
    return filled(4).sum()


@njit(cache=True)
def many(n):
    return filled(n).sum()


@njit(cache=True, error_model="numpy")
def five_numpy():
    return filled(5).sum()


def unit(x):
    raise NotImplementedError("a kernel's helper: called from kernels only")


@overload(unit)
def _unit(x):
    one = 1 if isinstance(x, types.Integer) else 1.0     # equal values, apart in type

    def impl(x):
        return one
    return impl


@njit(cache=True)
def units():
    return unit(2), unit(2.5)
'''


def test_an_overloads_implementation_compiles_once_per_code_and_inherited_flags(tmp_path):
    """numba alone compiled ``impl`` for ``(int64,)`` three times here: for ``three``, again
    for ``four`` (a ``nogil`` kernel; another literal), and for ``five_numpy``. numpy's error
    model reaches the callee's code, so that one compiles on its own; ``nogil`` and the
    literal do not."""
    (tmp_path / "overloaded_for_jit_test.py").write_text(OVERLOADED)
    said = _run(tmp_path, """
        from numba.core import event
        compiled = []
        class Listener(event.Listener):
            def on_start(self, ev):
                d = ev.data["dispatcher"]
                if d.py_func.__module__ == "overloaded_for_jit_test":
                    compiled.append((d.py_func.__name__, tuple(map(str, ev.data["args"]))))
            def on_end(self, ev): pass
        event.register("numba:compile", Listener())
        import core.jit, overloaded_for_jit_test as k
        print(core.jit.SHARED_OVERLOAD_IMPLS, k.three(), k.four(), k.many(6), k.five_numpy())
        print([args for name, args in compiled if name == "impl"])
    """)
    # 7 x 3, 7 x 4, 7 x 6, 7 x 5
    assert said == "True 21 28 42 35\n[('int64',), ('int64',)]"


def test_implementations_closing_over_equal_values_of_other_types_stay_apart(tmp_path):
    (tmp_path / "overloaded_for_jit_test.py").write_text(OVERLOADED)
    said = _run(tmp_path, """
        import overloaded_for_jit_test as k
        print(k.units())
    """)
    assert said == "(1, 1.0)"


def _kernels_with_loops_branches_and_reassignments():
    """Small kernels, compiled afresh (no cache): loops, branches, variables assigned more
    than once, an inlined helper, a tuple return."""
    import numpy as np
    from numba import njit as plain

    @plain(inline="always")
    def clamp(x, lo, hi):
        if x < lo:
            x = lo
        elif x > hi:
            x = hi
        return x

    @plain
    def walk(a, t):
        best, k = np.inf, -1
        for i in range(a.shape[0]):
            v = clamp(a[i] * t, -1.0, 1.0)
            if v < best:
                best, k = v, i
            while v > 0.5:
                v -= 0.25
                k += 1
        return best, k

    @plain
    def select(a, n):
        s = 0.0
        for i in range(n):
            x = a[i % a.shape[0]]
            if i % 3 == 0:
                x = -x
            elif i % 3 == 1:
                continue
            s += clamp(x, 0.0, 2.0)
        return s
    a = np.linspace(-2.0, 2.0, 9)
    calls = ((walk, (a, 0.7)), (walk, (a, -1.3)), (select, (a, 20)))
    # compiled, and as Python runs them (the interpreter: an independent check of the code)
    return [(kernel(*args), kernel.py_func(*args)) for kernel, args in calls]


def test_liveness_on_bit_sets_gives_numbas_own_live_sets(monkeypatch):
    """Consistency check against numba's own implementation (a different algorithm's code,
    not ours): every live map numba asks for while compiling these kernels is the same."""
    from numba.core import analysis, ir_utils

    import core.jit as jit
    assert jit.BITSET_LIVE_MAPS
    theirs = analysis.compute_live_map.__wrapped__
    checked = []

    def both(cfg, blocks, use, defs):
        mine = jit._live_map(cfg, blocks, use, defs)
        assert mine == theirs(cfg, blocks, use, defs)
        checked.append(sum(len(v) for v in mine.values()))
        return mine
    monkeypatch.setattr(analysis, "compute_live_map", both)
    monkeypatch.setattr(ir_utils, "compute_live_map", both)
    _kernels_with_loops_branches_and_reassignments()
    assert len(checked) >= 10 and max(checked) > 20


def test_ssa_over_the_blocks_naming_a_variable_gives_numbas_own_ir(monkeypatch):
    """Consistency check against numba's own SSA reconstruction, run on a deep copy of the
    same blocks: the same blocks, statements and fresh names, printed line by line."""
    import copy

    from numba.core import ssa

    import core.jit as jit
    assert jit.SSA_BY_BLOCKS_NAMED
    theirs = ssa._run_ssa.__wrapped__
    rewritten = []

    def text(blocks):
        return [(label, [str(stmt) for stmt in block.body]) for label, block in blocks.items()]

    def both(blocks):
        expected = theirs(copy.deepcopy(blocks))
        mine = jit._ssa_blocks(blocks)
        assert text(mine) == text(expected)
        assert not any(mine[label] is blocks[label] for label in mine)
        rewritten.append(sum("phi(" in line for _, body in text(mine) for line in body))
        return mine
    monkeypatch.setattr(ssa, "_run_ssa", both)
    results = _kernels_with_loops_branches_and_reassignments()
    assert len(rewritten) >= 3 and max(rewritten) >= 2       # phi nodes were placed
    assert all(compiled == interpreted for compiled, interpreted in results), results


def test_compile_flags_read_without_their_properties_are_numbas_values_and_hash():
    """Consistency check against numba's own reading (each option through its property)."""
    from numba.core.compiler import Flags

    import core.jit as jit
    assert jit.QUICK_COMPILE_FLAGS
    plain, set_some = Flags(), Flags()
    set_some.nrt, set_some.error_model, set_some.fastmath = True, "numpy", True
    for flags in (plain, set_some, set_some.copy()):
        expected = {name: getattr(flags, name) for name in flags.options}
        got = flags.values()
        assert got == expected and list(got) == list(expected)
        assert hash(flags) == hash(tuple(sorted(expected)))
    assert set_some == set_some.copy() and set_some != plain
    assert {set_some: 1}[set_some.copy()] == 1


def test_listed_variables_are_numbas_own_in_the_same_order(monkeypatch):
    """Consistency check against numba's ``_rec_list_vars`` (put back for the expected
    lists, so that its recursion is numba's throughout): every statement of a function's IR
    lists the same variables, the same objects in the same order."""
    from numba.core import ir
    from numba.core.compiler import run_frontend

    import core.jit as jit
    assert jit.LISTED_VARS_IN_ONE_LIST

    def kernel(a, n):
        s, t = 0.0, (1, 2)
        for i in range(n):
            s += a[i % 3] * t[i % 2] if i > 1 else -a[0]
        return s, [s, n], {"k": s}
    statements = [stmt for block in run_frontend(kernel).blocks.values() for stmt in block.body]
    mine = [stmt.list_vars() for stmt in statements]
    monkeypatch.setattr(ir.Inst, "_rec_list_vars", jit._rec_list_vars.__wrapped__)
    expected = [stmt.list_vars() for stmt in statements]
    assert [[id(v) for v in vs] for vs in mine] == [[id(v) for v in vs] for vs in expected]
    assert len(statements) > 20 and sum(map(len, mine)) > 20
