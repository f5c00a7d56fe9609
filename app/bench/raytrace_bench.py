"""``python -m app bench --renderer raytrace``: the ray tracer's rows beside Embree's.

Primary rays a second (ours on all cores and on one thread, Embree on the same rays), whole
Whitted frames a second and the rays of each kind a frame, on the Whitted scene and the glass
bunny (the full scan where ``../shared`` has it, else the shipped decimated one), and the cost
of more primary rays over 10,000 spheres. Writes ``DIR/bench_raytrace.json``.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np

from app.bench.bench_tables import progress
from core.paths import ROOT


# ------------------------------------------------------------------------------------ the ray tracer

def _bunny_file() -> Path | None:
    for folder in ROOT.parents:
        candidate = folder / "shared" / "data" / "stanford-bunny" / "bun_zipper.ply"
        if candidate.exists():
            return candidate
    return None


def _raytrace_scenes(args) -> list:
    """``[(label, scene, view)]``: the classic Whitted scene and the glass bunny (or --scene)."""
    from core.scene.formats import load_scene
    from core.scene.formats.scenefile import read_scene_file
    if args.scene:
        scene = load_scene(args.scene, size=args.size)
        return [(scene.name, scene, scene.views[0])] if scene.views else []
    scenes = [("whitted", load_scene(str(ROOT / "scenes" / "whitted.toml")))]
    path = ROOT / "scenes" / "glass_bunny.toml"
    text, bunny = path.read_text(), _bunny_file()
    if bunny is None:
        progress("the full Stanford bunny is not on this machine: the glass bunny is the "
                  "shipped decimated scan (16,301 triangles)")
    else:       # the full scan (69,451 triangles) in place of the shipped decimated one
        text = text.replace("stanford-bunny/bun_zipper_res2.ply", bunny.as_posix())
    scenes.append(("glass bunny", read_scene_file(text, str(path), path.parent)))
    return [(label, scene, scene.views[0]) for label, scene in scenes]


def _median_seconds(run, frames: int, warmup: int) -> tuple[float, float]:
    """Median wall and CPU seconds (all threads of this process) of ``run()``. On a machine
    shared with other work the wall time grows with the load; the CPU time hardly does, so
    CPU seconds / cores estimates the wall time on an idle machine."""
    for _ in range(warmup):
        run()
    walls, cpus = [], []
    for _ in range(frames):
        start, cpu = time.perf_counter(), time.process_time()
        run()
        walls.append(time.perf_counter() - start)
        cpus.append(time.process_time() - cpu)
    return float(np.median(walls)), float(np.median(cpus))


def _embree_run(scene, origins, directions):
    """Embree's closest-hit query of the rays on the scene's triangles (float32), as a
    function to time, or None (no embreex, or no triangles)."""
    try:
        from embreex import rtcore_scene
        from embreex.mesh_construction import TriangleMesh
    except ImportError:
        return None
    from core.raytrace.geometry import traced_meshes
    meshes = traced_meshes(scene)
    if not meshes:
        return None                                      # spheres and planes only
    corners = np.concatenate([m.positions[m.triangles] for m in meshes]).astype(np.float32)
    oracle = rtcore_scene.EmbreeScene()
    TriangleMesh(oracle, corners)
    o32, d32 = origins.astype(np.float32), directions.astype(np.float32)
    return lambda: oracle.run(o32, d32, output=1)


def _alternating_medians(runs: dict, frames: int, warmup: int) -> dict:
    """``{name: (median wall s, median CPU s)}`` of each run, timed in turns (one of each,
    then again): the host's speed drifts on a shared machine, and a ratio of two medians
    taken minutes apart would carry the drift."""
    for _ in range(warmup):
        for run in runs.values():
            run()
    times = {name: ([], []) for name in runs}
    for _ in range(frames):
        for name, run in runs.items():
            start, cpu = time.perf_counter(), time.process_time()
            run()
            times[name][0].append(time.perf_counter() - start)
            times[name][1].append(time.process_time() - cpu)
    return {name: (float(np.median(w)), float(np.median(c))) for name, (w, c) in times.items()}


def raytrace_bench(args) -> int:
    """Primary visibility rays/s (ours and Embree's, same rays, same run) and full Whitted
    frames/s at ``--size``, for the classic Whitted scene and the glass bunny."""
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    load_before = os.getloadavg()
    frames, warmup = max(1, min(args.frames, 5)), max(1, args.warmup)
    rows = [_raytrace_row(args, label, scene, view, frames, warmup)
            for label, scene, view in _raytrace_scenes(args)]
    spheres = None if args.scene else _many_spheres_row(frames, warmup)
    report = {"size": list(args.size), "projection": args.projection, "frames": frames,
              "rows": rows, "spheres": spheres, "loadavg_before": list(load_before),
              "loadavg_after": list(os.getloadavg()), "cpus": os.cpu_count()}
    (out / "bench_raytrace.json").write_text(json.dumps(report, indent=2))
    _print_raytrace(args, report, load_before)
    print(f"wrote {out / 'bench_raytrace.json'}")
    return 0


def _raytrace_row(args, label: str, scene, view, frames: int, warmup: int) -> dict:
    """One scene's row: the BVH build, primary rays/s (ours and Embree's), Whitted frames."""
    from core.raytrace import bvh, geometry
    from core.renderers.raytrace.draw import TraceOptions, prepare, primary, render_raw
    progress(f"{label}: build, primary rays, Whitted frames ...")
    bvh.build(np.eye(3), [[0, 1, 2]])                 # load the compiled build first
    geometry.forget(scene)                            # time the build from nothing
    setup = prepare(scene, view, args.projection, args.size, TraceOptions())
    build = setup.packing.build
    origins, directions, t_min, t_max = primary(setup, 0, args.size[1], 0, args.size[0])
    live = np.isfinite(t_min)
    rays = (np.ascontiguousarray(origins[live]), np.ascontiguousarray(directions[live]),
            np.ascontiguousarray(t_min[live]), np.ascontiguousarray(t_max[live]))
    rates = _primary_ray_rates(setup, scene, rays, frames, warmup)
    frame_s, frame_cpu = _median_seconds(lambda: render_raw(prepare(scene, view, args.projection,
                                                         args.size, TraceOptions())),
                              frames, warmup)
    counted = prepare(scene, view, args.projection, args.size, TraceOptions())
    render_raw(counted)
    return {"scene": label, "triangles": build.triangles,
            "bvh_build_ms": build.seconds * 1e3, "bvh_bytes": build.bytes,
            "primary_rays": int(live.sum()), **rates,
            "whitted_frame_ms": frame_s * 1e3, "whitted_fps": 1.0 / frame_s,
            "whitted_frame_cpu_ms": frame_cpu * 1e3,
            "rays_per_frame": {k: int(v) for k, v in zip(
                ("primary", "shadow", "reflected", "refracted", "TIR", "cut by depth",
                 "cut adaptive"), counted.counts)}}


def _primary_ray_rates(setup, scene, rays, frames: int, warmup: int) -> dict:
    """Primary visibility rays per second and per CPU second: ours (all threads and one) and
    Embree's where it is installed, timed in turns on the same rays."""
    import numba

    from core.raytrace import whitted
    o, d, lo, hi = rays
    kind, index, t_hit = np.empty(len(o), np.int64), np.empty(len(o), np.int64), np.empty(len(o))

    def ours():
        whitted.visible_many(setup.packing.packed, o, d, lo, hi, kind, index, t_hit)

    def ours_one_thread():
        threads = numba.get_num_threads()
        numba.set_num_threads(1)
        try:
            ours()
        finally:
            numba.set_num_threads(threads)

    runs = {"ours": ours, "ours, one thread": ours_one_thread}
    embree_run = _embree_run(scene, o, d)
    if embree_run is not None:
        runs["embree"] = embree_run
    timed = _alternating_medians(runs, 2 * frames, warmup)   # ours, Embree, ours, ...
    primary_s, primary_cpu = timed["ours"]
    one_thread_cpu = timed["ours, one thread"][1]
    embree = None
    if embree_run is not None:
        embree = len(o) / timed["embree"][0], len(o) / timed["embree"][1]
    return {"primary_rays_per_s": len(o) / primary_s,
            "primary_rays_per_cpu_s": len(o) / primary_cpu,
            "primary_rays_per_cpu_s_one_thread": len(o) / one_thread_cpu,
            "embree_rays_per_s": embree[0] if embree else None,
            "embree_rays_per_cpu_s": embree[1] if embree else None}


