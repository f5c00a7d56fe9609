"""The window's samples per pixel: the path tracer's at rest from its registry entry (256),
the others the scene's, the user's number over both, a refused number said and not taken."""

from __future__ import annotations

from pathlib import Path

from app.session.state import ViewerState

ROOT = Path(__file__).resolve().parents[3]


def test_the_path_tracer_accumulates_to_its_registered_number_unless_the_user_chooses():
    from core.registry import get_renderer
    state = ViewerState.open(ROOT / "scenes" / "cornell_box.toml", size=(32, 32))
    assert state.choices.settings().samples == 1                       # the z-buffer: the scene's
    state.choices.set_renderer("pathtrace")
    assert get_renderer("pathtrace").samples_at_rest == 256
    assert state.choices.settings().samples == 256
    state.dirty = False
    assert state.choices.set_samples(16) and state.dirty and state.choices.settings().samples == 16
    state.choices.set_renderer("zbuffer")
    assert state.choices.settings().samples == 16                  # the user's, for any renderer
    state.dirty = False
    assert not state.choices.set_samples(0) and not state.dirty
    assert state.option_message == ("samples per pixel must be a whole number from 1 to 256, "
                                    "not 0; samples per pixel stay 16")
    assert state.choices.set_samples(None) and state.choices.settings().samples == 1
    assert state.option_message == ""


def test_view_samples_on_the_command_line_reaches_the_state(monkeypatch):
    import app.viewer.launch as launch
    from app.cli import main
    opened = []
    monkeypatch.setattr(launch, "main", lambda scene, size, **kw: opened.append(kw) or 0)
    assert main(["view", str(ROOT / "scenes" / "cornell_box.toml"), "--samples", "64"]) == 0
    assert opened[0]["options"]["samples"] == 64
    state = ViewerState.open(ROOT / "scenes" / "cornell_box.toml", size=(8, 8),
                             **{k: v for k, v in opened[0]["options"].items() if v is not None})
    state.choices.set_renderer("pathtrace")
    assert state.choices.settings().samples == 64


def test_view_help_lists_every_key_and_mouse_action():
    import subprocess
    import sys
    from app.viewer.hands import keys_help
    done = subprocess.run([sys.executable, "-m", "app", "view", "--help"], capture_output=True,
                          text=True, timeout=60, cwd=ROOT)
    assert done.returncode == 0
    for key, what in keys_help():
        assert key in done.stdout and what[:30] in done.stdout.replace("\n", " ")
