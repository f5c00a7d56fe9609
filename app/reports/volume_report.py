"""The report's volume rows: the ray marcher's error against its step, and against time.

``python -m app report`` calls :func:`write` after its own sweep. Two series, each at steps
of 2, 1, 1/2 and 1/4 of a sample (the renderer's default is 1/2):

- **sphere, exact**: a homogeneous sphere (σ = 2, grey emission 0.8, radius 0.8 on 97
  samples a side) seen along an axis, against the closed form ``c (1 − e^{−σ·chord})`` at the
  pixels more than three samples inside its silhouette (where the data is the sphere; see
  ``docs/volume.md``);
- **phantom, lit**: the Shepp–Logan phantom (96³) with the shipped transfer function and
  gradient shading, against the same rays at 1/16 of a sample.

RMSE and the largest error are in 8-bit units over those pixels; time is the median of three
marches of the frame's rays. Writes ``volume_steps.csv``, ``.md`` and ``.png``.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

STEPS = (2.0, 1.0, 0.5, 0.25)
REFERENCE_STEP = 1 / 16
SIZE = 128


def _march(volume, rays, fraction, repeats=3):
    from core.shading.illumination import pack_lights
    from core.scene.model import Light
    from core.volume.raymarch import march_volume
    from core.renderers.volume.draw import step_of
    lights = pack_lights([Light(position=(4.0, 5.0, 6.0))])
    times, result = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        result = march_volume(volume, *rays, step_of(volume) * fraction / 0.5, lights,
                              np.full(3, 0.3), np.array([1.0, 0.0, 0.0, 6.0]))
        times.append(time.perf_counter() - start)
    return result[0][:, 0] * 255.0, 1e3 * statistics.median(times)


def _cases():
    from core.camera.rays import camera_rays
    from core.camera.view import View
    from core.volume import generators
    from core.volume.data import Volume
    view = View(vrp=(0, 0, 0), vpn=(0, 0, 1), vup=(0, 1, 0), window=(-1, 1, -1, 1),
                prp=(0, 0, 6), front=2, back=-2, label="report view")
    rays = camera_rays(view, "perspective", SIZE, SIZE)
    sigma, c, r = 2.0, 0.8, 0.8
    values, spacing = generators.sphere(97, radius=r, density=sigma)
    sphere = Volume(values=values, spacing=spacing, lighting="none",
                    transfer=np.array([[0.0, c, c, c, 0.0], [sigma, c, c, c, sigma]]))
    # the exact chord of each ray through the sphere about the origin (|d| = 1)
    o, d = rays[0], rays[1]
    along = -(o * d).sum(1)
    miss2 = (o * o).sum(1) - along ** 2
    chord = 2 * np.sqrt(np.clip(r * r - miss2, 0.0, None))
    inside = np.sqrt(miss2) < r - 3 * spacing[0]
    exact = 255.0 * c * (1 - np.exp(-sigma * chord))
    from app.bench.volume_bench import TRANSFER
    head, head_spacing = generators.shepp_logan(96)
    phantom = Volume(values=head, spacing=head_spacing, transfer=TRANSFER)
    return [("sphere, exact", sphere, rays, lambda: (exact, inside)),
            ("phantom, lit", phantom, rays,
             lambda: (_march(phantom, rays, REFERENCE_STEP, 1)[0], np.ones(len(o), bool)))]


def rows(progress=print) -> list[dict]:
    out = []
    for series, volume, rays, reference in _cases():
        truth, where = reference()
        for fraction in STEPS:
            progress(f"volume: {series}, step {fraction} of a sample ...")
            found, ms = _march(volume, rays, fraction)
            error = np.abs(found - truth)[where]
            out.append({"series": series, "samples": 1, "step": fraction, "time_ms": ms,
                        "rmse": float(np.sqrt(np.mean(error ** 2))),
                        "max_error": float(error.max())})
    return out


def write(out_dir: Path, progress=print) -> list[Path]:
    from app.reports.series_report import write as write_series
    data = rows(progress)
    intro = (f"The ray marcher's error against its step (in samples) at {SIZE} x {SIZE}: a "
             f"homogeneous sphere against its closed form, the lit phantom against a step of "
             f"{REFERENCE_STEP:g}; 8-bit units.")
    return write_series(out_dir, "volume_steps", data, intro,
                        [("series", "series"), ("step", "step (samples)"),
                         ("time_ms", "time ms (median)"), ("rmse", "RMSE"),
                         ("max_error", "max error")],
                        "Volume ray marching: error against time, one point per step",
                        "RMSE (8-bit units)")
