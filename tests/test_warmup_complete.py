"""``python -m app warmup`` compiles every kernel a shipped scene's first picture needs (issue 21).

From an empty kernel cache (``NUMBA_CACHE_DIR`` in a temporary directory) one process runs the
warm-up; a second one opens every shipped scene in every renderer, shading and texture filter,
the way the window does, with a listener on numba's ``numba:compile`` event (raised only when
a kernel is compiled, not when it is loaded from the cache). It must hear nothing.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from core.paths import ROOT

_OPEN_ALL = r"""
import json, sys
from numba.core import event
compiled = []
class Listener(event.Listener):
    def on_start(self, ev):
        compiled.append(str(ev.data.get("dispatcher", "?")))
    def on_end(self, ev):
        pass
event.register("numba:compile", Listener())
from app.tools.warmup import scene_jobs, shipped_scenes
opened = 0
for path in shipped_scenes():
    for label, run in scene_jobs(path, size=(72, 40)):    # not the warm-up's size
        before = len(compiled)
        run()
        opened += 1
        if len(compiled) > before:
            print("compiled while opening", label, compiled[before:], file=sys.stderr)
print(json.dumps({"opened": opened, "compiled": sorted(set(compiled))}))
"""


@pytest.mark.slow
def test_no_kernel_compiles_after_the_warm_up(tmp_path):
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "kernels"))
    warm = subprocess.run([sys.executable, "-m", "app", "warmup"], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=3600)
    assert warm.returncode == 0, warm.stderr[-2000:]
    assert any((tmp_path / "kernels").rglob("*.nbi")), "the warm-up cached no kernel"
    done = subprocess.run([sys.executable, "-c", _OPEN_ALL], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=3600)
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["opened"] >= 3 * 4 * 20              # renderers x shadings x scenes
    assert result["compiled"] == [], done.stderr[-4000:]
