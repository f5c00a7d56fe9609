"""The window's keys, Render menu and title read the registries: a shading mode or a renderer
registered with a key and a title has them in the window with no line of the window edited."""

from __future__ import annotations

import pytest

from tests.conftest import ROOT


@pytest.fixture
def toys():
    import registry_toys                # tests/registry_toys.py: one module registers both
    registry_toys.register()
    yield
    registry_toys.unregister()


def test_the_built_in_keys_are_as_they_were():
    pytest.importorskip("glfw")
    from app.viewer.keys import char_shortcuts, next_renderer
    shortcuts = char_shortcuts()
    assert {c: shortcuts[c] for c in "pow123"} == {
        "p": ("projection", "perspective"), "o": ("projection", "parallel"),
        "w": ("shading", "wireframe"), "1": ("shading", "flat"),
        "2": ("shading", "gouraud"), "3": ("shading", "phong")}
    assert next_renderer("r", "zbuffer") == "raytrace"
    assert next_renderer("r", "raytrace") == "zbuffer"
    assert next_renderer("r", "radiosity") == "raytrace"
    assert next_renderer("q", "zbuffer") is None


def test_a_registered_mode_and_renderer_have_their_keys_menu_item_and_title(toys):
    pytest.importorskip("glfw")
    from app.session.state import ViewerState
    from app.viewer.keys import char_shortcuts, next_renderer
    from app.viewer.window import window_title
    from core.renderers import renderers
    assert char_shortcuts()["9"] == ("shading", "toy-mode")
    assert next_renderer("x", "zbuffer") == "toy"
    assert [e.key for e in renderers() if e.name == "toy"] == ["X"]    # its Render menu item
    state = ViewerState.open(ROOT / "scenes" / "house.toml", size=(64, 48))
    assert not window_title(state).endswith("drawn")
    state.choices.set_renderer("toy")
    state.choices.set_shading("toy-mode")
    assert window_title(state).endswith(" - toy-mode - toy drawn")
