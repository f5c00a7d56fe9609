"""The status line's top: the last error or refusal, until the next successful action."""

from __future__ import annotations

from pathlib import Path

from app.session.state import ViewerState

ROOT = Path(__file__).resolve().parents[3]


def test_a_failed_open_is_the_problem_until_the_next_frame_asked_for_is_shown(tmp_path):
    state = ViewerState.open(ROOT / "scenes" / "cube.toml", size=(40, 30))
    assert state.frames.update() and state.messages.problem == ""
    bad = tmp_path / "notes.ply"
    bad.write_text("these are my notes, not a mesh\n")
    assert not state.open_scene(bad)
    assert state.messages.problem.startswith(f"could not open {bad}")
    assert state.messages.problem == state.open_messages[-1]       # the list below keeps it too
    assert not state.frames.update()                              # nothing asked: it stays
    assert state.messages.problem.startswith("could not open")
    state.choices.set_shading("phong")                             # the next successful action
    assert state.frames.update() and state.messages.problem == ""
    assert state.open_messages                             # still listed below, until Esc
    state.messages.clear()
    assert state.open_messages == []


def test_a_renderers_refusal_is_the_problem_in_the_windows_words():
    from core.scene import generators
    state = ViewerState.open(ROOT / "scenes" / "cube.toml", size=(40, 30))
    many = generators.uv_sphere(1.0, 160, 80)              # 25,280 triangles
    many.material = state.scene.meshes[0].material
    state.scene.meshes = [many]
    state.choices.set_renderer("radiosity")
    assert state.frames.update()
    assert "too many for radiosity (at most 20,000)" in state.messages.problem
    assert "Render › Path traced" in state.messages.problem


def test_a_refused_setting_is_the_problem_until_a_good_one():
    state = ViewerState.open(ROOT / "scenes" / "cube.toml", size=(40, 30))
    assert not state.choices.set_samples(1000)
    assert state.messages.problem.startswith("samples per pixel must be")
    assert state.choices.set_samples(4) and state.messages.problem == ""
