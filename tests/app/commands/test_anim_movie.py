"""``python -m app animate``: one process against a local Dask cluster, resuming a killed run,
retrying a failed frame, and the three output kinds."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tools import need_module

from app.cli import main
from tests.conftest import ROOT

need_module("av", "the animate extra (pip install 'fvd-viewer[anim]') writes MP4")
need_module("distributed", "the animate extra runs frames on Dask workers")

SCENE = """
name = "movie test"
shading = "gouraud"
background = [0.05, 0.05, 0.1]
[[geometry]]
generator = "uv_sphere"
params = { radius = 0.6, segments = 16, rings = 8 }
name = "ball"
[[view]]
vrp = [0, 0, 0]
vpn = [0, 0, 1]
vup = [0, 1, 0]
window = [-2, 2, -2, 2]
prp = [0, 0, 8]
front = 4
back = -4
[animation]
duration = 1.0
fps = 12
seed = 3
[[key]]
time = 0
view = { vpn = [0, 0, 1], vup = [0, 1, 0] }
object.ball = { translate = [-0.5, 0, 0] }
[[key]]
time = 1
view = { vpn = [1, 0.5, 1], vup = [0, 1, 0] }
object.ball = { translate = [0.5, 0, 0] }
[[emitter]]
shape = "sphere"
radius = 0.7
rate = 300
rate_var = 50
speed = 1.5
speed_var = 0.3
lifetime = 0.6
size = 0.05
color = [1, 0.6, 0.2]
alpha = 0.8
alpha_end = 0.0
"""


@pytest.fixture
def scene_file(tmp_path) -> Path:
    path = tmp_path / "movie.toml"
    path.write_text(SCENE)
    return path


def frames(folder: Path) -> list[np.ndarray]:
    from PIL import Image
    return [np.asarray(Image.open(p)) for p in sorted(folder.glob("frame_*.png"))]


def decoded(movie: Path) -> list[np.ndarray]:
    import av
    with av.open(str(movie)) as container:
        return [f.to_ndarray(format="rgb24") for f in container.decode(video=0)]


@pytest.fixture
def on_the_cluster(monkeypatch):
    """A short job on --workers 2 (or any on a busy machine) would be kept in this process
    (a cluster cannot win); these tests want frames rendered by the local cluster's worker."""
    import app.commands.animate_frames as animate_frames
    monkeypatch.setattr(animate_frames, "CLUSTER_START_SECONDS", 0.0)
    monkeypatch.setattr(animate_frames, "idle_cores", lambda since: 8.0)
    monkeypatch.setattr(animate_frames, "RENDER_WHILE_STARTING", False)
    # The prediction also uses the cores this process was measured to keep busy while timing
    # a frame; on a loaded machine that measure once said "could not win" (12 tiny frames).
    # The decision has tests of its own (predict, _cannot_win): here the cluster must run.
    monkeypatch.setattr(animate_frames, "_cannot_win", lambda *args, **kwargs: None)


def test_two_local_workers_give_the_single_process_movie(scene_file, tmp_path, on_the_cluster,
                                                         capsys):
    one, two = tmp_path / "one.mp4", tmp_path / "two.mp4"
    assert main(["animate", str(scene_file), "--out", str(one), "--size", "48x40",
                 "--keep-frames"]) == 0
    assert main(["animate", str(scene_file), "--out", str(two), "--size", "48x40",
                 "--workers", "2", "--keep-frames"]) == 0
    assert "this process and 1 local worker, started once in" in capsys.readouterr().out
    a, b = frames(tmp_path / "one.frames"), frames(tmp_path / "two.frames")
    assert len(a) == len(b) == 12
    assert all(np.array_equal(x, y) for x, y in zip(a, b))       # the same pictures, exactly
    # (not the same bytes: x264 was seen, rarely, to code the same frames differently)
    assert all(np.abs(m.astype(int) - x.astype(int)).mean() < 8 for m, x in zip(decoded(two), b))
    movie = decoded(one)
    assert len(movie) == 12 and movie[0].shape == (40, 48, 3)
    # H.264 is lossy, but near: the frames are the pictures we rendered
    assert np.abs(movie[5].astype(int) - a[5].astype(int)).mean() < 8      # 5.8 here
    assert not np.array_equal(a[0], a[11])                       # and it does move


