"""The window's own file dialog without a window (app.viewer.path_dialog.PathChooser): it
lists a folder, walks into folders and up, and refuses in one line a name with a line break,
a folder it cannot write into, a file that is not there."""

from __future__ import annotations

from app.viewer.path_dialog import PathChooser


def test_it_lists_folders_first_then_the_files_it_is_for(tmp_path):
    (tmp_path / "b.views").write_text("")
    (tmp_path / "a.png").write_bytes(b"")
    (tmp_path / "notes.txt").write_text("")
    (tmp_path / "sub").mkdir()
    chooser = PathChooser("save view", save=True, folder=tmp_path, suffixes=(".views",))
    assert chooser.entries() == (["sub"], ["b.views"], 0)
    everything = PathChooser("open", save=False, folder=tmp_path)
    assert everything.entries() == (["sub"], ["a.png", "b.views", "notes.txt"], 0)
    chooser.enter("sub")
    assert chooser.folder == (tmp_path / "sub").resolve() and chooser.entries() == ([], [], 0)
    chooser.enter("..")
    assert chooser.folder == tmp_path.resolve()


def test_saving_takes_a_new_name_in_a_folder_it_can_write(tmp_path):
    chooser = PathChooser("save screenshot", save=True, folder=tmp_path)
    chooser.name = "shot.png"
    assert chooser.chosen() == tmp_path / "shot.png" and chooser.message == ""
    chooser.name = "two\nlines.png"
    assert chooser.chosen() is None
    assert chooser.message == "a file name cannot hold a line break or a NUL"


def test_saving_into_a_folder_that_is_not_there_is_refused(tmp_path):
    chooser = PathChooser("save view", save=True, folder=tmp_path)
    chooser.name = "gone/saved.views"
    assert chooser.chosen() is None and chooser.message == f"cannot write into {tmp_path / 'gone'}"


def test_opening_a_file_that_vanished_is_refused_and_the_dialog_stays(tmp_path):
    scene = tmp_path / "scene.toml"
    scene.write_text("")
    chooser = PathChooser("open", save=False, folder=tmp_path)
    chooser.name = "scene.toml"
    assert chooser.chosen() == scene
    scene.unlink()
    assert chooser.chosen() is None and chooser.message == f"{scene}: no such file"
    chooser.name = ""
    assert chooser.chosen() is None and chooser.message == "type a file name or pick one"


def test_a_folder_it_cannot_list_is_said(tmp_path):
    chooser = PathChooser("open", save=False, folder=tmp_path / "missing")
    assert chooser.entries() == ([], [], 0)
    assert chooser.message.startswith(f"cannot list {tmp_path / 'missing'}")
