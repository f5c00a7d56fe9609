"""Hostile use of the command line: --out never destroys what the user owns,
--size says what is wrong, and MemoryError or a closed standard input end in a message."""

from __future__ import annotations

import argparse
import errno
import io
import os
import sys

import pytest

from app import cli
from app.cli_arguments import parse_size
from app.output_files import PNG_SIGNATURE
from core.paths import SCENES_DIR

VIEWS = SCENES_DIR / "house.views"


def run(capsys, *argv) -> tuple[int, str]:
    """``python -m app ARGV`` in process: (exit status, stderr)."""
    try:
        status = cli.main(list(argv))
    except SystemExit as exit_:                  # argparse's own errors
        status = exit_.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return status, err


def render(capsys, source, out, *more) -> tuple[int, str]:
    return run(capsys, "render", str(source), "--size", "16x16", "--out", str(out), *more)


def test_out_equal_to_the_input_is_refused(tmp_path, capsys):
    views = tmp_path / "hv.png"
    views.write_bytes(VIEWS.read_bytes())
    status, err = render(capsys, views, views)
    assert status == 2 and "it is the input" in err
    assert views.read_bytes() == VIEWS.read_bytes()


def test_out_equal_to_the_input_through_a_link_is_refused(tmp_path, capsys):
    views = tmp_path / "hv.png"
    views.write_bytes(VIEWS.read_bytes())
    (tmp_path / "link.png").symlink_to(views)
    os.link(views, tmp_path / "hard.png")
    for source, out in (("link.png", "hv.png"), ("hv.png", "link.png"), ("hard.png", "hv.png")):
        status, err = render(capsys, tmp_path / source, tmp_path / out)
        assert status == 2 and "it is the input" in err
    assert views.read_bytes() == VIEWS.read_bytes()


@pytest.mark.parametrize("name, reason", [
    ("x.jpg", "only PNG is written"), ("x.gif", "only PNG is written"),
    ("x.pdf", "only PNG is written"), ("x.eps", "only PNG is written"),
    ("x", "only PNG is written"), ("missing/x.png", "does not exist (it is not created)"),
    ("folder.png", "it is a folder"),
])
def test_out_is_refused_cleanly(tmp_path, capsys, name, reason):
    (tmp_path / "folder.png").mkdir()
    status, err = render(capsys, VIEWS, tmp_path / name)
    assert status == 2 and reason in err
    assert not (tmp_path / "missing").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.png"]


def test_a_device_is_not_written(tmp_path, capsys):
    (tmp_path / "full.png").symlink_to("/dev/full")
    status, err = render(capsys, VIEWS, tmp_path / "full.png")
    assert status == 2 and "not a regular file" in err


def test_an_existing_file_that_is_not_a_png_is_kept_unless_forced(tmp_path, capsys):
    notes = tmp_path / "notes.png"
    notes.write_text("my notes")
    status, err = render(capsys, VIEWS, notes)
    assert status == 2 and "--force" in err and notes.read_text() == "my notes"
    status, _ = render(capsys, VIEWS, notes, "--force")
    assert status == 0 and notes.read_bytes().startswith(PNG_SIGNATURE)
    status, _ = render(capsys, VIEWS, notes)          # now a PNG: replaced without --force
    assert status == 0


def test_a_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, capsys, monkeypatch):
    out = tmp_path / "old.png"
    status, _ = render(capsys, VIEWS, out)
    before = out.read_bytes()

    def disk_full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    from PIL import Image
    monkeypatch.setattr(Image.Image, "save", disk_full)
    status, err = render(capsys, VIEWS, out)
    assert status == 2 and "No space left on device" in err
    assert out.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["old.png"]


def test_the_written_png_has_ordinary_permissions(tmp_path, capsys):
    out = tmp_path / "a.png"
    assert render(capsys, VIEWS, out)[0] == 0
    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask


@pytest.mark.parametrize("text, reason", [
    ("-5x5", "the width must be at least 1, got -5"),
    ("5x-5", "the height must be at least 1, got -5"),
    ("0x5", "the width must be at least 1, got 0"),
    ("+5x+5", "without a sign"),
    ("1_0x1_0", "ASCII digits"),
    ("\uff15x\uff15", "ASCII digits"),            # fullwidth 5
    ("\u0665x5", "ASCII digits"),                 # Arabic-Indic 5
    ("5x5x5", "ASCII digits"),
    ("9" * 5000 + "x1", "ASCII digits"),
    ("99999x1", "out of range"),
])
def test_size_accepts_ascii_digits_only_and_says_what_is_wrong(text, reason):
    with pytest.raises(argparse.ArgumentTypeError, match=reason):
        parse_size(text)


