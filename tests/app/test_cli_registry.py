"""The command line reads the registries: every registered renderer and transparency kind is
a choice of the flags and named in their help."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _help(*command) -> str:
    # Wide enough that argparse wraps no line: it breaks words at hyphens ("depth-" "sort").
    env = {**os.environ, "COLUMNS": "10000"}
    done = subprocess.run([sys.executable, "-m", "app", *command, "--help"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60, env=env)
    assert done.returncode == 0, done.stderr
    return " ".join(done.stdout.split())


def test_every_registered_renderer_and_transparency_kind_is_offered():
    from core.renderers import renderers
    from core.settings import TRANSPARENCIES
    text = _help("render")
    for entry in renderers():
        assert f"{entry.name}: {' '.join((entry.label or entry.description).split())}" in text
    for kind in TRANSPARENCIES:
        assert kind in text
    view = _help("view")
    assert all(entry.name in view for entry in renderers())
