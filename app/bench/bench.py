"""``python -m app bench``: our CPU pipeline against real OpenGL in software.

Renders a scene (default: a sphere plus a torus at 1k, 10k, 100k and 1M triangles, 500 x 500,
flat, Gouraud and Phong) two ways in the same run:

- ours: the full CPU pipeline (``core.render.render``: normalize, cull, clip, project, scan-line
  z-buffer, shade) plus the upload the viewer does each frame (``app.viewer.blit.Blit.upload``, a
  ``texture.write`` into a moderngl texture; no readback);
- llvmpipe: :class:`app.oracles.reference_gl.GLRenderer` with the equivalent GLSL shaders, geometry
  uploaded once, each frame timed as draw + ``ctx.finish()`` (the readback is timed apart).

Each case runs ``--warmup`` frames and then ``--frames`` timed ones (at least 20 by default);
the table gives the median and the min–max in ms, fps, and the ratio ours / llvmpipe. The CPU
frame's own per-stage times (``Frame.stats["ms"]``) are kept as medians, so the output says
where the time goes. It also measures the numba JIT's cold and warm start (a fresh process
rendering one frame with an empty and with the normal cache) and the time from
``python -m app`` to the first frame shown (the viewer under Xvfb, read from its log).

Writes ``DIR/bench.json`` and a bar chart ``DIR/bench.png``; prints progress to stderr.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import socket
import sys
import time
from pathlib import Path

import numpy as np

from app.bench.bench_tables import (format_depth, format_stages, format_startup, format_table,
                                    format_threads, progress, write_chart)
from app.bench.raytrace_bench import raytrace_bench
from app.bench.startup import first_frame_scenes, first_frame_time, jit_start_times
from core.settings import RenderSettings

DEFAULT_SIZES = "1k,10k,100k,1M"
DEFAULT_SHADINGS = "flat,gouraud,phong"
from core.settings import PROJECTIONS, SOLID_SHADINGS as SHADINGS


def _count(text: str) -> int:
    """``"1k"`` → 1000, ``"1M"`` → 1000000, ``"2500"`` → 2500."""
    text = text.strip()
    factor = {"k": 1_000, "m": 1_000_000}.get(text[-1:].lower(), 1)
    digits = text[:-1] if factor > 1 else text
    try:
        value = int(float(digits) * factor)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a triangle count: {text!r} (try 1k, 100k, 1M)") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"a triangle count must be positive, not {text!r}")
    return value


def _counts(text: str) -> list[int]:
    return [_count(part) for part in text.split(",") if part.strip()]


def _shadings(text: str) -> list[str]:
    chosen = [part.strip() for part in text.split(",") if part.strip()]
    from core.registry import shading_names
    for s in chosen:
        if s not in shading_names():
            raise argparse.ArgumentTypeError(f"shading must be among {', '.join(shading_names())}, "
                                             f"not {s!r}")
    return chosen


def add_arguments(parser: argparse.ArgumentParser, parse_size) -> None:
    """The bench's options, added to the ``bench`` sub-parser by ``app/cli_arguments.py`` (which hands
    over its ``WxH`` parser, so that there is one)."""
    parser.add_argument("--scene", default=None,
                        help="a scene file to time instead of the generated sphere + torus "
                             "(then --sizes is ignored)")
    parser.add_argument("--sizes", type=_counts, default=_counts(DEFAULT_SIZES),
                        help=f"triangle counts of the sphere + torus (default {DEFAULT_SIZES})")
    parser.add_argument("--frames", type=int, default=20, help="timed frames per case (default 20)")
    parser.add_argument("--warmup", type=int, default=2, help="untimed frames first (default 2)")
    parser.add_argument("--shading", type=_shadings, default=_shadings(DEFAULT_SHADINGS),
                        help=f"shading modes (default {DEFAULT_SHADINGS})")
    parser.add_argument("--projection", choices=PROJECTIONS, default="perspective")
    parser.add_argument("--size", type=parse_size, default=(500, 500),
                        help="framebuffer WxH (default 500x500)")
    parser.add_argument("--out", default="out/bench", help="directory for bench.json and bench.png")
    parser.add_argument("--no-startup", action="store_true",
                        help="skip the JIT cold/warm start and the first-frame measurements")
    parser.add_argument("--no-threads", action="store_true",
                        help="skip the thread-scaling table (every case again on one thread)")
    parser.add_argument("--no-animation", action="store_true",
                        help="skip the animation rows (the fountain and the fly-around on 1 "
                             "process and 2 workers)")
    parser.add_argument("--no-depth", action="store_true",
                        help="skip the depth-complexity rows (100 stacked full-screen layers)")
    parser.add_argument("--window", action="store_true",
                        help="time the window as a user sees it (app/bench/window_bench.py): "
                             "orbits of real scans at 500x500 and 1580x1080 and a ray-traced "
                             "scene, driven by xdotool under X (Xvfb without a display), and "
                             "the path tracer converging at rest")
    parser.add_argument("--seconds", type=float, default=8.0,
                        help="--window: how long each orbit drags (default 8)")
    parser.add_argument("--renderer", type=_renderers, default="zbuffer",
                        help="zbuffer (default); raytrace: the ray tracer's rows beside Embree; "
                             "radiosity,pathtrace,twopass (any of them): the global illumination "
                             "rows on the Cornell box, beside Mitsuba, and the two-pass method's "
                             "on its room; a list with bsp, depth-sort or "
                             "scanline (e.g. bsp,depth-sort,scanline,zbuffer): the painter's "
                             "algorithms and Watkins' scan line against the z-buffer; volume: the "
                             "ray marcher and marching cubes on a 256³ phantom, beside scikit-image")


def benched(family: str = "") -> tuple[str, ...]:
    """The renderers the bench times (their entry's ``bench``), those of ``family`` if named:
    ``gi`` the global-illumination rows, ``painters`` the object-precision visible-surface
    algorithms timed against the z-buffer."""
    from core.renderers import renderers
    return tuple(r.name for r in renderers() if r.bench and (r.bench == family or not family))


def _renderers(text: str) -> str:
    """One benched renderer, a list of the ``gi`` family (checked by their bench, which
    names an unknown one), or a list of the painters and zbuffer."""
    chosen = [part.strip() for part in text.split(",") if part.strip()]
    if len(chosen) == 1 and chosen[0] in benched():
        return chosen[0]
    if any(name in benched("gi") for name in chosen):
        return ",".join(chosen)
    for name in chosen:
        if name not in (*benched("painters"), "zbuffer"):
            alone = ", ".join(r for r in benched() if r not in benched("gi")
                              and r not in benched("painters"))
            raise argparse.ArgumentTypeError(
                f"renderer must be {alone}, a list of {' and '.join(benched('gi'))}, or a "
                f"list of {', '.join(benched('painters'))} and zbuffer; not {name!r}")
    return ",".join(chosen)


# ----------------------------------------------------------------------------- scenes

def bench_scene(triangles: int):
    """The default bench scene: a sphere plus a torus of about ``triangles`` triangles."""
    from core.scene.generators import sphere_torus
    return sphere_torus(triangles=triangles)


def _scenes(args) -> list:
    if args.scene:
        from core.scene.formats import ReaderError, load_scene
        try:
            scene = load_scene(args.scene, size=args.size)
        except ReaderError as error:
            raise SystemExit(f"error: {error}") from None
        if not scene.views:
            raise SystemExit(f"error: {args.scene}: no valid view to time")
        return [scene]
    return [bench_scene(n) for n in args.sizes]


# ----------------------------------------------------------------------------- timing

def _summary(seconds: list[float], cpu_seconds: list[float]) -> dict:
    """Wall-time median, min and max in ms; ``cpu_median``: the process's CPU time per frame
    (all threads), which says how much of the wall time other processes took."""
    ms = np.asarray(seconds) * 1e3
    return {"median": float(np.median(ms)), "min": float(ms.min()), "max": float(ms.max()),
            "frames": len(ms), "cpu_median": float(np.median(cpu_seconds) * 1e3)}


def time_ours(scene, projection: str, shading: str, size, frames: int, warmup: int, blit) -> dict:
    """Full CPU frames plus the viewer's texture upload; per-stage medians from Frame.stats."""
    from core.render import render
    totals, cpu, uploads, stages = [], [], [], {}
    frame = None
    for k in range(warmup + frames):
        c0 = time.process_time()
        t0 = time.perf_counter()
        frame = render(scene, scene.views[0],
                       RenderSettings.for_scene(scene, projection=projection, shading=shading, size=size))
        t1 = time.perf_counter()
        blit.upload(frame.rgbx)
        t2 = time.perf_counter()
        if k >= warmup:
            cpu.append(time.process_time() - c0)
            totals.append(t2 - t0)
            uploads.append(t2 - t1)
            for stage, ms in frame.stats.get("ms", {}).items():
                stages.setdefault(stage, []).append(ms)
    result = _summary(totals, cpu)
    result["upload_ms"] = float(np.median(uploads) * 1e3)
    result["stages_ms"] = {stage: float(np.median(v)) for stage, v in stages.items()}
    if frame is not None and frame.message:
        result["message"] = frame.message
    return result


def precision_rows(scenes, projection: str, size, frames: int, warmup: int) -> list[dict]:
    """Each scene's pixel step and whole frame in every lit mode, lit by the float32 passes
    (the default) and by the float64 textbook kernels (``--shading-precision float64``), in
    alternation: median ms of each."""
    from core.context import RenderContext
    from core.render import render
    rows = []
    for scene in scenes:
        for shading in ("flat", "gouraud", "phong"):
            runs = {p: ([], []) for p in ("float32", "float64")}
            contexts = {p: RenderContext() for p in runs}
            for k in range(warmup + frames):
                for precision, (pixel, whole) in runs.items():
                    settings = RenderSettings.for_scene(scene, projection=projection,
                                                        shading=shading, size=size,
                                                        shading_precision=precision)
                    t0 = time.perf_counter()
                    frame = render(scene, scene.views[0], settings, contexts[precision])
                    if k >= warmup:
                        whole.append((time.perf_counter() - t0) * 1e3)
                        pixel.append(frame.stats["ms"].get("shade: pixel step", 0.0))
            rows.append({"scene": scene.name, "triangles": scene.triangle_count,
                         "shading": shading,
                         **{f"{p} {what}": float(np.median(v)) for p, (px, fr) in runs.items()
                            for what, v in (("pixel step ms", px), ("frame ms", fr))}})
    return rows


def format_precision(rows: list[dict]) -> str:
    lines = ["lighting in float32 passes against the float64 kernels (median ms; pixel step "
             "includes lighting the visible faces or vertices):"]
    for r in rows:
        lines.append(f"  {r['triangles']:>9,} {r['shading']:<8} pixel step "
                     f"{r['float32 pixel step ms']:6.2f} / {r['float64 pixel step ms']:6.2f}"
                     f"   frame {r['float32 frame ms']:6.2f} / {r['float64 frame ms']:6.2f}")
    return "\n".join(lines)


def time_llvmpipe(renderer, projection: str, shading: str, frames: int, warmup: int) -> dict:
    """llvmpipe frames: draw + finish timed; the readback timed apart."""
    draws, cpu, reads = [], [], []
    for k in range(warmup + frames):
        c0 = time.process_time()
        draw, read = renderer.timed_frame(renderer.scene.views[0], projection, shading)
        if k >= warmup:
            cpu.append(time.process_time() - c0)     # includes the readback
            draws.append(draw)
            reads.append(read)
    result = _summary(draws, cpu)
    result["readback_ms"] = float(np.median(reads) * 1e3)
    return result


def time_floor(floor, view, frames: int, warmup: int) -> dict:
    """The bare numba Gouraud rasterizer (app.bench.floor): whole frames."""
    totals, cpu = [], []
    for k in range(warmup + frames):
        c0 = time.process_time()
        t0 = time.perf_counter()
        floor.frame(view)
        if k >= warmup:
            totals.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
    return _summary(totals, cpu)


def thread_scaling(scene, projection: str, shading: str, size, frames: int, warmup: int,
                   blit) -> dict:
    """Per-stage medians on one thread and on all (numba.set_num_threads), and the speed-up."""
    import numba
    most = numba.config.NUMBA_NUM_THREADS
    runs = {}
    try:
        for threads in (1, most):
            numba.set_num_threads(threads)
            runs[threads] = time_ours(scene, projection, shading, size, frames, warmup, blit)
    finally:
        numba.set_num_threads(most)
    one, all_ = runs[1], runs[most]
    stages = {name: {"1": ms, str(most): all_["stages_ms"].get(name, float("nan")),
                     "speedup": ms / all_["stages_ms"][name]
                     if all_["stages_ms"].get(name) else float("nan")}
              for name, ms in one["stages_ms"].items()}
    return {"threads": most, "total": {"1": one["median"], str(most): all_["median"],
                                       "speedup": one["median"] / all_["median"]},
            "stages": stages}


def depth_complexity(size, frames: int, warmup: int) -> dict:
    """The rasterizer on 1 and 100 full-screen layers of 10k triangles each (the cost of overdraw), front
    to back and back to front: median ms of ``rasterize`` and the ratio to one layer."""
    from app.bench.depth_bench import time_layers
    width, height = size
    one = time_layers(1, 10_000, width, height, True, frames, warmup)
    rows = {"1 layer": one}
    for label, front in (("100 layers, front to back", True), ("100 layers, back to front", False)):
        row = time_layers(100, 10_000, width, height, front, frames, warmup)
        row["ratio"] = row["median"] / one["median"]
        rows[label] = row
    return rows


# ----------------------------------------------------------------------------- main

def run_cases(scenes: list, shadings: list[str], projection: str, size, frames: int, warmup: int,
              threads: bool = False) -> list[dict]:
    """Every (scene, shading) case: ours, the GLSL oracle on llvmpipe, the lean llvmpipe row
    (one light, indexed, culled: app.oracles.lean_gl) and, for a scene with lights and closed
    meshes, the bare numba floor (app.bench.floor, Gouraud, one light), all in this run."""
    from app.viewer.blit import Blit
    from app.bench.floor import Floor
    from app.oracles.lean_gl import MODES as LEAN_MODES, LeanGL
    from app.oracles.reference_gl import GLRenderer

    gl = GLRenderer(size)
    lean = LeanGL(size)
    blit = Blit(gl.ctx)            # the viewer's upload path, on an EGL context like the window's
    rows = []
    try:
        for scene in scenes:
            t = time.perf_counter()
            gl.load(scene, modes=tuple(shadings))
            progress(f"{scene.name}: {scene.triangle_count:,} triangles uploaded to llvmpipe "
                      f"in {time.perf_counter() - t:.2f} s")
            comparable = bool(scene.lights) and projection == "perspective"
            if comparable:
                lean.load(scene)
                progress(f"{scene.name} {scene.triangle_count:,}: the numba floor ...")
                floor = time_floor(Floor(scene, size), scene.views[0], frames, warmup)
            for shading in shadings:
                progress(f"{scene.name} {scene.triangle_count:,} {shading}: ours ...")
                ours = time_ours(scene, projection, shading, size, frames, warmup, blit)
                progress(f"{scene.name} {scene.triangle_count:,} {shading}: llvmpipe ...")
                ref = time_llvmpipe(gl, projection, shading, frames, warmup)
                row = {"scene": scene.name, "triangles": scene.triangle_count,
                       "shading": shading, "projection": projection, "size": list(size),
                       "ours": ours, "ours_fps": 1e3 / ours["median"], "llvmpipe": ref,
                       "llvmpipe_fps": 1e3 / ref["median"],
                       "ratio": ours["median"] / ref["median"]}
                if comparable and shading in LEAN_MODES:
                    lean.scene = scene
                    row["lean"] = time_llvmpipe(lean, projection, shading, frames, warmup)
                    row["ratio_lean"] = ours["median"] / row["lean"]["median"]
                    row["floor"] = floor
                    row["ratio_floor"] = ours["median"] / floor["median"]
                if threads:
                    progress(f"{scene.name} {scene.triangle_count:,} {shading}: 1 thread ...")
                    row["threads"] = thread_scaling(scene, projection, shading, size, frames,
                                                    warmup, blit)
                rows.append(row)
                progress(f"    ours {ours['median']:.2f} ms, llvmpipe {ref['median']:.2f} ms, "
                          f"ratio {rows[-1]['ratio']:.2f}"
                          + (f", lean {row['lean']['median']:.2f} ms, floor "
                             f"{row['floor']['median']:.2f} ms" if "lean" in row else ""))
    finally:
        blit.release()
        lean.release()
        gl.release()
    return rows


def main(args) -> int:
    if args.frames < 1 or args.warmup < 0:
        print("error: --frames must be at least 1 and --warmup at least 0", file=sys.stderr)
        return 2
    status = _other_bench(args)
    if status is not None:
        return status
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    load_before = os.getloadavg()
    progress("building scenes ...")
    scenes = _scenes(args)
    rows = run_cases(scenes, args.shading, args.projection, args.size, args.frames, args.warmup,
                     threads=not getattr(args, "no_threads", False))

    progress("lighting: float32 passes against the float64 kernels ...")
    precision = precision_rows(scenes, args.projection, args.size, args.frames, args.warmup)
    startup = _startup_times(args)
    depth = _depth_rows(args)
    animation = _animation_rows(args)
    info = _machine_info(load_before)

    report = {"frames": args.frames, "warmup": args.warmup, "cases": rows,
              "precision": precision, "startup": startup,
              "depth_complexity": depth,
              "animation": animation, "machine": info, "bench_seconds": time.perf_counter() - t_start}
    (out / "bench.json").write_text(json.dumps(report, indent=2))
    write_chart(rows, out / "bench.png")
    _print_bench(args, report, load_before)
    print()
    print(f"wrote {out / 'bench.json'} and {out / 'bench.png'} "
          f"({time.perf_counter() - t_start:.0f} s in all)")
    return 0


def _other_bench(args) -> int | None:
    """The exit status of the bench of another renderer family or of the window, or None for
    the rasterizer's."""
    if getattr(args, "window", False):
        from app.bench.window_bench import main as window_main
        return window_main(args)
    if args.renderer in benched("raytrace"):
        return raytrace_bench(args)
    if args.renderer in benched("volume"):
        from app.bench.volume_bench import run as volume_run
        return volume_run(args)
    chosen = args.renderer.split(",")
    if any(name in benched("painters") for name in chosen):
        from app.bench.painters_bench import run
        return run(args, chosen)
    if any(name in benched("gi") for name in chosen):
        from app.bench.gi_bench import main as gi_main
        return gi_main(args)
    return None


def _startup_times(args) -> dict:
    """The JIT's cold and warm starts and the viewer's first frames (none with --no-startup)."""
    startup = {}
    if not args.no_startup:
        progress("JIT cold and warm start (fresh processes) ...")
        startup["jit"] = jit_start_times()
        progress("python -m app view under Xvfb, to the first frame ...")
        startup["first_frame_warm"] = first_frame_time()
        startup["first_frame_warm_torus"] = first_frame_time(scene="scenes/torus.toml")
        progress("python -m app view with an empty JIT cache ...")
        startup["first_frame_cold"] = first_frame_time(cold=True)
        progress("first picture of every shipped scene (warm cache) ...")
        startup["first_frame_scenes"] = first_frame_scenes()
    return startup


def _depth_rows(args):
    if getattr(args, "no_depth", False):
        return None
    progress("depth complexity: 100 layers of 10k triangles ...")
    return depth_complexity(args.size, min(args.frames, 7), min(args.warmup, 1))


def _animation_rows(args):
    if args.no_animation:            # the fountain and the fly-around, 1 process and 2 workers
        return None
    progress("animation: the fountain and the fly-around at 500 x 500 on 1 process and "
              "--workers 2 ...")
    from app.commands.animate import bench_animation
    return bench_animation(size=args.size)


def _machine_info(load_before) -> dict:
    """What the numbers were measured on, the load before and after included."""
    from app.oracles.reference_gl import GLRenderer
    info = {"machine": platform.machine(), "cpus": os.cpu_count(), "python": platform.python_version(),
            "host": socket.gethostname(), "numpy": np.__version__,
            # Other processes on a 2-core machine change every number here: keep the load.
            "loadavg_before": list(load_before), "loadavg_after": list(os.getloadavg())}
    try:
        import numba
        info["numba"] = numba.__version__
    except ImportError:
        pass
    probe = GLRenderer((1, 1))
    info["gl_renderer"] = probe.renderer_name
    probe.release()
    return info


def _print_bench(args, report: dict, load_before) -> None:
    """The bench's tables, as bench.json holds them."""
    rows, info, startup = report["cases"], report["machine"], report["startup"]
    depth, animation = report["depth_complexity"], report["animation"]
    print(f"{args.frames} frames after {args.warmup} warm-up, {args.size[0]} x {args.size[1]}, "
          f"{args.projection}; llvmpipe: {info['gl_renderer']}, {info['cpus']} CPUs; load average "
          f"{load_before[0]:.1f} before, {info['loadavg_after'][0]:.1f} after")
    print(format_table(rows))
    print()
    print("where our time goes (median ms per stage):")
    print(format_stages(rows))
    print()
    print(format_precision(report["precision"]))
    if any("threads" in r for r in rows):
        print()
        print("thread scaling (median ms per stage, one thread → all):")
        print(format_threads(rows))
    if depth:
        print()
        print(format_depth(depth))
    if startup:
        print()
        print(format_startup(startup))
    if animation:
        from app.commands.animate import format_animation
        print()
        print(format_animation(animation))


