"""A clone needs nothing outside itself: every shipped scene opens with nothing beside the
repository. The scenes folder is copied where no ``../shared`` can be found from it
(``tmp_path``), and each scene is opened from the copy, as a user's fresh clone would."""

from __future__ import annotations

import shutil

import pytest

from app.loading import shipped_scenes
from core.paths import SCENES_DIR
from core.scene.formats import load_scene

SHIPPED = [path.name for path in shipped_scenes()]


@pytest.fixture(scope="module")
def lone_scenes(tmp_path_factory):
    clone = tmp_path_factory.mktemp("lone-clone")
    shutil.copytree(SCENES_DIR, clone / "scenes")
    assert not any((folder / "shared").exists() for folder in clone.parents)
    return clone / "scenes"


@pytest.mark.parametrize("name", SHIPPED)
def test_every_shipped_scene_opens_with_nothing_beside_the_clone(lone_scenes, name):
    scene = load_scene(lone_scenes / name)
    assert scene.views and (scene.meshes or scene.triangle_count == 0), name


def test_the_glass_bunny_is_the_shipped_decimated_scan(lone_scenes):
    scene = load_scene(lone_scenes / "glass_bunny.toml")
    bunny, = (mesh for mesh in scene.meshes if mesh.name == "bunny")
    # the file's 16,301 faces less the 6 degenerate ones the reader drops (as from the ASCII)
    assert len(bunny.triangles) == 16_295
    readme = (SCENES_DIR / "stanford-bunny" / "README.md").read_text()
    assert "Stanford 3D Scanning Repository" in readme


def test_no_shipped_file_names_a_path_outside_the_repository():
    for path in SCENES_DIR.rglob("*"):
        if path.suffix in (".toml", ".views", ".tri"):
            assert "../" not in path.read_text(errors="replace"), path.name
