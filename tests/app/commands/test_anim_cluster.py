"""``animate --scheduler`` on a real cluster: a ``dask scheduler`` and a ``dask worker`` process
on loopback, the worker started in an empty folder with only the package. The scene names a
mesh file and a texture in the user's folder, which is gone before the first frame is dealt:
the worker can only have them from the job (content-addressed bundle). A run that fails once
on the worker is retried by Dask, and the movie's frames are those of one process."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tools import need_module

from app.cli import main
from tests.conftest import ROOT

need_module("distributed", "the animate extra runs frames on Dask workers")
pytestmark = pytest.mark.slow

SCENE = """
name = "shipped"
shading = "gouraud"
background = [0.1, 0.1, 0.15]
[[geometry]]
file = "meshes/box.obj"
name = "box"
material = { ka = 0.4, kd = 0.6, od = [1, 1, 1], texture = "maps/noise.png" }
[[light]]
position = [3, 4, 5]
[[view]]
vrp = [0, 0, 0]
vpn = [0.4, 0.3, 1]
vup = [0, 1, 0]
window = [-1.5, 1.5, -1.5, 1.5]
prp = [0, 0, 6]
front = 3
back = -3
[animation]
duration = 0.5
fps = 8
[[key]]
time = 0
object.box = { rotate = [0, 0, 0] }
[[key]]
time = 0.5
object.box = { rotate = [0, 60, 0] }
[[emitter]]
shape = "sphere"
radius = 0.9
rate = 40
speed = 0.5
lifetime = 0.3
size = 0.04
color = [1, 0.8, 0.3]
"""

# A unit cube with texture coordinates on every face (v, vt, f v/vt).
BOX = "\n".join(
    [f"v {x} {y} {z}" for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    + ["vt 0 0", "vt 1 0", "vt 1 1", "vt 0 1"]
    + [f"f {a}/1 {b}/2 {c}/3 {d}/4" for a, b, c, d in
       ((1, 5, 7, 3), (2, 4, 8, 6), (1, 2, 6, 5), (3, 7, 8, 4), (1, 3, 4, 2), (5, 6, 8, 7))]) + "\n"


def user_folder(root: Path) -> Path:
    from PIL import Image
    folder = root / "user"
    (folder / "meshes").mkdir(parents=True)
    (folder / "maps").mkdir()
    (folder / "scene.toml").write_text(SCENE)
    (folder / "meshes" / "box.obj").write_text(BOX)
    noise = np.random.default_rng(4).integers(0, 256, (16, 16, 3), dtype=np.uint8)
    Image.fromarray(noise).save(folder / "maps" / "noise.png")
    return folder


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """``(address, worker's temporary folder)`` of a scheduler and one worker on loopback."""
    root = tmp_path_factory.mktemp("cluster")
    empty, worker_tmp = root / "empty", root / "worker-tmp"
    empty.mkdir()
    worker_tmp.mkdir()
    dask = str(Path(sys.executable).with_name("dask"))
    env = {**os.environ, "PYTHONPATH": str(ROOT), "DASK_LOGGING__DISTRIBUTED": "error"}
    scheduler_file = root / "scheduler.json"
    scheduler = subprocess.Popen([dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
                                  "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                                 cwd=root, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    processes = [scheduler]
    try:
        deadline = time.monotonic() + 120
        address = None
        while address is None and time.monotonic() < deadline:
            try:                      # dask writes the file in more than one step: until whole
                address = json.loads(scheduler_file.read_text())["address"]
            except (OSError, ValueError, KeyError):
                time.sleep(0.1)
        assert address is not None, "the dask scheduler wrote no address in 120 s"
        worker = subprocess.Popen([dask, "worker", address, "--nthreads", "1", "--nworkers", "1",
                                   "--no-dashboard", "--local-directory", str(worker_tmp)],
                                  cwd=empty, env={**env, "TMPDIR": str(worker_tmp)},
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        processes.append(worker)
        from dask.distributed import Client
        with Client(address, timeout=120) as client:
            client.wait_for_workers(1, timeout=120)
        yield address, worker_tmp, empty
    finally:
        for process in reversed(processes):
            process.terminate()
            process.wait(timeout=60)


def frames(folder: Path) -> list[np.ndarray]:
    from PIL import Image
    return [np.asarray(Image.open(p)) for p in sorted(folder.glob("frame_*.png"))]


def fail_once(marker: str):
    """``render_run`` that fails the first time a worker runs it (it takes the marker file).
    Everything it uses is inside it: pytest's name for this module is not importable on the
    cluster, and a nested function is pickled by value."""
    def run(job, bundle, frames_, checkpoint=None):
        import os

        from app.commands.animate_frames import render_run
        try:
            os.unlink(marker)
        except FileNotFoundError:
            return render_run(job, bundle, frames_, checkpoint)
        raise MemoryError("the worker was busy")
    return run


def test_a_worker_in_an_empty_folder_renders_shipped_files(cluster, tmp_path, monkeypatch, capsys):
    import app.commands.animate_frames as animate_frames
    address, worker_tmp, empty = cluster
    user = user_folder(tmp_path)
    here = tmp_path / "here"
    assert main(["animate", str(user / "scene.toml"), "--out", str(here), "--size", "40x40"]) == 0
    real = animate_frames.render_on_cluster

    def user_files_gone(*args, **kwargs):
        shutil.rmtree(user)                    # loaded here; the worker must use the bundle
        return real(*args, **kwargs)

    monkeypatch.setattr(animate_frames, "render_on_cluster", user_files_gone)
    there = tmp_path / "there"
    assert main(["animate", str(user / "scene.toml"), "--out", str(there), "--size", "40x40",
                 "--scheduler", address]) == 0
    assert "on the cluster at" in capsys.readouterr().out
    assert not user.exists() and list(empty.iterdir()) == []
    a, b = frames(here), frames(there)
    assert len(a) == len(b) == 4 and all(np.array_equal(x, y) for x, y in zip(a, b))
    # the worker unpacked the scene, the mesh and the texture under their hash's folder
    for name in ("scene.toml", "meshes/box.obj", "maps/noise.png"):
        assert len(list(worker_tmp.glob(f"fvd-bundles-*/*/{name}"))) == 1, name
    # the texture is drawn: its noise shows on the box (a flat colour would have few values)
    assert len(np.unique(b[0].reshape(-1, 3), axis=0)) > 12        # untextured: at most 7


def test_dask_retries_a_run_that_failed_on_the_worker(cluster, tmp_path, monkeypatch, capsys):
    import app.commands.animate_frames as animate_frames
    address, _, _ = cluster
    user = user_folder(tmp_path)
    marker = tmp_path / "fail-once"
    marker.write_text("")
    monkeypatch.setattr(animate_frames, "render_run", fail_once(str(marker)))
    out = tmp_path / "m"
    assert main(["animate", str(user / "scene.toml"), "--out", str(out), "--size", "32x32",
                 "--scheduler", address, "--retries", "1"]) == 0
    assert not marker.exists()                 # it failed once on the worker ...
    assert len(frames(out)) == 4               # ... and Dask ran it again
    capsys.readouterr()
    marker.write_text("")
    again = tmp_path / "n"
    assert main(["animate", str(user / "scene.toml"), "--out", str(again), "--size", "32x32",
                 "--scheduler", address, "--retries", "0"]) == 1
    err = capsys.readouterr().err
    assert "failed after 1 tries" in err and "the worker was busy" in err and "Traceback" not in err
