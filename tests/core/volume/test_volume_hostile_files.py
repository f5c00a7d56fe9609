"""The volume readers take regular files only, and no header can make them loop or block:
a FIFO, a device, a detached data file that is a FIFO, a line skip of 10^10."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from core.volume.data import VolumeError
from core.volume.readers import read_nifti, read_nrrd, read_raw

NRRD_HEAD = "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n"


@pytest.fixture
def fifo(tmp_path) -> Path:
    path = tmp_path / "pipe.nrrd"
    os.mkfifo(path)
    return path


@pytest.mark.parametrize("read", [lambda p: read_raw(p, (2, 2, 2)), read_nrrd, read_nifti],
                         ids=["raw", "nrrd", "nifti"])
def test_a_fifo_is_refused_before_it_is_opened(fifo, read):
    with pytest.raises(VolumeError, match=r"is a FIFO \(named pipe\): volumes are read from "
                                          r"regular files only"):
        read(fifo)


def test_a_device_is_refused():
    with pytest.raises(VolumeError, match="is a device"):
        read_raw(Path("/dev/zero"), (4, 4, 4))


def test_a_symlink_to_a_device_is_refused(tmp_path):
    link = tmp_path / "zeros.nrrd"
    link.symlink_to("/dev/zero")
    with pytest.raises(VolumeError, match="is a device"):
        read_nrrd(link)


def test_a_detached_data_file_that_is_a_fifo_or_a_device_is_refused(tmp_path):
    os.mkfifo(tmp_path / "data.raw")
    header = tmp_path / "head.nhdr"
    header.write_text(NRRD_HEAD + "data file: data.raw\n\n")
    with pytest.raises(VolumeError, match=r"data file data.raw: is a FIFO"):
        read_nrrd(header)
    header.write_text(NRRD_HEAD + "data file: /dev/zero\n\n")
    with pytest.raises(VolumeError, match=r"data file /dev/zero: is a device"):
        read_nrrd(header)


def test_a_line_skip_beyond_reach_is_refused_at_once(tmp_path):
    path = tmp_path / "skip.nrrd"
    path.write_bytes((NRRD_HEAD + "line skip: 10000000000\n\n").encode() + bytes(8))
    with pytest.raises(VolumeError, match=r"line skip 10000000000 is beyond reach"):
        read_nrrd(path)


def test_a_plain_nrrd_still_reads(tmp_path):
    path = tmp_path / "ok.nrrd"
    path.write_bytes((NRRD_HEAD + "\n").encode() + bytes(range(8)))
    values, spacing = read_nrrd(path)
    assert values.shape == (2, 2, 2) and spacing == (1.0, 1.0, 1.0)
    assert np.array_equal(np.sort(values.ravel()), np.arange(8))


def test_a_very_anisotropic_volume_steps_at_most_max_steps_along_its_diagonal():
    import math
    from core.volume.data import Volume
    from core.renderers.volume.draw import MAX_STEPS, STEP, step_of
    transfer = np.array([[0.0, 1, 1, 1, 0.0], [1.0, 1, 1, 1, 1.0]])
    values = np.zeros((64, 64, 64), np.float32)
    flat = Volume(values=values, spacing=(1e-3, 1e3, 1e3), transfer=transfer)
    diagonal = 63 * math.sqrt(1e-6 + 2e6)
    assert step_of(flat) == pytest.approx(diagonal / MAX_STEPS, rel=1e-12)   # not 0.5e-3
    even = Volume(values=values, spacing=(0.1, 0.1, 0.1), transfer=transfer)
    assert step_of(even) == pytest.approx(STEP * 0.1, rel=1e-12)            # unchanged


def test_metaballs_are_bounded_by_the_samples_they_reach_and_refuse_nan():
    from core.volume import generators
    with pytest.raises(VolumeError, match=r"20,000 balls reach .* samples in all; at most "
                                          r"50,000,000"):
        generators.metaballs(128, [(0.0, 0.0, 0.0, 0.5)] * 20_000)
    for bad in ([(float("nan"), 0, 0, 0.5)], [(0, 0, 0, 1e-300)]):
        with pytest.raises(VolumeError, match="finite numbers within"):
            generators.metaballs(32, bad)
    # many small balls are cheap: each touches only the samples of its own box
    values, _ = generators.metaballs(128, [(x, 0.0, 0.0, 0.05) for x in
                                           np.linspace(-0.9, 0.9, 2000)])
    assert values.max() > 0.9


def test_a_gzip_bomb_is_refused_after_the_bytes_its_sizes_need(tmp_path):
    import gzip
    path = tmp_path / "bomb.nrrd"
    head = NRRD_HEAD.replace("encoding: raw", "encoding: gzip") + "\n"
    path.write_bytes(head.encode() + gzip.compress(bytes(64 * 1024 * 1024), 9))     # 64 MiB
    assert path.stat().st_size < 200_000
    with pytest.raises(VolumeError, match=r"inflates past the 8 bytes its sizes need"):
        read_nrrd(path)
    ok = tmp_path / "ok.nrrd"
    ok.write_bytes(head.encode() + gzip.compress(bytes(range(8))))
    values, _ = read_nrrd(ok)
    assert np.array_equal(np.sort(values.ravel()), np.arange(8))


def test_a_raw_nrrd_longer_than_its_sizes_is_refused(tmp_path):
    path = tmp_path / "long.nrrd"
    path.write_bytes((NRRD_HEAD + "\n").encode() + bytes(8 + 1000))
    with pytest.raises(VolumeError, match=r"is longer than its sizes say"):
        read_nrrd(path)


def test_marching_cubes_refuses_a_surface_past_the_budget_before_building_it(monkeypatch):
    import core.volume.marching as marching
    monkeypatch.setattr(marching, "MAX_TRIANGLES", 1000)
    noise = np.random.default_rng(0).random((32, 32, 32)).astype(np.float32)
    with pytest.raises(VolumeError, match=r"noise: the surface at iso 0.5 crosses .* cell "
                                          r"edges, about .* triangles; at most 1,000"):
        marching.marching_cubes(noise, 0.5, "noise")
    ball = np.fromfunction(lambda i, j, k: (i - 8.0) ** 2 + (j - 8.0) ** 2 + (k - 8.0) ** 2,
                           (17, 17, 17))
    positions, triangles, _ = marching.marching_cubes(ball, 25.0, "ball")   # within it
    assert 0 < len(triangles) <= 1000


def test_a_volume_made_in_code_one_sample_thick_is_refused_as_a_files_would_be():
    # the marcher indexes its cells unsigned (no negative-index checks): a grid one sample
    # thick made in code, past the readers, gets their message instead of being read past
    from core.volume.data import Volume
    with pytest.raises(VolumeError, match=r"thin: dims along x must be a whole number of at "
                                          r"least 2 samples, not 1"):
        Volume(values=np.ones((1, 8, 8), np.float32), name="thin")
