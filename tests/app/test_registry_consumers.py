"""A renderer and a shading mode registered in one module (``tests/registry_toys.py``) are
found in every consumer beyond the window (whose keys, menus and title
``tests/app/viewer/test_window_registry.py`` holds): the window's key help, the command
line's choices and help, the bench's list, the warm-up's steps, the pixel inspector and the
plan report."""

from __future__ import annotations

import contextlib
import io

import pytest

from tests.conftest import ROOT


@pytest.fixture
def toys():
    import registry_toys
    registry_toys.register()
    yield registry_toys
    registry_toys.unregister()


def _help(*command) -> str:
    from app.cli import main
    out = io.StringIO()
    with contextlib.redirect_stdout(out), pytest.raises(SystemExit):
        main([*command, "--help"])
    return " ".join(out.getvalue().split())


def test_the_command_line_offers_them(toys):
    from app.cli import main
    for command in ("render", "plan", "inspect"):
        text = _help(command)
        assert "toy-mode" in text, command          # --shading's choices
    render = _help("render")
    assert "toy: Toy" in render and "{zbuffer," in render and ",toy}" in render
    assert "toy" in _help("view")
    animate = _help("animate")                      # checked with the job, named in the help
    assert "| toy (default: zbuffer)" in animate and "| toy-mode" in animate
    with contextlib.redirect_stdout(io.StringIO()):  # parsed, not refused
        assert main(["plan", str(ROOT / "scenes" / "torus.toml"), "--renderer", "toy",
                     "--shading", "toy-mode"]) == 0


def test_the_windows_help_names_their_keys(toys):
    from app.viewer.hands import keys_help
    rows = dict(keys_help())                        # F1 and view --help
    assert rows["w 1 2 3 9"].endswith(", Phong, Toy mode") and rows["x"] == "Toy"
    assert rows["r"] == "Z-buffer / Ray traced"


def test_the_bench_lists_it(toys):
    from app.bench.bench import benched
    assert "toy" in benched() and "toy" in benched("painters")
    assert "toy" not in benched("gi")


def test_the_warm_up_draws_them(toys):
    from app.distribution.warmup_steps import quick, steps
    from core.settings import RenderSettings
    labels = [label for label, _ in steps()]
    assert "toy frame" in labels                    # the renderer's own frame
    assert "toy-mode, perspective, edge rasterizer" in labels
    assert quick(RenderSettings(renderer="toy", samples=4)).samples == 1


def test_the_plan_reports_them(toys):
    from core.plan import plan
    from core.scene.formats import load_scene
    scene = load_scene(ROOT / "scenes" / "torus.toml")
    stages = {s.name: s for s in plan(scene, "perspective", "toy-mode", renderer="toy")}
    assert stages["illuminate pixels"].runs
    assert stages["illuminate pixels"].reason.startswith("Toy mode shading:")
    flat = {s.name: s for s in plan(scene, "perspective", "flat")}
    assert flat["illuminate pixels"].reason == "not Phong shading or Toy mode shading"


def test_the_inspector_takes_its_pixels_apart(toys):
    from core.inspect import inspect_pixel
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    scene = load_scene(ROOT / "scenes" / "torus.toml")
    settings = RenderSettings.for_scene(scene, size=(48, 48), renderer="toy",
                                        shading="toy-mode")
    record = inspect_pixel(scene, scene.views[0], settings, 24, 16)
    assert record["layer"] == "triangle", record["layer"]
    text = repr(record)
    assert "no breakdown" not in text and "'phong'" in text     # Phong's terms at the pixel
