"""``render --scheduler``: a ray-traced frame traced by bands on a Dask cluster is
byte for byte the picture one process traces; ``--workers`` on one machine says why it keeps
the frame in this process; a scene that is not ray traced is not split."""

from __future__ import annotations

import numpy as np
import pytest

from tools import need_module

from app.cli import main
from tests.conftest import ROOT

need_module("distributed", "the animate extra runs frames on Dask workers")


def png(path):
    from PIL import Image
    return np.asarray(Image.open(path))


@pytest.mark.slow
def test_a_frame_traced_by_bands_on_a_cluster_is_the_one_process_picture(tmp_path, capsys):
    from dask.distributed import LocalCluster

    from app.commands.cluster import quiet_dask
    quiet_dask()
    scene = str(ROOT / "scenes" / "whitted.toml")
    common = ["render", scene, "--renderer", "raytrace", "--samples", "4", "--size", "60x44"]
    assert main([*common, "--out", str(tmp_path / "one.png")]) == 0
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        assert main([*common, "--out", str(tmp_path / "split.png"),
                     "--scheduler", cluster.scheduler_address]) == 0
    assert "traced on the cluster at" in capsys.readouterr().out
    one, split = png(tmp_path / "one.png"), png(tmp_path / "split.png")
    assert one.shape == (44, 60, 3) and np.array_equal(one, split)
    assert len(np.unique(one.reshape(-1, 3), axis=0)) > 50        # a real picture


def test_local_workers_say_why_the_frame_stays_here(tmp_path, capsys):
    scene = str(ROOT / "scenes" / "sphere.toml")
    assert main(["render", scene, "--size", "24x24", "--out", str(tmp_path / "z.png"),
                 "--workers", "2"]) == 0
    assert "only ray-traced frames are split across workers" in capsys.readouterr().err
    assert main(["render", scene, "--size", "24x24", "--out", str(tmp_path / "r.png"),
                 "--renderer", "raytrace", "--workers", "2"]) == 0
    assert "cannot beat this process" in capsys.readouterr().err
    assert main(["render", scene, "--size", "24x24", "--out", str(tmp_path / "g.png"),
                 "--renderer", "raytrace", "--scheduler", "garbage"]) == 1
    err = capsys.readouterr().err
    assert err.count("error:") == 1 and "expected a Dask scheduler's address" in err
    assert not (tmp_path / "g.png").exists()


@pytest.mark.slow
def test_local_workers_trace_the_one_process_picture_when_they_have_more_cores(tmp_path, capsys):
    """With one kernel thread here (NUMBA_NUM_THREADS=1), two local single-thread workers have
    more cores than this process: ``render --workers 2`` starts them, traces by bands, and the
    PNG is byte for byte the one this process writes."""
    import os

    import numba
    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip("needs two cores: a local cluster on one cannot have more")
    scene = str(ROOT / "scenes" / "whitted.toml")
    common = ["render", scene, "--renderer", "raytrace", "--samples", "4", "--size", "60x44"]
    assert main([*common, "--out", str(tmp_path / "one.png")]) == 0
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        assert main([*common, "--out", str(tmp_path / "split.png"), "--workers", "2"]) == 0
    finally:
        numba.set_num_threads(before)
    assert "traced by 2 local workers (started in" in capsys.readouterr().out
    assert (tmp_path / "one.png").read_bytes() == (tmp_path / "split.png").read_bytes()


def test_the_local_rule_compares_cores_with_kernel_threads(monkeypatch):
    import numba

    from app.commands import split_render
    monkeypatch.setattr(split_render.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        if numba.get_num_threads() == 2:               # the tracer on both cores: no
            assert "runs on 2 of the 2 cores" in split_render.local_problem(2)
        numba.set_num_threads(1)                       # one kernel thread: two workers win
        assert split_render.local_problem(2) is None
        assert "runs on 1 of the 2 cores" in split_render.local_problem(1)
    finally:
        numba.set_num_threads(before)
