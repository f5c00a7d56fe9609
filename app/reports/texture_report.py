"""The report's texture rows: each filter at 1, 4 and 16 samples a pixel on the grazing floor.

``python -m app report`` calls :func:`write` after its own sweep. The scene is
``scenes/texture_floor.toml`` (view 1, a checkered floor running to the horizon, where
texture aliasing is worst); the reference is the same frame at 256 samples a pixel (16 x 16
regular grid, box-filtered) with bilinear filtering — at that density every filter converges
to the box-filtered texture, so it stands for the exact picture. Each setting's time is the
median of a few frames after one warm-up; RMSE is over the whole frame in 8-bit units.
Writes ``texture_filters.csv``, ``texture_filters.md`` and ``texture_filters.png`` (RMSE
against time, one colour per filter, one marker per sample count).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

from core.texture.modes import FILTERS

SCENE = Path(__file__).resolve().parents[2] / "scenes" / "texture_floor.toml"
SAMPLES = (1, 4, 16)
REFERENCE_SAMPLES = 256


def _frame(scene, settings, repeats: int):
    from core import render
    render(scene, scene.views[0], settings)                    # warm-up (and compile)
    times, frame = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        frame = render(scene, scene.views[0], settings)
        times.append(time.perf_counter() - start)
    return frame.color.astype(np.float64), statistics.median(times)


def rows(size: int = 256, repeats: int = 3, progress=print) -> list[dict]:
    from core.scene.formats import load_scene
    from core.settings import RenderSettings
    scene = load_scene(SCENE)
    base = RenderSettings.for_scene(scene, size=(size, size))
    reference, ref_time = _frame(scene, base.replace(samples=REFERENCE_SAMPLES,
                                                     texture_filter="bilinear"), 1)
    progress(f"texture rows: reference {REFERENCE_SAMPLES} spp in {ref_time:.1f} s")
    out = []
    for name in FILTERS:
        for samples in SAMPLES:
            image, seconds = _frame(scene, base.replace(samples=samples, texture_filter=name),
                                    repeats)
            rmse = float(np.sqrt(np.mean((image - reference) ** 2)))
            out.append({"filter": name, "samples": samples, "time_ms": seconds * 1e3,
                        "rmse": rmse})
            progress(f"  {name:12s} {samples:3d} spp  {seconds * 1e3:8.1f} ms  RMSE {rmse:.2f}")
    return out


def write(out_dir: Path, size: int = 256, progress=print) -> list[Path]:
    from app.reports.series_report import write as write_series
    data = [{"series": r["filter"], **r} for r in rows(size, progress=progress)]
    intro = (f"Texture filters on `scenes/texture_floor.toml` at {size} x {size}, against "
             f"{REFERENCE_SAMPLES} samples a pixel (bilinear); RMSE in 8-bit units.")
    return write_series(out_dir, "texture_filters", data, intro,
                        [("filter", "filter"), ("samples", "samples/pixel"),
                         ("time_ms", "time ms (median)"), ("rmse", "RMSE")],
                        "Grazing checkered floor: filter x samples (o 1, ■ 4, ▲ 16 spp)",
                        "RMSE against 256 spp")
