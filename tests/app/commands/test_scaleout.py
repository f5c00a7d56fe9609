"""The bench's scale-out rows (``python -m app bench``, ``python -m app.commands.scaleout``): the
same movie made by the real command in one process and with ``--workers 2``, in fresh
processes; the rows say both times, their CPU, the ratio, what ``--workers`` did, and whether
the frames are identical."""

from __future__ import annotations

import pytest

from tools import need_module

from tests.conftest import ROOT

need_module("av", "the animate extra (pip install 'fvd-viewer[anim]') writes MP4")
pytestmark = pytest.mark.slow


def test_the_rows_compare_one_process_with_workers_on_both_scenes():
    from app.commands.animate import bench_animation, format_animation
    result = bench_animation(size=(40, 32), frames=3, repeats=2)
    rows = result["rows"]
    assert [row["scene"] for row in rows] == ["fountain.toml", "house_flyaround.toml"]
    for row in rows:
        assert row["identical_frames"] and row["identical_movies"]
        assert len(row["one"]["walls"]) == len(row["many"]["walls"]) == 2
        assert row["speedup"] == pytest.approx(row["one"]["median_wall"] / row["many"]["median_wall"])
        assert row["one"]["cpu"] > 0 and row["many"]["cpu"] > 0
    text = format_animation(result)
    assert text.count("animate ") == 2 and "3 frames of 40 x 32, median of 2" in text
    # three tiny frames cannot pay a start: --workers said so, and the row shows it
    assert "not starting a local cluster" in text and "frames identical" in text


def test_the_scenes_are_the_shipped_ones():
    from app.commands.scaleout import SCENES
    assert all((ROOT / scene).is_file() for scene in SCENES)