def test_size_with_a_leading_minus_reaches_the_parser(tmp_path, capsys):
    for argv in (("--size", "-5x5"), ("--size=-5x5",)):
        status, err = run(capsys, "render", str(VIEWS), "--out", str(tmp_path / "a.png"), *argv)
        assert status == 2 and "the width must be at least 1, got -5" in err
        assert "expected one argument" not in err


def test_memory_error_is_a_message(capsys, monkeypatch):
    def exhausted(args):
        raise MemoryError
    monkeypatch.setattr(cli, "_dispatch", exhausted)
    status, err = run(capsys, "render", str(VIEWS), "--out", "x.png")
    assert status == 3 and "out of memory" in err


def test_closed_stdin_is_a_message(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(sys, "stdin", None)
    status, err = render(capsys, "-", tmp_path / "a.png")
    assert status == 2 and "standard input is closed" in err
    stream = io.TextIOWrapper(io.BytesIO(b""))
    stream.close()
    monkeypatch.setattr(sys, "stdin", stream)
    status, err = render(capsys, "-", tmp_path / "a.png")
    assert status == 2 and "standard input is closed" in err


def test_render_from_dev_zero_ends_in_a_message(tmp_path):
    import subprocess
    with open("/dev/zero", "rb") as zero:
        done = subprocess.run([sys.executable, "-m", "app", "render", "-", "--out",
                               str(tmp_path / "a.png")], stdin=zero, capture_output=True,
                              text=True, timeout=120, cwd=str(SCENES_DIR.parent))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "a views input may have at most" in done.stderr


def test_render_time_draws_an_animated_scene_with_its_particles(tmp_path):
    """``render --time T`` on an animated scene draws that moment: the fountain's water is
    there at 3 s, and the still frame (no --time) has only a few such pixels (highlights on the basin)."""
    import subprocess
    import sys

    import numpy as np
    from PIL import Image
    images = {}
    for name, extra in (("still", []), ("moment", ["--time", "3"])):
        out = tmp_path / f"{name}.png"
        done = subprocess.run([sys.executable, "-m", "app", "render", "scenes/fountain.toml",
                               "--size", "120x120", "--out", str(out), *extra],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        images[name] = np.asarray(Image.open(out)).astype(int)
    spray = lambda im: ((im[:, :, 2] > 180) & (im[:, :, 0] > 120)).sum()  # noqa: E731
    assert spray(images["still"]) < 20 and spray(images["moment"]) > 10 * spray(images["still"]) + 100


def test_a_view_only_parallel_can_draw_is_explained_by_every_command(tmp_path, capsys):
    views = tmp_path / "z.views"
    views.write_text("0 0 0\n0 0 1\n0 1 0\n-1 1 -1 1\n0 0 5\n1 0.9999999999999999\n")
    for argv in (("matrices", str(views), "--projection", "perspective"),
                 ("render", str(views), "--projection", "perspective", "--shading", "flat",
                  "--size", "8x8", "--out", str(tmp_path / "p.png"))):
        status, err = run(capsys, *argv)
        assert status == 2 and "z_min = -1 rounds to -1" in err      # one rule: 2
    status, _ = run(capsys, "render", str(views), "--projection", "parallel", "--size", "8x8",
                    "--out", str(tmp_path / "q.png"))
    assert status == 0 and (tmp_path / "q.png").exists()


def test_a_reader_that_goes_away_gets_no_traceback():
    """``python -m app matrices ... | head -c 1``: stdout's reader has gone; the command ends
    with status 1 and says nothing on stderr (Python's own BrokenPipeError traceback, and its
    'Exception ignored' at exit, are what a user used to get)."""
    import subprocess
    from core.paths import ROOT
    read, write = os.pipe()
    os.close(read)                                  # nobody will read: the first write fails
    try:
        done = subprocess.run([sys.executable, "-m", "app", "matrices",
                               str(SCENES_DIR / "torus.toml"), "--view", "1"],
                              stdout=write, stderr=subprocess.PIPE, cwd=ROOT, timeout=120)
    finally:
        os.close(write)
    assert done.returncode == 1
    assert "Traceback" not in done.stderr.decode() and "Broken pipe" not in done.stderr.decode()
