"""``animate`` under hostile use: no user file lost, one output rule, verified
resumes, options that would be clamped or crash refused in one clean line, a scheduler that
is not one named for what it is not, and a failing frame on workers reported in one line."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from tools import need_module

from app.cli import main
from tests.conftest import ROOT

need_module("av", "the animate extra (pip install 'fvd-viewer[anim]') writes MP4")
need_module("distributed", "the animate extra runs frames on Dask workers")

SCENE = """
name = "output test"
shading = "flat"
[[geometry]]
generator = "cube"
name = "box"
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 8]
front = 4
back = -4
[[view]]
name = "side"
vrp = [0, 0, 0]
vpn = [1, 0, 0]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 8]
front = 4
back = -4
[animation]
duration = 0.5
fps = 8
[[key]]
time = 0
object.box = { rotate = [0, 0, 0] }
[[key]]
time = 0.5
object.box = { rotate = [0, 90, 0] }
"""


@pytest.fixture
def scene_file(tmp_path) -> Path:
    path = tmp_path / "anim.toml"
    path.write_text(SCENE)
    return path


def run(*argv) -> int:
    try:
        return main(["animate", *map(str, argv)])
    except SystemExit as exit:                      # argparse's refusals
        return exit.code


def one_error(capsys) -> str:
    """The captured stderr holds exactly one ``error:`` line and no traceback; returns it."""
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "error:" in line]
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# ---------------------------------------------------------------------- data loss


def test_only_our_own_temporary_frames_are_removed(scene_file, tmp_path):
    out = tmp_path / "seq"
    out.mkdir()
    (out / "notes.tmp").write_text("mine")
    (out / "frame_00001.png.tmp.bak").write_text("mine too")
    (out / "frame_00002.png.tmp").write_bytes(b"half a frame of ours")
    assert run(scene_file, "--out", out, "--size", "24x24") == 0
    assert (out / "notes.tmp").read_text() == "mine"
    assert (out / "frame_00001.png.tmp.bak").read_text() == "mine too"
    assert not (out / "frame_00002.png.tmp").exists()
    assert len(list(out.glob("frame_*.png"))) == 4


def test_a_movie_never_replaces_what_it_did_not_write(scene_file, tmp_path, capsys):
    for name in ("x.gif", "x.mp4"):
        out = tmp_path / name
        out.write_text("my notes")
        assert run(scene_file, "--out", out, "--size", "24x24") == 2
        assert "is not a GIF" in one_error(capsys) or "is not an MP4" in capsys.readouterr().err \
            or out.read_text() == "my notes"
        assert out.read_text() == "my notes"
        assert run(scene_file, "--out", out, "--size", "24x24", "--force") == 0
        assert out.read_bytes()[:3] == b"GIF" if name == "x.gif" else out.read_bytes()[4:8] == b"ftyp"
    # a movie it wrote is replaced without --force (as render replaces a PNG)
    assert run(scene_file, "--out", tmp_path / "x.gif", "--size", "24x24", "--frames", "2") == 0
    from PIL import Image
    with Image.open(tmp_path / "x.gif") as image:
        assert image.n_frames == 2
    capsys.readouterr()
    assert run(scene_file, "--out", tmp_path / "missing" / "x.mp4", "--size", "24x24") == 2
    assert "does not exist (it is not created)" in one_error(capsys)
    assert not (tmp_path / "missing").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.toml", "x.gif", "x.mp4"]


@pytest.mark.parametrize("kind", ["gif", "mp4"])
def test_a_failed_encode_leaves_the_old_movie_and_nothing_else(scene_file, tmp_path, capsys,
                                                                monkeypatch, kind):
    import app.commands.movie_files as movie_files
    out = tmp_path / f"old.{kind}"
    assert run(scene_file, "--out", out, "--size", "24x24") == 0
    before = out.read_bytes()
    if kind == "gif":                                # a GIF is written in one call at the end
        real = movie_files._gif

        def full_disk(paths, temp, *rest):
            real(paths[:2], temp, *rest)             # part of the movie is written, then:
            raise OSError(28, "No space left on device")
        monkeypatch.setattr(movie_files, "_gif", full_disk)
    else:                                            # an MP4 as the frames come
        real = movie_files.Mp4Writer.add

        def full_disk(self, rgb):
            if getattr(self, "added", 0) == 1:       # part of the movie is written, then:
                raise OSError(28, "No space left on device")
            self.added = getattr(self, "added", 0) + 1
            real(self, rgb)
        monkeypatch.setattr(movie_files.Mp4Writer, "add", full_disk)
    capsys.readouterr()
    assert run(scene_file, "--out", out, "--size", "24x24", "--fps", "4") == 1
    assert "No space left on device" in one_error(capsys)
    assert out.read_bytes() == before
    # nothing beside it but the frames, kept for the rerun
    assert {p.name for p in tmp_path.iterdir()} == {"anim.toml", f"old.{kind}", "old.frames"}
    monkeypatch.undo()
    assert run(scene_file, "--out", out, "--size", "24x24", "--fps", "4") == 0
    assert out.read_bytes() != before and not (tmp_path / "old.frames").exists()


def test_resumed_frames_are_verified(scene_file, tmp_path, capsys):
    from PIL import Image
    out = tmp_path / "seq"
    assert run(scene_file, "--out", out, "--size", "24x24") == 0
    good = {p.name: np.asarray(Image.open(p)) for p in out.glob("frame_*.png")}
    (out / "frame_00001.png").write_bytes(b"junk")                               # not a PNG
    Image.new("RGB", (10, 10)).save(out / "frame_00002.png")                    # wrong size
    Image.fromarray(good["frame_00000.png"]).save(out / "frame_00003.png")      # no hash
    capsys.readouterr()
    assert run(scene_file, "--out", out, "--size", "24x24") == 0
    err = capsys.readouterr().err
    assert "frame_00001.png: not a whole PNG" in err and "frame_00002.png: 10x10, not 24x24" in err
    assert "frame_00003.png: not rendered by this job" in err
    assert all(np.array_equal(np.asarray(Image.open(out / n)), a) for n, a in good.items())
    # without our job.json the folder is not taken as ours: its files are not written over
    (out / "job.json").unlink()
    (out / "frame_00001.png").write_bytes(b"someone's file")
    assert run(scene_file, "--out", out, "--size", "24x24") == 2
    assert "frame_00001.png: not a whole PNG" in one_error(capsys)
    assert (out / "frame_00001.png").read_bytes() == b"someone's file"
    assert run(scene_file, "--out", out, "--size", "24x24", "--force") == 0
    assert np.array_equal(np.asarray(Image.open(out / "frame_00001.png")), good["frame_00001.png"])


def test_a_broken_job_record_is_named(scene_file, tmp_path, capsys):
    out = tmp_path / "seq"
    assert run(scene_file, "--out", out, "--size", "24x24") == 0
    (out / "job.json").write_text("{not json")
    capsys.readouterr()
    assert run(scene_file, "--out", out, "--size", "24x24") == 2
    assert f"{out / 'job.json'}: not a job record" in one_error(capsys)


def test_after_the_movie_the_frames_are_removed_or_kept_when_asked(scene_file, tmp_path, capsys):
    assert run(scene_file, "--out", tmp_path / "a.mp4", "--size", "24x24") == 0
    assert not (tmp_path / "a.frames").exists()
    assert run(scene_file, "--out", tmp_path / "b.mp4", "--size", "24x24", "--keep-frames") == 0
    assert "the frames stay in" in capsys.readouterr().err
    assert len(list((tmp_path / "b.frames").glob("frame_*.png"))) == 4


def test_out_dev_full_says_what_is_wrong(scene_file, capsys):
    assert run(scene_file, "--out", "/dev/full", "--size", "24x24") == 2
    assert "it exists and is not a folder" in one_error(capsys)


# ---------------------------------------------------------------------- options


@pytest.mark.parametrize("options, says", [
    (["--frames", "200000"], "from 1 to 100000"),
    (["--fps", "0.0004"], "from 0.001 to 1000"),
    (["--fps", "inf"], "finite"),
    (["--fps", "nan"], "finite"),
    (["--fps", "1e30"], "from 0.001 to 1000"),
    (["--duration", "inf"], "finite"),
    (["--duration", "1e308"], "at most 100000 are rendered"),
    (["--crf", "-5"], "from 0 to 51"),
    (["--retries", "-1"], "from 0 to 100"),
    (["--out-gif-fps", "0.001"], "a GIF frame lasts at most 655.35 s"),
    (["--view", "3"], "--view 3: the file has 2 views"),
    (["--scheduler", "garbage"], "expected a Dask scheduler's address"),
])
def test_refused_options_end_in_one_line(scene_file, tmp_path, capsys, options, says):
    out = tmp_path / "m.mp4"
    if options[0] == "--out-gif-fps":
        options, out = ["--fps", options[1]], tmp_path / "m.gif"
    assert run(scene_file, "--out", out, "--size", "24x24", *options) == 2
    assert says in one_error(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.toml"]


def test_a_gif_says_the_rate_it_stores(scene_file, tmp_path, capsys):
    assert run(scene_file, "--out", tmp_path / "m.gif", "--size", "24x24", "--fps", "60") == 0
    assert "60 fps is written as 0.02 s a frame (50 fps)" in capsys.readouterr().err


def test_view_numbers_are_file_positions(scene_file, tmp_path):
    from PIL import Image
    for k in ("1", "2"):
        assert run(scene_file, "--out", tmp_path / f"v{k}", "--size", "24x24", "--frames", "1",
                   "--view", k) == 0
        assert main(["render", str(scene_file), "--out", str(tmp_path / f"r{k}.png"), "--size",
                     "24x24", "--view", k]) == 0
        assert np.array_equal(np.asarray(Image.open(tmp_path / f"v{k}" / "frame_00000.png")),
                              np.asarray(Image.open(tmp_path / f"r{k}.png")))


def test_animate_warns_like_render(tmp_path, capsys):
    scene = tmp_path / "warn.toml"
    scene.write_text(SCENE.replace('name = "box"', 'name = "box"\nmaterial = { texture = "gone.png" }')
                     .replace("vup = [0, 1, 0]\nwindow = [-2, 2, -2, 2]\nprp = [0, 0, 8]\nfront = 4\nback = -4\n[animation]",
                              "vup = [1, 0, 0]\nwindow = [-2, 2, -2, 2]\nprp = [0, 0, 8]\nfront = 4\nback = -4\n[animation]"))
    assert run(scene, "--out", tmp_path / "seq", "--size", "24x24", "--frames", "1") == 0
    err = capsys.readouterr().err
    assert "warning:" in err and "gone.png" in err
    assert "invalid view:" in err and "view 2" in err


def test_workers_are_capped_by_the_machine(scene_file, tmp_path, capsys):
    assert run(scene_file, "--out", tmp_path / "seq", "--size", "24x24", "--workers", "5000") == 0
    assert f"--workers 5000: using {min(os.cpu_count(), len(os.sched_getaffinity(0)))}" \
        in capsys.readouterr().err


# ---------------------------------------------------------------------- schedulers that are not


def _serve(answer):
    """A TCP server on loopback that runs ``answer(connection)`` for each client."""
    server = socket.create_server(("127.0.0.1", 0))

    def loop():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            threading.Thread(target=answer, args=(conn,), daemon=True).start()

    threading.Thread(target=loop, daemon=True).start()
    return server, f"tcp://127.0.0.1:{server.getsockname()[1]}"


def _silent(conn):
    conn.recv(1)                                  # holds it open, never answers


def _http(conn):
    conn.recv(4096)
    conn.sendall(b"HTTP/1.0 400 Bad Request\r\nContent-Length: 0\r\n\r\n")
    conn.close()


def _huge(conn):
    conn.sendall(b"\xff" * 8)                     # a length of 2^64 - 1 bytes
    conn.recv(1)


@pytest.mark.parametrize("answer, says", [
    (_silent, "is not a Dask scheduler: it accepted the connection but sent no handshake within 1 s"),
    (_http, "is an HTTP server, not a Dask scheduler"),
    (_huge, "is not a Dask scheduler: its first message claims 18446744073709551615 bytes"),
])
def test_a_scheduler_that_is_not_one(scene_file, tmp_path, capsys, monkeypatch, answer, says):
    import app.commands.cluster as cluster
    monkeypatch.setattr(cluster, "HANDSHAKE_TIMEOUT", 1.0)
    server, address = _serve(answer)
    with server:
        assert run(scene_file, "--out", tmp_path / "m.mp4", "--size", "24x24",
                   "--scheduler", address) == 1
    assert says in one_error(capsys)
    assert not (tmp_path / "m.mp4").exists()


def test_nothing_listening_is_said_in_one_line(scene_file, tmp_path, capsys):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]                   # free: nobody listens on it
    assert run(scene_file, "--out", tmp_path / "m.mp4", "--size", "24x24",
               "--scheduler", f"127.0.0.1:{port}") == 1
    assert "cannot reach the Dask scheduler" in one_error(capsys)


# ---------------------------------------------------------------------- a failing frame on workers


@pytest.mark.slow
def test_a_failing_frame_on_workers_is_one_line(tmp_path):
    """Frames whose keyed view turns invalid (F behind B from t = 0.25 on) fail on the
    workers; the user sees one line for them, no Dask traceback (the scene may also be
    refused at load, where its tracks are checked: one line too)."""
    scene = tmp_path / "swap.toml"
    scene.write_text(SCENE.split("[[key]]")[0] + """
