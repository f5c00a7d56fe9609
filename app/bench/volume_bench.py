"""``python -m app bench --renderer volume``: the volume renderer and marching cubes on a 256³
volume (the Shepp–Logan phantom), against VTK and scikit-image on the same machine.

- emission–absorption (gradient-shaded and unlit) and MIP frames at ``--size`` (default
  500 x 500), median of ``--frames`` (at most 5) after ``--warmup``; beside each, VTK's
  ``vtkFixedPointVolumeRayCastMapper`` drawing the same volume, view, transfer function and
  size offscreen (:mod:`app.bench.volume_vtk`), its median, the ratio, and the mean and largest
  difference of the two pictures (of 255);
- isosurface extraction at two levels of the phantom, ours, VTK's ``vtkFlyingEdges3D`` and
  ``skimage.measure.marching_cubes`` (when scikit-image is installed: it is in the ``test``
  extra), median of three. VTK is the ``bench`` extra; without it the bench says so in one line.

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


def _view():
    from core.camera.view import View
    return View(vrp=(0, 0, 0), vpn=(0.5, 0.35, 1), vup=(0, 1, 0),
                window=(-1.25, 1.25, -1.25, 1.25), prp=(0, 0, 6), front=2, back=-2,
                label="bench view")


LIGHT = (4, 5, 6)
MODES = (("emission-absorption, gradient-shaded", "emission-absorption", "gradient"),
         ("emission-absorption, unlit", "emission-absorption", "none"),
         ("MIP", "mip", "none"))


def frame_rows(values, spacing, size, frames, warmup) -> list[dict]:
    """Ours, and VTK's ray caster beside each mode where VTK is installed."""
    from app.bench import volume_vtk
    from core.render import render
    from core.scene.model import Light, Scene
    from core.settings import RenderSettings
    from core.volume.data import Volume, attach_volumes
    from core.renderers.volume.draw import step_of
    view, rows = _view(), []
    peer = volume_vtk.available()
    for label, mode, lighting in MODES:
        scene = Scene(name="volume bench", meshes=[], views=[view],
                      lights=[Light(position=LIGHT)])
        volume = Volume(values=values, spacing=spacing, mode=mode, lighting=lighting,
                        transfer=TRANSFER)
        attach_volumes(scene, [volume])
        settings = RenderSettings.for_scene(scene, renderer="volume", size=size)
        _progress(f"{label} frames ...")
        ours = _median(lambda: render(scene, view, settings), frames, warmup)
        rows.append({"case": f"{label}, {size[0]}x{size[1]}", **ours})
        if not peer:
            continue
        m = volume.material
        vtk = volume_vtk.VtkVolume(values, spacing, view, size, TRANSFER, mode, lighting,
                                   step_of(volume), LIGHT, (m.ka, m.kd, m.ks, m.n))
        _progress(f"{label}: VTK frames ...")
        theirs = _median(vtk.render, frames, max(warmup, 1))
        difference = np.abs(render(scene, view, settings).color[..., :3].astype(np.int16)
                            - vtk.picture().astype(np.int16))
        rows.append({"case": f"VTK {volume_vtk.version()} fixed-point ray cast, {label}",
                     **theirs, "ratio": ours["wall_ms"] / theirs["wall_ms"],
                     "difference": f"mean {difference.mean():.2f}, max {difference.max()}"})
    if not peer:
        rows.append(_missing_vtk())
    return rows


def _missing_vtk() -> dict:
    return {"case": "VTK: not installed (pip install -e .[bench]); no peer rows",
            "wall_ms": float("nan"), "cpu_ms": float("nan")}


def marching_rows(values, spacing) -> list[dict]:
    from app.bench import volume_vtk
    from core.volume.marching import marching_cubes
    try:
        from skimage import measure
    except ImportError:
        measure = None
    rows = []
    for iso in ISO_LEVELS:
        _progress(f"marching cubes at iso {iso} ...")
        triangles = len(marching_cubes(values, iso)[1])
        ours = _median(lambda: marching_cubes(values, iso), 3, 0)
        rows.append({"case": f"marching cubes, iso {iso} ({triangles} triangles)", **ours})
        if volume_vtk.available():
            extract, count = volume_vtk.flying_edges(values, spacing, iso)
            theirs = _median(extract, 3, 0)
            rows.append({"case": f"VTK vtkFlyingEdges3D, iso {iso} ({count} triangles)",
                         **theirs, "ratio": ours["wall_ms"] / theirs["wall_ms"]})
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
            + marching_rows(values, spacing))
    info = {"volume": f"Shepp-Logan phantom {SIDE}^3", "cpus": os.cpu_count(),
            "load_before": load_before, "load_after": os.getloadavg()}
    (out / "volume.json").write_text(json.dumps({"info": info, "rows": rows}, indent=1))
    table = "\n".join(["| case | wall ms | CPU ms | ours / peer | pictures differ by (of 255) |",
                       "|---|---:|---:|---:|---|"]
                      + [f"| {r['case']} | {r['wall_ms']:.0f} | {r['cpu_ms']:.0f} | "
                         + (f"{r['ratio']:.2f}x" if "ratio" in r else "") + " | "
                         + r.get("difference", "") + " |" for r in rows])
    text = (f"{info['volume']}, {info['cpus']} CPUs, load average "
            f"{load_before[0]:.1f} before, {info['load_after'][0]:.1f} after\n\n{table}\n")
    (out / "volume.md").write_text(text)
    print(text)
    return 0
