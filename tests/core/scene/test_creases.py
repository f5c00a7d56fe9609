"""Normals with a crease angle (core/scene/normals.py ``crease_split``): boxes get
flat faces under Gouraud and Phong, smooth surfaces stay smooth, and the angle is a scene key
and a command-line option."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from core.render import render
from core.scene import generators
from core.scene.formats import ReaderError, load_scene
from core.scene.normals import crease_split, vertex_normals, with_creases
from core.settings import RenderSettings

CUBE_SCENE = """
name = "flat cube"
ambient = [0.2, 0.2, 0.2]
{extra}
[[geometry]]
generator = "cube"
material = {{ ka = 0.3, kd = 0.7, ks = 0.0, od = [0.9, 0.6, 0.3] }}
[[view]]
vrp = [0, 0, 0]
vpn = [1, 0.8, 1.2]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 6]
front = 3
back = -3
[[light]]
direction = [0.3, 1, 0.6]
"""


def _cube_scene(tmp_path, extra: str = "", **load):
    path = tmp_path / "cube.toml"
    path.write_text(CUBE_SCENE.format(extra=extra))
    return load_scene(path, **load)


def test_cube_splits_into_one_vertex_per_face_corner():
    cube = with_creases(generators.cube())
    assert len(cube.positions) == 24 and len(cube.triangles) == 12
    normals = vertex_normals(cube)
    # every vertex's normal is the axis of its face, and each axis has its four corners
    axes, counts = np.unique(np.round(normals, 12), axis=0, return_counts=True)
    assert len(axes) == 6 and np.all(counts == 4)
    assert np.allclose(np.abs(axes).sum(axis=1), 1.0)


def test_smooth_meshes_stay_as_they_are():
    sphere = generators.uv_sphere(segments=8, rings=4)   # 45° a step: still smooth
    bare = type(sphere)(positions=sphere.positions, triangles=sphere.triangles, closed=True)
    assert len(with_creases(bare).positions) == len(sphere.positions)
    torus = generators.torus()
    assert with_creases(torus) is torus                     # normals of its own: untouched


def test_two_faces_folded_at_more_than_the_angle_split():
    # two triangles sharing the edge (0, 1), folded by 50° (hand-made), wound either way
    fold = np.radians(50.0)
    p = np.array([(0, 0, 0), (1, 0, 0), (0.5, 1, 0),
                  (0.5, -np.cos(fold), np.sin(fold))], dtype=np.float64)
    t = np.array([[0, 1, 2], [1, 0, 3]])
    split, origin = crease_split(p, t, angle=45.0)
    assert len(origin) == 6 and list(origin[4:]) == [1, 0]   # both edge vertices doubled
    same, origin = crease_split(p, t, angle=55.0)
    assert len(origin) == 4 and np.array_equal(same, t)
    # an open soup wound inconsistently is compared after orienting: still smooth at 55°
    _, origin = crease_split(p, np.array([[0, 1, 2], [0, 1, 3]]), angle=55.0, closed=False)
    assert len(origin) == 4


@pytest.mark.parametrize("shading", ["gouraud", "phong"])
def test_cube_faces_are_uniform_under_gouraud_and_phong(tmp_path, shading):
    """k_s = 0 and a directional light: each face's interior within 2/255 of flat."""
    scene = _cube_scene(tmp_path)
    settings = RenderSettings.for_scene(scene, size=(120, 120))
    flat = render(scene, scene.views[0], settings.replace(shading="flat")).color.astype(int)
    smooth = render(scene, scene.views[0], settings.replace(shading=shading)).color.astype(int)
    # interior: the pixel and its 8 neighbours have one flat colour (not the background)
    same = np.ones(flat.shape[:2], bool)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            same[1:-1, 1:-1] &= np.all(flat[1 + dy:119 + dy, 1 + dx:119 + dx] == flat[1:-1, 1:-1],
                                       axis=2)
    same[[0, -1], :] = same[:, [0, -1]] = False
    faces = {tuple(c) for c in flat[same]} - {tuple(flat[0, 0])}
    assert len(faces) == 3                                   # three faces seen, each one colour
    interior = same & np.any(flat != flat[0, 0], axis=2)
    assert np.abs(smooth[interior] - flat[interior]).max() <= 2
    # and with the crease angle at 180° the corners are averaged again: not uniform
    blob = _cube_scene(tmp_path, crease_angle=180.0)
    averaged = render(blob, blob.views[0], settings.replace(shading=shading)).color.astype(int)
    assert np.abs(averaged[interior] - flat[interior]).max() > 20


def test_scene_key_and_its_errors(tmp_path):
    assert _cube_scene(tmp_path).crease_angle == 45.0
    keyed = _cube_scene(tmp_path, extra="crease_angle = 180")
    assert keyed.crease_angle == 180.0 and len(keyed.meshes[0].positions) == 8
    # the argument overrides the file
    assert len(_cube_scene(tmp_path, extra="crease_angle = 180", crease_angle=30.0)
               .meshes[0].positions) == 24
    with pytest.raises(ReaderError, match=r"crease_angle: 200 is out of range \[0, 180\]"):
        _cube_scene(tmp_path, extra="crease_angle = 200")
    with pytest.raises(ReaderError, match="crease angle must be from 0 to 180"):
        load_scene(tmp_path / "cube.toml", crease_angle=float("nan"))


def _stl_cube() -> bytes:
    """A binary STL of the cube [0, 1]^3: 12 facets, every corner repeated (as STL does)."""
    cube = generators.cube(size=1.0)
    facets = [struct.pack("<12fH", 0, 0, 0, *cube.positions[t].reshape(-1), 0)
              for t in cube.triangles]
    return b"\0" * 80 + struct.pack("<I", len(facets)) + b"".join(facets)


def test_stl_parts_get_flat_faces(tmp_path):
    path = tmp_path / "box.stl"
    path.write_bytes(_stl_cube())
    mesh = load_scene(path).meshes[0]
    assert len(mesh.positions) == 24                          # merged to 8, split to 24
    axes = np.unique(np.round(vertex_normals(mesh), 12), axis=0)
    assert len(axes) == 6


def test_cli_option(tmp_path):
    from app.cli import main
    path = tmp_path / "cube.toml"
    path.write_text(CUBE_SCENE.format(extra=""))
    out = tmp_path / "cube.png"
    assert main(["render", str(path), "--shading", "gouraud", "--size", "40x40",
                 "--crease-angle", "180", "--out", str(out)]) == 0
    assert out.exists()


def test_the_viewer_takes_the_crease_angle_to_its_reader(tmp_path):
    """``view --crease-angle`` reaches the reader, as ``render``'s does: a bad angle is the
    reader's one-line error (here without a display, where the viewer writes PNGs)."""
    import os
    import subprocess
    import sys
    from core.paths import ROOT
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([sys.executable, "-m", "app", "view", "scenes/cube.toml",
                           "--crease-angle", "-5", "--out", str(tmp_path)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert "the crease angle must be from 0 to 180 degrees, not -5.0" in done.stderr
    done = subprocess.run([sys.executable, "-m", "app", "view", "scenes/cube.toml",
                           "--crease-angle", "90", "--out", str(tmp_path)], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and len(list(tmp_path.glob("cube-view*.png"))) == 3
