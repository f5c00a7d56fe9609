"""The error-against-time sweep (core/analysis/accuracy.py) and ``python -m app report``
(app/reports/report.py): the reduced sweep runs once and must show the expected order of errors."""

from __future__ import annotations

import csv
from types import SimpleNamespace

import numpy as np
import pytest

from core.analysis import accuracy
from core.analysis.accuracy import Point


def point(ms, rmse, shading="phong", level=8, samples=1, scene="sphere") -> Point:
    return Point(scene=scene, shading=shading, level=level, samples=samples, triangles=100,
                 ms=ms, frames=3, ms_min=ms, rmse=rmse, max_error=10 * rmse, rmse_inside=rmse / 2,
                 coverage_differs=0.01)


# --- pieces -------------------------------------------------------------------------------

def test_pareto_front_keeps_what_nothing_beats():
    points = [point(10, 5.0), point(20, 6.0), point(30, 2.0), point(40, 2.0), point(50, 1.0),
              point(5, 9.0)]
    front = accuracy.pareto_front(points)
    assert [(p.ms, p.rmse) for p in front] == [(5, 9.0), (10, 5.0), (30, 2.0), (50, 1.0)]
    assert [p.pareto for p in points] == [True, False, True, False, True, True]
    assert accuracy.best_within(points, 35).rmse == 2.0
    assert accuracy.best_within(points, 4) is None


def test_box_filter_and_sample_coverage():
    big = np.zeros((4, 4, 3), np.uint8)
    big[0, 0] = 40                  # one of the four samples of pixel (0, 0)
    big[2:, 2:] = 200               # all four of pixel (1, 1)
    small = accuracy.box_filter(big, 2)
    assert small.shape == (2, 2, 3)
    np.testing.assert_array_equal(small[..., 0], [[10, 0], [0, 200]])
    np.testing.assert_array_equal(accuracy.sample_coverage(big, 2), [[1, 0], [0, 4]])
    np.testing.assert_array_equal(accuracy.box_filter(big, 1), big.astype(float))


def test_analytic_scenes_match_their_exact_shapes():
    scene, shape = accuracy.analytic_scene("sphere", 8)
    assert scene.triangle_count == 4 * 8 * 7 and shape.radius == 1.0
    assert scene.meshes[0].material is shape.material
    scene, shape = accuracy.analytic_scene("torus", 8)
    assert scene.triangle_count == 4 * 8 * 8 and (shape.major, shape.minor) == (1.0, 0.35)
    np.testing.assert_allclose(np.hypot(np.hypot(*scene.meshes[0].positions[:, :2].T) - 1.0,
                                        scene.meshes[0].positions[:, 2]), 0.35)
    with pytest.raises(ValueError):
        accuracy.analytic_scene("teapot", 8)


def test_reference_cache_returns_the_same_image(tmp_path):
    first = accuracy.cached_reference("sphere", 16, 1, cache=tmp_path)
    assert len(list(tmp_path.glob("*.npz"))) == 1
    again = accuracy.cached_reference("sphere", 16, 1, cache=tmp_path)
    np.testing.assert_array_equal(first.rgb, again.rgb)
    np.testing.assert_array_equal(first.coverage, again.coverage)
    assert again.coverage.sum() > 0


# --- the reduced sweep --------------------------------------------------------------------

@pytest.fixture(scope="module")
def quick_points():
    return accuracy.sweep(accuracy.QUICK)


@pytest.mark.slow
def test_quick_sweep_covers_every_setting(quick_points):
    q = accuracy.QUICK
    assert len(quick_points) == len(q.scenes) * len(q.shadings) * len(q.levels) * len(q.samples)
    for p in quick_points:
        assert p.ms >= p.ms_min > 0 and p.frames >= 3 and 0 < p.rmse <= p.max_error <= 255 and 0 <= p.coverage_differs < 0.1
    assert any(p.pareto for p in quick_points)


@pytest.mark.slow
def test_flat_worse_than_gouraud_worse_than_phong(quick_points):
    by = {(p.scene, p.shading, p.level, p.samples): p.rmse for p in quick_points}
    for (scene, shading, level, samples), rmse in by.items():
        if shading == "flat":
            gouraud, phong = by[(scene, "gouraud", level, samples)], by[(scene, "phong", level, samples)]
            assert rmse > gouraud > phong, (scene, level, samples, rmse, gouraud, phong)


@pytest.mark.slow
def test_error_falls_with_tessellation_and_samples(quick_points):
    by = {(p.scene, p.shading, p.level, p.samples): p for p in quick_points}
    levels, samples = accuracy.QUICK.levels, accuracy.QUICK.samples
    for scene in accuracy.QUICK.scenes:
        for shading in accuracy.QUICK.shadings:
            for s in samples:
                errors = [by[(scene, shading, level, s)].rmse for level in levels]
                assert errors == sorted(errors, reverse=True), (scene, shading, s, errors)
                # the silhouette converges too: fewer pixels of wrong coverage
                cover = [by[(scene, shading, level, s)].coverage_differs for level in levels]
                assert cover[-1] < cover[0], (scene, shading, s, cover)
            for level in levels:
                errors = [by[(scene, shading, level, s)].rmse for s in samples]
                assert errors == sorted(errors, reverse=True), (scene, shading, level, errors)


@pytest.mark.slow
def test_report_command_writes_csv_markdown_and_plot(quick_points, tmp_path, monkeypatch, capsys):
    from PIL import Image

    from app.reports import report
    monkeypatch.setattr(accuracy, "sweep", lambda config, progress=None: quick_points)
    assert report.main(SimpleNamespace(out=str(tmp_path / "out"), quick=True)) == 0
    folder = tmp_path / "out"
    with open(folder / "error_vs_time.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(quick_points) and set(rows[0]) == set(accuracy.COLUMNS)
    assert {r["shading"] for r in rows} == set(accuracy.QUICK.shadings)
    text = (folder / "error_vs_time.md").read_text()
    assert text.index("## Reading") < text.index("## Table")
    assert "which setting for a frame-time budget" in text
    assert text.count("\n| sphere |") + text.count("\n| torus |") == len(quick_points)
    image = Image.open(folder / "error_vs_time.png")
    assert image.size[0] > 800 and image.size[1] > 400
    assert "wrote" in capsys.readouterr().out


def test_report_refuses_an_unwritable_folder(tmp_path, capsys):
    from app.reports import report
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    assert report.main(SimpleNamespace(out=str(blocker / "sub"), quick=True)) == 2
    assert "cannot create" in capsys.readouterr().err