def _print_raytrace(args, report: dict, load_before) -> None:
    """The ray tracer's table, as bench_raytrace.json holds it."""
    frames, rows, spheres = report["frames"], report["rows"], report["spheres"]
    print(f"ray tracer, {args.size[0]} x {args.size[1]} {args.projection}, median of {frames} "
          f"(primary rays: of {2 * frames}, ours and Embree's in turns); "
          f"{os.cpu_count()} CPUs, load average {load_before[0]:.1f} before, "
          f"{report['loadavg_after'][0]:.1f} after")
    cores = os.cpu_count() or 1
    print(f"{'scene':<14}{'triangles':>10}{'BVH build':>11}{'primary Mray/s':>16}"
          f"{'Embree Mray/s':>15}{'ratio':>7}{'Whitted frame':>15}{'fps':>7}"
          f"{'frame CPU':>11}{'CPU/cores':>11}")
    for r in rows:
        embree = r["embree_rays_per_s"]
        print(f"{r['scene']:<14}{r['triangles']:>10}{r['bvh_build_ms']:>9.0f}ms"
              f"{r['primary_rays_per_s'] / 1e6:>16.2f}"
              f"{(embree / 1e6 if embree else float('nan')):>15.2f}"
              f"{(embree / r['primary_rays_per_s'] if embree else float('nan')):>7.2f}"
              f"{r['whitted_frame_ms']:>13.0f}ms{r['whitted_fps']:>7.2f}"
              f"{r['whitted_frame_cpu_ms']:>9.0f}ms{r['whitted_frame_cpu_ms'] / cores:>9.0f}ms")
        if embree:
            print(f"{'':<14}per CPU second: ours {r['primary_rays_per_cpu_s'] / 1e6:.2f} Mray, "
                  f"Embree {r['embree_rays_per_cpu_s'] / 1e6:.2f} Mray (ratio "
                  f"{r['embree_rays_per_cpu_s'] / r['primary_rays_per_cpu_s']:.2f}); ours on one "
                  f"thread, as Embree runs here: "
                  f"{r['primary_rays_per_cpu_s_one_thread'] / 1e6:.2f} Mray (ratio "
                  f"{r['embree_rays_per_cpu_s'] / r['primary_rays_per_cpu_s_one_thread']:.2f})")
        print(f"{'':<14}rays per frame: " + ", ".join(f"{k} {v}" for k, v in r["rays_per_frame"].items()))
    if spheres:
        print(f"{spheres['spheres']:,} spheres (radius {spheres['radius']}), shadows off: "
              f"{spheres['more_rays']:,} more primary rays ({spheres['small']}² → "
              f"{spheres['large']}² pixels) cost {spheres['more_cpu_s']:.3f} CPU-s, "
              f"{spheres['more_wall_s']:.3f} s wall; the spheres' BVH builds in "
              f"{spheres['build_ms']:.0f} ms")


