"""Shading modes are a registry: a new mode is one module (its Shader) and one registration.

A toy mode, "normal colours" (each pixel (N + 1) / 2 of its interpolated normal, unlit), is
registered here and then chosen everywhere a user chooses a shading: RenderSettings, a scene
file, the plan, the command line and the window's state; the z-buffer draws it. The expected
colours are hand-derived: a cube seen from (+x, +y, +z) shows exactly its +x, +y and +z faces,
whose normals are the axes.
"""

from __future__ import annotations

import numpy as np
import pytest

from core.registry import register_shading, shading_names, unregister_shading
from core.shading.registry import Shader, register_shader
from core.shading.shade import all_vertex_normals

CUBE = """
name = "normal colours cube"
shading = "{shading}"
background = [0, 0, 0]
[[geometry]]
generator = "cube"
closed = true
[[view]]
vrp = [0, 0, 0]
vpn = [1, 0.8, 0.6]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 12]
front = 5
back = -5
"""


def _vertex(s, scene, meshes, weighting) -> None:
    s.vertex_attrs = all_vertex_normals(s, scene, meshes, weighting)


def _pixel(s, vis, triangles, attrs, source, background8, out) -> None:
    covered = vis.tri >= 0
    t = vis.tri[covered]
    b1, b2 = vis.b1[covered][:, None], vis.b2[covered][:, None]
    corners = attrs[triangles[t]]                                  # (P, 3 corners, 3)
    n = (1 - b1 - b2) * corners[:, 0] + b1 * corners[:, 1] + b2 * corners[:, 2]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    out[...] = background8
    out[covered] = np.round((n + 1) / 2 * 255).astype(np.uint8)


@pytest.fixture
def normal_colours():
    register_shader(Shader("normal-colours", _vertex, _pixel, varyings=("normal",), width=3))
    register_shading("normal-colours", __name__, label="Normal colours", normals="vertex")
    yield
    unregister_shading("normal-colours")


def _cube(tmp_path, shading="normal-colours"):
    from core.scene.formats import load_scene
    path = tmp_path / "cube.toml"
    path.write_text(CUBE.format(shading=shading))
    return load_scene(path)


def test_a_registered_mode_is_read_planned_and_drawn(tmp_path, normal_colours):
    from core.plan import plan
    from core.render import render
    from core.settings import RenderSettings
    scene = _cube(tmp_path)                         # the reader takes the new name
    assert scene.shading == "normal-colours"
    stages = {s.name: s.runs for s in plan(scene, "perspective", "normal-colours")}
    assert stages["vertex normals"] and not stages["face normals"]
    assert not any(stages[f"illuminate {w}"] for w in ("faces", "vertices", "pixels"))
    frame = render(scene, scene.views[0], RenderSettings.for_scene(scene, size=(80, 80)))
    colours, counts = np.unique(frame.color.reshape(-1, 3), axis=0, return_counts=True)
    axes = {(255, 128, 128): "+x", (128, 255, 128): "+y", (128, 128, 255): "+z",
            (0, 0, 0): "background"}
    assert {tuple(int(v) for v in c) for c in colours} == set(axes)
    assert counts.min() > 100                      # each face covers a good part of the frame


def test_the_command_line_and_the_window_offer_it(tmp_path, normal_colours):
    from app.cli_arguments import command_parser
    from app.session.state import ViewerState
    path = tmp_path / "cube.toml"
    path.write_text(CUBE.format(shading="flat"))
    args = command_parser("render").parse_args(["render", str(path), "--shading", "normal-colours"])
    assert args.shading == "normal-colours"
    state = ViewerState.open(path, size=(32, 32))
    state.choices.set_shading("normal-colours")
    assert state.choices.settings().shading == "normal-colours"


def test_an_unregistered_name_is_refused_with_the_modes_there_are(tmp_path):
    from core.scene.formats import ReaderError
    from core.settings import RenderSettings
    assert "normal-colours" not in shading_names()
    with pytest.raises(ValueError, match="shading must be one of wireframe, flat, gouraud, "
                                         "phong, depth, not 'normal-colours'"):
        RenderSettings(shading="normal-colours")
    with pytest.raises(ReaderError, match="normal-colours"):
        _cube(tmp_path)
