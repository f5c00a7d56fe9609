"""The report's ray-traced rows (app/reports/raytrace_report.py), on a small frame."""

from __future__ import annotations

import csv


def test_raytrace_rows_converge_with_samples_and_are_written(tmp_path):
    from app.reports import raytrace_report
    paths = raytrace_report.write(tmp_path, size=48, cache=tmp_path / "cache",
                                  progress=lambda line: None)
    assert [p.name for p in paths] == ["raytrace.csv", "raytrace.md", "raytrace.png"]
    rows = list(csv.DictReader(open(paths[0])))
    assert len(rows) == 2 * (3 + 2)                 # 2 scenes x (regular 1/4/16, jittered 4/16)
    for scene in ("sphere", "torus"):
        regular = {int(r["samples"]): float(r["rmse"]) for r in rows
                   if r["scene"] == scene and r["pattern"] == "regular"}
        # more samples a pixel: the jagged silhouette averages out towards the exact image
        assert regular[16] < regular[4] < regular[1], regular
    assert "| sphere | regular | 1 |" in paths[1].read_text()