SPHERES, SPHERE_RADIUS = 10_000, 0.03


def _many_spheres_row(frames: int, warmup: int, small: int = 100, large: int = 400) -> dict:
    """What ``large² − small²`` more primary rays cost on 10,000 small spheres (radius 0.03,
    uniform in a 4-unit cube in front of the Whitted scene's camera, shadows off): the whole
    frame, CPU and wall, median of ``frames``."""
    import dataclasses
    from core.raytrace import geometry
    from core.renderers.raytrace.draw import TraceOptions, prepare, render_raw
    from core.scene.formats import load_scene
    from core.scene.primitives import Sphere
    progress(f"{SPHERES:,} spheres: {small}² and {large}² frames ...")
    base = load_scene(str(ROOT / "scenes" / "whitted.toml"))
    centres = np.random.default_rng(1).uniform(-2.0, 2.0, (SPHERES, 3)) + [0.0, 1.0, 0.0]
    scene = dataclasses.replace(base, meshes=[], primitives=[
        Sphere(center=tuple(c), radius=SPHERE_RADIUS) for c in centres])
    options = TraceOptions(shadows="off")
    start = time.perf_counter()
    geometry.pack(scene)
    build_ms = (time.perf_counter() - start) * 1e3
    times = {n: _median_seconds(lambda: render_raw(prepare(scene, base.views[0], "perspective",
                                                          (n, n), options)), frames, warmup)
             for n in (small, large)}
    return {"spheres": SPHERES, "radius": SPHERE_RADIUS, "small": small, "large": large,
            "more_rays": large * large - small * small, "build_ms": build_ms,
            "more_wall_s": times[large][0] - times[small][0],
            "more_cpu_s": times[large][1] - times[small][1]}