def test_a_killed_run_resumed_completes(scene_file, tmp_path):
    out = tmp_path / "killed.mp4"
    folder = tmp_path / "killed.frames"
    command = [sys.executable, "-m", "app", "animate", str(scene_file), "--out", str(out),
               "--size", "96x96", "--duration", "5"]                # 60 frames
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.Popen(command, cwd=ROOT, env=env, stdout=subprocess.DEVNULL,
                           stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 600           # a loaded machine loads the kernels slowly
    while len(list(folder.glob("frame_*.png"))) < 3 and time.monotonic() < deadline:
        assert run.poll() is None, "the run ended before it could be killed"
        time.sleep(0.01)
    run.send_signal(signal.SIGKILL)
    run.wait()
    done_before = len(list(folder.glob("frame_*.png")))
    assert 3 <= done_before < 60 and not out.exists(), done_before
    # resumed keeping its frames (not part of the job: it resumes the same run), to compare them
    resumed = subprocess.run(command + ["--keep-frames"], cwd=ROOT, env=env,
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert f"{done_before} of 60 frames already in" in resumed.stderr
    assert len(decoded(out)) == 60
    # the resumed run's pictures are those of a clean run, exactly (compared as pictures, not
    # as H.264: x264 was seen, rarely, to code the same frames a little differently)
    clean = tmp_path / "clean"
    assert main(["animate", str(scene_file), "--out", str(clean), "--size", "96x96",
                 "--duration", "5"]) == 0
    kept, pictures = frames(folder), frames(clean)
    assert len(kept) == len(pictures) == 60
    differ = [(k, int(np.abs(x.astype(int) - y).max()), int(np.count_nonzero(x != y)))
              for k, (x, y) in enumerate(zip(kept, pictures)) if not np.array_equal(x, y)]
    # (frame, largest difference, values different): which frames a failure is about
    assert differ == [], (f"killed after {done_before} frames", differ)


def test_a_failed_frame_is_retried_not_the_movie(scene_file, tmp_path, monkeypatch, capsys):
    import app.commands.animate_frames as animate_frames
    real, calls = animate_frames.render_pixels, []

    def flaky(job, k, *rest):
        calls.append(k)
        if k == 4 and calls.count(4) == 1:
            raise MemoryError("the machine was busy")
        return real(job, k, *rest)

    monkeypatch.setattr(animate_frames, "render_pixels", flaky)
    out = tmp_path / "seq"
    assert main(["animate", str(scene_file), "--out", str(out), "--size", "32x32"]) == 0
    assert calls.count(4) == 2 and all(calls.count(k) == 1 for k in range(12) if k != 4)
    assert len(frames(out)) == 12


def test_gif_and_frames_and_refusals(scene_file, tmp_path, capsys):
    from PIL import Image
    gif = tmp_path / "loop.gif"
    assert main(["animate", str(scene_file), "--out", str(gif), "--size", "40x30", "--frames", "6",
                 "--keep-frames"]) == 0
    with Image.open(gif) as image:
        assert image.n_frames == 6 and image.size == (40, 30)
    # the same folder with other settings is refused rather than mixed
    assert main(["animate", str(scene_file), "--out", str(gif), "--size", "40x32", "--frames", "6"]) == 2
    assert "other settings" in capsys.readouterr().err
    scene_file.write_text(SCENE.replace("rate = 300", "rate = 200"))     # an edited scene too
    assert main(["animate", str(scene_file), "--out", str(gif), "--size", "40x30", "--frames", "6"]) == 2
    assert "other settings" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(SCENE.replace("rate = 300", "rate = 'many'"))
    assert main(["animate", str(bad), "--out", str(tmp_path / "x.mp4")]) == 2
    assert "emitter[1].rate: expected a number" in capsys.readouterr().err


def test_frames_are_written_beside_the_rendering_and_a_failed_write_stops_the_command(
        scene_file, tmp_path, monkeypatch, capsys):
    """The PNGs and the movie are made on the frame writer's thread, in frame order; a write
    that fails (a full disk) is the command's error, said once, not a frame to retry."""
    import threading

    import app.commands.animate as animate
    real, written = animate.write_frame, []

    def recording(folder, k, data):
        written.append((k, threading.current_thread().name))
        real(folder, k, data)
    monkeypatch.setattr(animate, "write_frame", recording)
    out = tmp_path / "seq"
    assert main(["animate", str(scene_file), "--out", str(out), "--size", "32x32"]) == 0
    assert written == [(k, "frame writer") for k in range(12)]
    assert len(frames(out)) == 12
    written.clear()

    def full(folder, k, data):
        written.append(k)
        if k == 5:
            raise OSError(28, "No space left on device")
        real(folder, k, data)
    monkeypatch.setattr(animate, "write_frame", full)
    assert main(["animate", str(scene_file), "--out", str(tmp_path / "full"),
                 "--size", "32x32"]) == 1
    err = capsys.readouterr().err
    assert "No space left on device" in err and err.count("No space left") == 1
    assert written == [0, 1, 2, 3, 4, 5]                 # nothing written after the failure
    assert len(frames(tmp_path / "full")) == 5           # what was written stays: resumable
