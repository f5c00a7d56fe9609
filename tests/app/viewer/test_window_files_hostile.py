"""The window's own files read as regular files only, within a size: a recent list or a view
file that is a FIFO, a link to /dev/zero, or JSON nested 200,000 deep gives one line and the
window works on."""

from __future__ import annotations

import os

import pytest

from app.viewer.files import RecentFiles
from app.viewer.hands import save_view
from core.camera.view import View

VIEW = View(vrp=(0.0, 0.0, 0.0), vpn=(0.0, 0.0, 1.0), vup=(0.0, 1.0, 0.0),
            window=(-1.0, 1.0, -1.0, 1.0), prp=(0.0, 0.0, 5.0), front=1.0, back=-1.0)


def _fifo(path):
    os.mkfifo(path)
    return path


def _zeros(path):
    path.symlink_to("/dev/zero")
    return path


@pytest.mark.parametrize("make, words", [(_fifo, "is a FIFO (named pipe), not a file"),
                                         (_zeros, "is a device, not a file")])
def test_a_recent_list_that_is_not_a_file_is_ignored_with_one_line(tmp_path, capsys, make,
                                                                   words):
    recent = RecentFiles(make(tmp_path / "recent.json"))
    assert recent.paths == [] and words in recent.warning
    assert capsys.readouterr().err.count("warning:") == 1


def test_a_recent_list_nested_too_deep_is_ignored(tmp_path):
    path = tmp_path / "recent.json"
    path.write_text("[" * 200_000 + "]" * 200_000)
    recent = RecentFiles(path)
    assert recent.paths == [] and "ignored" in recent.warning


def test_a_huge_recent_list_is_not_read(tmp_path):
    path = tmp_path / "recent.json"
    path.write_text('{"recent": ["' + "x" * 100_000 + '"]}')
    recent = RecentFiles(path)
    assert recent.paths == [] and "at most 65,536 are read" in recent.warning


@pytest.mark.parametrize("make, words", [(_fifo, "is a FIFO (named pipe), not a file"),
                                         (_zeros, "is a device, not a file")])
def test_ctrl_s_refuses_a_view_file_that_is_not_a_file(tmp_path, make, words):
    path = make(tmp_path / "saved.views")
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)")):
        save_view(VIEW, path, "test")


def test_ctrl_s_still_appends_to_a_plain_view_file(tmp_path):
    path = tmp_path / "saved.views"
    assert save_view(VIEW, path, "one") == 1 and save_view(VIEW, path, "two") == 2
