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


def test_a_kernel_compiles_again_when_a_kernel_it_inlines_changes(tmp_path):
    """numba alone checks a cached kernel against its own file; ``twice`` keeps ``step``'s
    code inside it, so after ``step`` changes the cache would still answer with the old
    code. With ``core.jit`` every kernel file under the kernel roots stamps the cache."""
    (tmp_path / "helper_for_jit_test.py").write_text(HELPER.format(step=1))
    (tmp_path / "user_for_jit_test.py").write_text(USER)
    run = f"""
        import core.jit
        core.jit.KERNEL_ROOTS.append(__import__("pathlib").Path({str(tmp_path)!r}))
        import user_for_jit_test as u
        print(u.twice(10))
    """
    assert _run(tmp_path, run) == "12"
    assert _run(tmp_path, run) == "12"                 # from the cache
    (tmp_path / "helper_for_jit_test.py").write_text(HELPER.format(step=5))
    assert _run(tmp_path, run) == "20"                 # not the cached 12


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
