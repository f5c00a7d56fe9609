"""``python -m app bench --renderer raytrace``: its rows come out, with Embree's beside ours."""

from __future__ import annotations

import json
import subprocess
import sys

from app.bench import raytrace_bench as bench_module
from tests.conftest import ROOT


def test_raytrace_bench_rows(tmp_path):
    run = subprocess.run([sys.executable, "-m", "app", "bench", "--renderer", "raytrace",
                          "--size", "48x48", "--frames", "1", "--warmup", "0",
                          "--out", str(tmp_path)], cwd=ROOT, capture_output=True, text=True,
                         timeout=900)
    assert run.returncode == 0, run.stderr
    report = json.loads((tmp_path / "bench_raytrace.json").read_text())
    rows = {r["scene"]: r for r in report["rows"]}
    whitted = rows["whitted"]
    assert whitted["primary_rays"] > 0 and whitted["primary_rays_per_s"] > 0
    assert whitted["rays_per_frame"]["reflected"] > 0 and whitted["rays_per_frame"]["refracted"] > 0
    assert whitted["whitted_fps"] > 0
    # the full scan where ../shared has it, else the shipped decimated one (less 6 degenerate)
    assert rows["glass bunny"]["triangles"] == (69451 if bench_module._bunny_file() else 16295)
    if bench_module._bunny_file():
        assert rows["glass bunny"]["embree_rays_per_s"] > 0
        assert rows["glass bunny"]["primary_rays_per_cpu_s_one_thread"] > 0
        assert "ours on one thread, as Embree runs here" in run.stdout
    assert "primary Mray/s" in run.stdout and "Embree" in run.stdout
    spheres = report["spheres"]                      # 10,000 spheres, 100² -> 400² pixels
    assert spheres["spheres"] == 10_000 and spheres["more_rays"] == 400 ** 2 - 100 ** 2
    assert spheres["more_cpu_s"] > 0 and "150,000 more primary rays" in run.stdout
