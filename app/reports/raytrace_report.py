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
                                          seed=1).replace(shadows="off")
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
    from app.reports.series_report import write as write_series
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


# -- adaptive supersampling (Whitted 1980) beside the regular and jittered grids

ADAPTIVE_SIZE = 96                  # the smallest size measured where the comparison is about
                                    # the picture, not sub-lattice aliasing at the horizon
ADAPTIVE_REFERENCE = 256            # regular samples a pixel of the reference image
ADAPTIVE_RUNS = [("regular", s, None, 0) for s in (1, 4, 16, 64)] + [
    ("jittered", s, None, 0) for s in (4, 16, 64)] + [
    ("adaptive", s, 0.05, 0) for s in (16, 64, 256)] + [
    ("adaptive, split once", s, 0.05, 1) for s in (16, 64, 256)]


def adaptive_rows(size: int = ADAPTIVE_SIZE, progress=print) -> list[dict]:
    """Error against rays cast on the Whitted scene (shadows, mirrors, glass and a checkered
    plane to the horizon): RMSE in 8-bit units against the regular 256-sample image."""
    from core.paths import SCENES_DIR
    from core.raytrace import adaptive
    from core.renderers.raytrace.draw import TraceOptions, prepare, render_image, trace_points
    from core.scene.formats import load_scene
    scene = load_scene(SCENES_DIR / "whitted.toml")
    view, shape = scene.views[0], (size, size)
    options = TraceOptions()
    _, reference, _ = render_image(scene, view, "perspective", shape, options,
                                   samples=ADAPTIVE_REFERENCE)
    reference = 255.0 * np.clip(reference, 0.0, 1.0)
    out = []
    for pattern, samples, threshold, min_levels in ADAPTIVE_RUNS:
        start = time.perf_counter()
        if threshold is None:
            _, raw, stats = render_image(scene, view, "perspective", shape, options,
                                         samples=samples, pattern=pattern, seed=1)
            rays = stats["rays"]["primary"]
        else:
            setup = prepare(scene, view, "perspective", shape, options)
            raw = adaptive.render_adaptive(lambda p: trace_points(setup, p), size, size,
                                           adaptive.levels_for(samples), threshold, min_levels)
            rays = int(setup.counts[0])
        seconds = time.perf_counter() - start
        error = 255.0 * np.clip(raw, 0.0, 1.0) - reference
        row = {"series": pattern, "pattern": pattern, "samples": samples,
               "threshold": threshold if threshold is not None else "",
               "rays": rays, "rays_per_pixel": rays / (size * size), "time_ms": seconds * 1e3,
               "rmse": float(np.sqrt(np.mean(error ** 2))),
               "max_error": float(np.abs(error).max())}
        out.append(row)
        progress(f"  whitted {pattern:20s} {samples:3d} spp {row['rays_per_pixel']:6.2f} rays/px "
                 f"RMSE {row['rmse']:.2f}")
    return out


def write_adaptive(out_dir: Path, size: int = ADAPTIVE_SIZE, progress=print) -> list[Path]:
    from app.reports.series_report import write as write_series
    data = adaptive_rows(size, progress)
    intro = (f"Adaptive supersampling (Whitted 1980: rays at the pixels' corners, a square split "
             f"in four where its corners differ by more than the threshold on 0-1) against the "
             f"regular and jittered grids, on scenes/whitted.toml at {size} x {size}; RMSE and "
             f"max in 8-bit units against the regular {ADAPTIVE_REFERENCE}-sample image. "
             f"\"samples\" is the most a pixel gets; \"split once\" splits every pixel once "
             f"before testing its corners. Below 96 x 96 the checkers beyond the horizon, finer "
             f"than the lattice, fill more of the picture and no threshold finds them (48 and "
             f"64: adaptive stays above the regular 16-sample error; 96 and 128: it reaches it "
             f"with fewer rays; docs/ray-tracing.md).")
    return write_series(out_dir, "raytrace_adaptive", data, intro,
                        [("pattern", "pattern"), ("samples", "samples/pixel (most)"),
                         ("threshold", "threshold"), ("rays_per_pixel", "rays/pixel"),
                         ("rmse", "RMSE"), ("max_error", "max error")],
                        "Whitted scene: error against rays cast", "RMSE against 256 spp",
                        x=("rays_per_pixel", "primary rays per pixel"))
