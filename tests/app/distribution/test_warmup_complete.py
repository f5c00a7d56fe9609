"""``python -m app warmup`` compiles every kernel a shipped scene's first picture needs.

The README's set-up is: a fresh clone (an empty kernel cache), ``make`` runs the warm-up, then
the tests. This test is collected first (``tests/conftest.py``), before any other test has
compiled anything, and opens every shipped scene in every renderer, shading and texture
filter the way the window does, with a listener on numba's ``numba:compile`` event (raised
only when a kernel is compiled, not when it is loaded from the cache). It must hear nothing:
on CI's fresh clone that is exactly "from an empty cache, the warm-up, then every scene".
On a working copy whose kernels changed since the last ``python -m app warmup``, run that
first.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

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
from app.distribution.warmup_steps import scene_jobs, shipped_scenes
opened = 0
for path in shipped_scenes():
    for label, run in scene_jobs(path, size=(72, 40), every=True):   # not the warm-up's size
        before = len(compiled)
        run()
        opened += 1
        if len(compiled) > before:
            print("compiled while opening", label, compiled[before:], file=sys.stderr)
print(json.dumps({"opened": opened, "compiled": sorted(set(compiled))}))
"""


def test_no_kernel_compiles_after_the_warm_up():
    done = subprocess.run([sys.executable, "-c", _OPEN_ALL], cwd=ROOT, env=dict(os.environ),
                          capture_output=True, text=True, timeout=3600)
    assert done.returncode == 0, done.stderr[-2000:]
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["opened"] >= 3 * 4 * 20              # renderers x shadings x scenes
    assert result["compiled"] == [], (
        "kernels compiled after the warm-up (if you changed kernel code, run `python -m app "
        "warmup` first): " + done.stderr[-4000:])
