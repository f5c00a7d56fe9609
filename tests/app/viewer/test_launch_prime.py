"""The viewer loads its renderer's kernels while the scene loads
(app.viewer.launch.prime_while_loading): the renderer and shading peeked from the file."""

from __future__ import annotations

import logging

from app.viewer.launch import _peeked_settings, prime_while_loading
from tests.conftest import ROOT


def test_the_renderer_and_shading_come_from_the_scene_files_top_level(tmp_path):
    bunny = _peeked_settings(str(ROOT / "scenes" / "glass_bunny.toml"), None)
    assert (bunny.renderer, bunny.shading, bunny.size) == ("raytrace", "phong", (16, 16))
    floor = _peeked_settings(str(ROOT / "scenes" / "texture_floor.toml"), None)
    assert (floor.renderer, floor.shading) == ("zbuffer", "phong")
    # the command line's renderer first
    assert _peeked_settings(str(ROOT / "scenes" / "glass_bunny.toml"), "zbuffer").renderer \
        == "zbuffer"
    plain = tmp_path / "plain.toml"
    plain.write_text('name = "no keys"\n')
    assert (_peeked_settings(str(plain), None).renderer,
            _peeked_settings(str(plain), None).shading) == ("zbuffer", "flat")


def test_nothing_is_primed_for_wireframe_other_files_or_unreadable_ones(tmp_path):
    assert _peeked_settings(str(ROOT / "scenes" / "house.toml"), None) is None   # wireframe
    assert prime_while_loading(str(ROOT / "scenes" / "house.toml"), None) is None
    assert _peeked_settings(str(ROOT / "scenes" / "few_triangles.tri"), None) is None
    broken = tmp_path / "broken.toml"
    broken.write_text("shading = [unclosed\n")
    assert _peeked_settings(str(broken), None) is None
    assert _peeked_settings(str(tmp_path / "missing.toml"), None) is None


def test_a_stand_in_frame_is_drawn_on_a_thread(caplog, monkeypatch):
    """The stand-in is drawn with the peeked settings; a failure is logged, not raised."""
    import app.session.state as state
    drawn = []
    real = state.render
    monkeypatch.setattr(state, "render", lambda scene, view, settings, context:
                        drawn.append(settings) or real(scene, view, settings, context))
    with caplog.at_level(logging.INFO, logger="fvd"):
        thread = prime_while_loading(str(ROOT / "scenes" / "glass_bunny.toml"), None)
        assert thread is not None and thread.name == "prime kernels early"
        thread.join(timeout=120)
    assert not thread.is_alive()
    assert [(s.renderer, s.shading, s.size) for s in drawn] == [("raytrace", "phong", (16, 16))]
    assert "not primed early" not in caplog.text
    monkeypatch.setattr(state, "render", lambda *args: 1 / 0)
    with caplog.at_level(logging.INFO, logger="fvd"):
        thread = prime_while_loading(str(ROOT / "scenes" / "sphere.toml"), None)
        thread.join(timeout=120)
    assert "kernels not primed early: division by zero" in caplog.text


def test_numba_is_imported_before_the_thread_starts():
    """Two threads importing numba at once can meet each other's half-made modules (CI saw
    the viewer exit on "partially initialized module 'numba.core.event'"): in a fresh
    process, numba is already imported when the priming thread starts."""
    import subprocess
    import sys
    code = (
        "import sys, threading\n"
        "seen = []\n"
        "start = threading.Thread.start\n"
        "def spy(self):\n"
        "    seen.append('numba' in sys.modules)\n"
        "    start(self)\n"
        "threading.Thread.start = spy\n"
        "from app.viewer.launch import prime_while_loading\n"
        "before = 'numba' in sys.modules\n"
        f"prime_while_loading({str(ROOT / 'scenes' / 'sphere.toml')!r}, None).join(120)\n"
        "print(before, seen)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[0] == "False [True]"
