"""The report's ray-traced rows: the Whitted ray tracer on the report's sphere and torus at 1,
4 and 16 samples a pixel, on a regular grid and jittered, against the exact images.

The scenes, lights, views and exact references are the error-against-time sweep's
(:mod:`core.analysis.accuracy`: the analytic surfaces ray-cast exactly at 16 samples a pixel,
box-filtered). The ray tracer traces the level-128 tessellation with its interpolated normals,
shadows off (the z-buffer and the exact reference cast none), so its error is the surface's
tessellation plus the sampling: beside the z-buffer's Phong rows of the main table it shows
what visibility by rays instead of scan conversion changes. Time is the median of a few frames
after one warm-up. Writes ``raytrace.csv``, ``raytrace.md`` and ``raytrace.png``.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

LEVEL = 128
SAMPLES = (1, 4, 16)
PATTERNS = ("regular", "jittered")


def _frame(scene, settings, repeats: int):
    from core import render
    render(scene, scene.views[0], settings)                    # warm-up (and compile)
    times, frame = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        frame = render(scene, scene.views[0], settings)
        times.append(time.perf_counter() - start)
    if frame.message:
        raise ValueError(frame.message)
    return frame.color.astype(np.float64), statistics.median(times)


def rows(size: int, repeats: int = 3, cache=None, progress=print) -> list[dict]:
    from core.analysis import accuracy
    from core.settings import RenderSettings
    out = []
    for name in accuracy.SCENES:
        scene, _ = accuracy.analytic_scene(name, LEVEL)
        reference = accuracy.cached_reference(name, size, accuracy.REFERENCE_SAMPLES,
                                              cache if cache is not None else accuracy.CACHE)
        for pattern in PATTERNS:
            for samples in SAMPLES:
                if pattern == "jittered" and samples == 1:
                    continue                 # one sample is the pixel centre, whatever the pattern
                settings = RenderSettings(shading="phong", size=(size, size), samples=samples,
                                          sample_pattern=pattern, renderer="raytrace",
                                          shadows="off", seed=1)
                image, seconds = _frame(scene, settings, repeats)
                error = image - 255.0 * reference.rgb
                row = {"series": f"{name} {pattern}", "scene": name, "pattern": pattern,
                       "samples": samples, "triangles": int(scene.triangle_count),
                       "time_ms": seconds * 1e3, "rmse": float(np.sqrt(np.mean(error ** 2))),
                       "max_error": float(np.abs(error).max())}
                out.append(row)
                progress(f"  ray traced {name} {pattern:8s} {samples:3d} spp "
                         f"{row['time_ms']:8.1f} ms  RMSE {row['rmse']:.2f}")
    return out


def write(out_dir: Path, size: int, cache=None, progress=print) -> list[Path]:
    from app.tools.series_report import write as write_series
    data = rows(size, cache=cache, progress=progress)
    intro = (f"The Whitted ray tracer (shadows off) on the level-{LEVEL} sphere and torus at "
             f"{size} x {size}, against the exact images (16 samples a pixel); RMSE and max in "
             "8-bit units.")
    return write_series(out_dir, "raytrace", data, intro,
                        [("scene", "scene"), ("pattern", "pattern"),
                         ("samples", "samples/pixel"), ("triangles", "triangles"),
                         ("time_ms", "time ms (median)"), ("rmse", "RMSE"),
                         ("max_error", "max error")],
                        f"Ray traced, level {LEVEL}: pattern x samples (o 1, ■ 4, ▲ 16 spp)",
                        "RMSE against the exact image")
