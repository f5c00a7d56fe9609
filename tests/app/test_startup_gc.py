"""app.startup_gc: the collector paused while the program starts, then resumed with what is
alive frozen. Run in a fresh process (pytest's own collector state is left alone)."""

from __future__ import annotations

import subprocess
import sys

from tests.conftest import ROOT


def test_paused_then_resumed_with_the_start_up_frozen():
    code = """
import gc
from app import startup_gc
startup_gc.pause()
paused = gc.isenabled()
kept = [[i] for i in range(1000)]           # objects alive at the resume
startup_gc.resume()
frozen = gc.get_freeze_count()
startup_gc.resume()                          # a second resume changes nothing
print(paused, gc.isenabled(), frozen >= 1000, gc.get_freeze_count() == frozen)
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "True", "True", "True"]


def test_a_command_other_than_the_viewer_collects_once_its_arguments_are_read():
    """``python -m app`` pauses at its first line; ``matrices`` (not the viewer) resumes
    before it runs, so a long command never runs without the collector."""
    code = """
import gc, runpy, sys
import app.cli
seen = []
real = app.cli._dispatch
app.cli._dispatch = lambda args: seen.append(gc.isenabled()) or real(args)
sys.argv = ["app", "matrices", "scenes/house.toml"]
try:
    runpy.run_module("app", run_name="__main__")
except SystemExit:
    pass
print(seen)
"""
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                          text=True, timeout=120)
    assert done.stdout.strip().splitlines()[-1] == "[True]", done.stdout + done.stderr