[[key]]
time = 0
view = { front = 4, back = -4 }
[[key]]
time = 0.5
view = { front = -4, back = 4 }
""")
    code = ("import app.commands.animate_frames as a; a.CLUSTER_START_SECONDS = 0; "
            "a.idle_cores = lambda since: 8.0; "
            "a.RENDER_WHILE_STARTING = False; from app.cli import main; import sys; "
            f"sys.exit(main(['animate', {str(scene)!r}, '--out', {str(tmp_path / 'm.mp4')!r}, "
            "'--size', '24x24', '--workers', '2', '--retries', '1']))")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          timeout=300, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert done.returncode in (1, 2)
    errors = [line for line in done.stderr.splitlines() if "error" in line.lower()]
    assert len(errors) == 1 and "Traceback" not in done.stderr, done.stderr
    assert "distributed" not in done.stderr, done.stderr
    assert not (tmp_path / "m.mp4").exists()
    if done.returncode == 1:
        assert "failed after 2 tries" in errors[0]


def test_the_mp4_bytes_do_not_depend_on_the_cores(tmp_path):
    """x264's default thread count follows the cores the process may use, and its output
    follows the thread count (measured: 24 busy 320 x 240 frames give other bytes on one core
    than on two). The encoder runs one thread with fixed options: the same frames give the
    same bytes on one core and on all of them, run after run."""
    from app.commands.movie_files import frame_png, write_frame
    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("needs two cores to compare with one")
    rng = np.random.default_rng(7)
    base = rng.integers(0, 256, (240, 320, 3), dtype=np.uint8)
    for k in range(24):
        write_frame(tmp_path, k, frame_png(np.roll(base, 7 * k, axis=1), "h", k))
    code = ("import sys; from pathlib import Path; from app.commands.movie_files import encode; "
            "encode(Path(sys.argv[1]), 24, Path(sys.argv[2]), 24.0)")
    for name, cores in (("one.mp4", {min(os.sched_getaffinity(0))}),
                        ("all.mp4", os.sched_getaffinity(0)), ("again.mp4", None)):
        subprocess.run([sys.executable, "-c", code, str(tmp_path), str(tmp_path / name)],
                       cwd=ROOT, check=True, timeout=300,
                       preexec_fn=(lambda c=cores: os.sched_setaffinity(0, c)) if cores else None)
    data = (tmp_path / "one.mp4").read_bytes()
    assert len(data) > 100_000
    assert data == (tmp_path / "all.mp4").read_bytes() == (tmp_path / "again.mp4").read_bytes()


def test_workers_are_not_started_when_they_cannot_win(scene_file, tmp_path, capsys, monkeypatch):
    """The decision is a prediction from two measurements: a frame's time here, and the cores
    the other processes left idle since the command started."""
    import app.commands.animate_frames as animate_frames
    monkeypatch.setattr(animate_frames, "idle_cores", lambda since: 1.0)
    assert run(scene_file, "--out", tmp_path / "short", "--size", "24x24", "--workers", "2",
               "--frames", "6") == 0
    captured = capsys.readouterr()                  # 2 tiny frames left: shorter than a start
    assert "not starting a local cluster: the remaining 2 frames would take ~1.0 s with 1 " \
           "local worker (~1 s to start, 1.0 idle core measured) against ~0.0 s" in captured.err
    assert "a cluster starts when it promises x1.2, this is x0.0" in captured.err
    assert "in this process (a cluster could not win)" in captured.out
    monkeypatch.setattr(animate_frames, "CLUSTER_START_SECONDS", 0.0)
    monkeypatch.setattr(animate_frames, "idle_cores", lambda since: 0.1)    # others keep the cores
    assert run(scene_file, "--out", tmp_path / "busy", "--size", "24x24", "--workers", "2",
               "--frames", "6") == 0
    captured = capsys.readouterr()
    assert "0.1 idle cores measured" in captured.err
    assert "in this process (a cluster could not win)" in captured.out


def test_the_prediction_behind_the_decision():
    """Hand-derived: 100 frames of 0.1 s are 10 s here; with a 1 s start and one idle core
    the worker joins for the last 9 s of work, adding 0.35 of a core (measured: what a
    second process adds beside this one and its frame writer): 1 + 9 / 1.35 = 7.67 s."""
    import app.commands.animate_frames as animate_frames
    assert animate_frames.WORKER_SHARE == 0.35 and animate_frames.CLUSTER_START_SECONDS == 1.0
    assert animate_frames.predict(100, 0.1, 2, 1.0) == pytest.approx((10.0, 1 + 9 / 1.35))
    assert animate_frames.predict(100, 0.1, 2, 0.5) == pytest.approx((10.0, 1 + 9 / 1.175))
    assert animate_frames.predict(100, 0.1, 4, 1.0) == pytest.approx((10.0, 1 + 9 / 1.35))  # 1 idle core
    assert animate_frames.predict(100, 0.1, 2, 0.0) == pytest.approx((10.0, 10.0))  # no gain
    assert animate_frames._cannot_win(100, 0.1, 2, 1.0) is None                    # x1.30
    assert "~9.3 s with 1 local worker" in animate_frames._cannot_win(100, 0.1, 2, 0.25)  # x1.08
    assert animate_frames._cannot_win(100, 0.1, 2, 0.25).endswith(
        "a cluster starts when it promises x1.2, this is x1.08")          # 10 / 9.28
    assert animate_frames._cannot_win(10, 0.1, 2, 1.0).endswith(
        "against ~1.0 s in this process (on 1.0 cores): a cluster starts when it promises "
        "x1.2, this is x1.00")
    # A process already on 1.5 cores (its kernel threads and frame writer) is 1.5 cores'
    # worth: the same worker on the idle core gives 1 + 9 x 1.5 / 1.35 = 11.0 s, no gain.
    assert animate_frames.predict(100, 0.1, 2, 1.0, 1.5) == pytest.approx((10.0, 1 + 9 * 1.5 / 1.35))
    assert animate_frames.predict(100, 0.1, 2, 1.0, 0.5) == animate_frames.predict(100, 0.1, 2, 1.0)
    assert "~11.0 s with 1 local worker" in animate_frames._cannot_win(100, 0.1, 2, 1.0, 1.5)


def test_runs_are_long_first_and_short_at_the_end():
    """Guided runs: each at most 1/(2 x renderers) of what is left (and MAX_RUN), cut at gaps."""
    from app.commands.animate_frames import Runs
    runs = Runs(list(range(100)), 2)
    lengths = []
    while runs:
        lengths.append(len(runs.next()))
    assert lengths == [25, 19, 14, 11, 8, 6, 5, 3, 3, 2, 1, 1, 1, 1]
    runs = Runs([0, 1, 2, 5, 6, 7, 8], 1)
    assert [runs.next() for _ in range(4)] == [[0, 1, 2], [5, 6], [7], [8]] and not runs


def test_the_idle_cores_are_measured(monkeypatch):
    """Idle seconds of every core over wall seconds: 3 s idle in 2 s is 1.5 idle cores."""
    import app.commands.animate_frames as animate_frames
    monkeypatch.setattr(animate_frames, "idle_mark", lambda: (12.0, 103.0))
    assert animate_frames.idle_cores((10.0, 100.0)) == pytest.approx(1.5)


@pytest.mark.parametrize("hold", [0, 1 << 30])
def test_frames_encoded_as_they_come_make_the_movie_of_the_folder(tmp_path, monkeypatch, hold):
    """The MP4 encoded while frames arrive out of order (held in memory, or read back from
    the folder when not held) is byte for byte the MP4 encoded from the finished folder."""
    from app.commands import movie_files
    from app.commands.movie_files import Movie, encode, frame_png, write_frame
    monkeypatch.setattr(movie_files, "HOLD_BYTES", hold)
    rng = np.random.default_rng(3)
    pictures = [rng.integers(0, 256, (30, 41, 3), dtype=np.uint8) for _ in range(9)]
    folder = tmp_path / "f"
    folder.mkdir()
    write_frame(folder, 0, frame_png(pictures[0], "h", 0))          # resumed from a run before
    movie = Movie(tmp_path / "streamed.mp4", folder, 9, 12.0, done={0})
    for k in (3, 1, 2, 8, 5, 4, 7, 6):                                # as workers return them
        write_frame(folder, k, frame_png(pictures[k], "h", k))
        movie.put(k, pictures[k])
        assert movie.held_bytes <= max(hold, pictures[0].nbytes)
    assert movie.next == 9
    movie.finish()
    encode(folder, 9, tmp_path / "folder.mp4", 12.0)
    streamed = (tmp_path / "streamed.mp4").read_bytes()
    assert len(streamed) > 1000 and streamed == (tmp_path / "folder.mp4").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f", "folder.mp4", "streamed.mp4"]


def test_an_abandoned_movie_leaves_nothing(tmp_path):
    from app.commands.movie_files import Movie
    (tmp_path / "old.mp4").write_bytes(b"....ftyp old")
    movie = Movie(tmp_path / "old.mp4", tmp_path, 3, 12.0)
    movie.put(0, np.zeros((8, 8, 3), np.uint8))
    movie.abandon()
    assert [p.name for p in tmp_path.iterdir()] == ["old.mp4"]
    assert (tmp_path / "old.mp4").read_bytes() == b"....ftyp old"
