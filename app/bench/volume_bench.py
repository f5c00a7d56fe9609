"""``python -m app bench --renderer volume``: the volume renderer and marching cubes on a 256³
volume (the Shepp–Logan phantom), against scikit-image's marching cubes on the same machine.

- emission–absorption (gradient-shaded and unlit) and MIP frames at ``--size`` (default
  500 x 500), median of ``--frames`` (at most 5) after ``--warmup``;
- isosurface extraction at two levels of the phantom, ours and ``skimage.measure.marching_cubes``
  (when scikit-image is installed: it is in the ``test`` extra), median of three.

Wall times on a shared machine mostly measure the other processes; this process's CPU time is
given beside them, and the load average before and after. Writes ``DIR/volume.json`` and
``DIR/volume.md``; prints the table.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

SIDE = 256
TRANSFER = np.array([[0.0, 0, 0, 0, 0], [0.15, 0.2, 0.3, 0.6, 0], [0.2, 0.45, 0.6, 0.9, 0.9],
                     [0.25, 0.9, 0.7, 0.3, 1.5], [0.3, 1, 0.55, 0.2, 12], [1, 1, 1, 1, 1.5]])
ISO_LEVELS = (0.1, 0.25)


def _progress(text: str) -> None:
    print(f"[bench] {text}", file=sys.stderr, flush=True)


def _median(run, frames: int, warmup: int) -> dict:
    for _ in range(warmup):
        run()
    wall, cpu = [], []
    for _ in range(frames):
        t, c = time.perf_counter(), time.process_time()
        run()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return {"wall_ms": 1e3 * float(np.median(wall)), "cpu_ms": 1e3 * float(np.median(cpu))}


def frame_rows(values, spacing, size, frames, warmup) -> list[dict]:
    from core.camera.view import View
    from core.render import render
    from core.scene.model import Light, Scene
    from core.settings import RenderSettings
    from core.volume.data import Volume, attach_volumes
    view = View(vrp=(0, 0, 0), vpn=(0.5, 0.35, 1), vup=(0, 1, 0),
                window=(-1.25, 1.25, -1.25, 1.25), prp=(0, 0, 6), front=2, back=-2,
                label="bench view")
    rows = []
    for label, mode, lighting in (("emission-absorption, gradient-shaded",
                                   "emission-absorption", "gradient"),
                                  ("emission-absorption, unlit", "emission-absorption", "none"),
                                  ("MIP", "mip", "none")):
        scene = Scene(name="volume bench", meshes=[], views=[view],
                      lights=[Light(position=(4, 5, 6))])
        attach_volumes(scene, [Volume(values=values, spacing=spacing, mode=mode,
                                      lighting=lighting, transfer=TRANSFER)])
        settings = RenderSettings.for_scene(scene, renderer="volume", size=size)
        _progress(f"{label} frames ...")
        rows.append({"case": f"{label}, {size[0]}x{size[1]}",
                     **_median(lambda: render(scene, view, settings), frames, warmup)})
    return rows


def marching_rows(values) -> list[dict]:
    from core.volume.marching import marching_cubes
    try:
        from skimage import measure
    except ImportError:
        measure = None
    rows = []
    for iso in ISO_LEVELS:
        _progress(f"marching cubes at iso {iso} ...")
        triangles = len(marching_cubes(values, iso)[1])
        rows.append({"case": f"marching cubes, iso {iso} ({triangles} triangles)",
                     **_median(lambda: marching_cubes(values, iso), 3, 0)})
        if measure is not None:
            rows.append({"case": f"scikit-image marching_cubes, iso {iso}",
                         **_median(lambda: measure.marching_cubes(values, iso), 3, 0)})
    if measure is None:
        rows.append({"case": "scikit-image: not installed (pip install scikit-image)",
                     "wall_ms": float("nan"), "cpu_ms": float("nan")})
    return rows


def run(args) -> int:
    from core.volume.generators import shepp_logan
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    load_before = os.getloadavg()
    _progress(f"the phantom at {SIDE}³ ...")
    values, spacing = shepp_logan(SIDE)
    rows = (frame_rows(values, spacing, args.size, min(args.frames, 5), min(args.warmup, 1))
            + marching_rows(values))
    info = {"volume": f"Shepp-Logan phantom {SIDE}^3", "cpus": os.cpu_count(),
            "load_before": load_before, "load_after": os.getloadavg()}
    (out / "volume.json").write_text(json.dumps({"info": info, "rows": rows}, indent=1))
    table = "\n".join(["| case | wall ms | CPU ms |", "|---|---:|---:|"]
                      + [f"| {r['case']} | {r['wall_ms']:.0f} | {r['cpu_ms']:.0f} |"
                         for r in rows])
    text = (f"{info['volume']}, {info['cpus']} CPUs, load average "
            f"{load_before[0]:.1f} before, {info['load_after'][0]:.1f} after\n\n{table}\n")
    (out / "volume.md").write_text(text)
    print(text)
    return 0
