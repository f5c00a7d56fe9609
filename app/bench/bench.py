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
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from core.settings import RenderSettings
from core.paths import ROOT

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
    """The bench's options, added to the ``bench`` sub-parser by ``app/cli.py`` (which hands
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
                             "radiosity,pathtrace (either or both): the global illumination rows "
                             "on the Cornell box, beside Mitsuba; a list with bsp, depth-sort or "
                             "scanline (e.g. bsp,depth-sort,scanline,zbuffer): the painter's "
                             "algorithms and Watkins' scan line against the z-buffer; volume: the "
                             "ray marcher and marching cubes on a 256³ phantom, beside scikit-image")


# the object-precision visible-surface algorithms timed against the z-buffer
GI_RENDERERS, PAINTERS = ("radiosity", "pathtrace"), ("bsp", "depth-sort", "scanline")


def _renderers(text: str) -> str:
    """``zbuffer``, ``raytrace``, a list of radiosity and pathtrace (checked by their bench,
    which names an unknown one), or a list of bsp, depth-sort, scanline and zbuffer."""
    chosen = [part.strip() for part in text.split(",") if part.strip()]
    if len(chosen) == 1 and chosen[0] in ("zbuffer", "raytrace", "volume", *GI_RENDERERS,
                                          *PAINTERS):
        return chosen[0]
    if any(name in GI_RENDERERS for name in chosen):
        return ",".join(chosen)
    for name in chosen:
        if name not in (*PAINTERS, "zbuffer"):
            raise argparse.ArgumentTypeError(
                f"renderer must be zbuffer, raytrace, volume, a list of radiosity and "
                f"pathtrace, or a list of bsp, depth-sort, scanline and zbuffer; not {name!r}")
    return ",".join(chosen)


def _progress(text: str) -> None:
    print(f"[bench] {text}", file=sys.stderr, flush=True)


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


# ----------------------------------------------------------------------------- start-up

_JIT_PROBE = r"""
import json, sys, time
t0 = time.perf_counter()
from core.render import render
from core.settings import RenderSettings
t_import = time.perf_counter()
from app.bench.bench import bench_scene
scene = bench_scene(1000)
t_scene = time.perf_counter()
first = {}
for shading in ("flat", "gouraud", "phong"):
    t = time.perf_counter()
    render(scene, scene.views[0],
           RenderSettings.for_scene(scene, projection="perspective", shading=shading, size=(500, 500)))
    first[shading] = (time.perf_counter() - t) * 1e3
t_end = time.perf_counter()
print(json.dumps({"import_ms": (t_import - t0) * 1e3, "scene_ms": (t_scene - t_import) * 1e3,
                  "first_frame_ms": first,
                  "to_first_frame_ms": (t_import - t0 + first["flat"] / 1e3) * 1e3,
                  "in_process_ms": (t_end - t0) * 1e3}))
"""


def _run_probe(env: dict) -> dict:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", _JIT_PROBE], cwd=ROOT, env=env,
                          capture_output=True, text=True, timeout=600)
    wall = (time.perf_counter() - start) * 1e3
    if done.returncode != 0:
        raise RuntimeError(done.stderr.strip().splitlines()[-1] if done.stderr.strip() else
                           f"exit status {done.returncode}")
    result = json.loads(done.stdout.strip().splitlines()[-1])
    result["process_wall_ms"] = wall
    return result


def jit_start_times() -> dict:
    """A fresh process importing the core and rendering flat, Gouraud, Phong frames once each.

    cold: ``NUMBA_CACHE_DIR`` is an empty directory, so every kernel compiles;
    warm: the normal cache, filled by one untimed run first.
    """
    result = {}
    with tempfile.TemporaryDirectory(prefix="fvd-numba-cold-") as empty:
        env = dict(os.environ, NUMBA_CACHE_DIR=empty)
        try:
            result["cold"] = _run_probe(env)
        except (RuntimeError, subprocess.TimeoutExpired, json.JSONDecodeError) as error:
            result["cold"] = {"error": str(error)}
    env = dict(os.environ)
    try:
        _run_probe(env)                           # fills the normal cache if it is stale
        result["warm"] = _run_probe(env)
    except (RuntimeError, subprocess.TimeoutExpired, json.JSONDecodeError) as error:
        result["warm"] = {"error": str(error)}
    return result


def _free_display() -> int | None:
    for number in range(90, 140):
        if not Path(f"/tmp/.X11-unix/X{number}").exists() and not Path(f"/tmp/.X{number}-lock").exists():
            return number
    return None


# The viewer logs "first frame shown 0.812 s after process start (0.650 s CPU)".
_FIRST_FRAME = re.compile(r"first frame.*?([0-9]+(?:\.[0-9]+)?)\s*(ms|s)\b(?:.*?([0-9.]+) s CPU)?",
                          re.IGNORECASE)


def first_frame_time(timeout: float = 60.0, cold: bool = False, scene: str | None = None) -> dict:
    """Seconds from spawning ``python -m app view [scene]`` (default: the default scene) to the
    first frame the viewer logs as shown.

    Runs the viewer under a private Xvfb with ``FVD_LOG`` pointing at a temporary file and reads
    the viewer's own "first frame" line; also gives the wall time until that line appeared.
    """
    xvfb = shutil.which("Xvfb")
    if xvfb is None:
        return {"measured": False, "reason": "Xvfb is not installed"}
    display = _free_display()
    if display is None:
        return {"measured": False, "reason": "no free X display number"}
    tmp = Path(tempfile.mkdtemp(prefix="fvd-first-frame-"))
    log = tmp / "viewer.log"
    server = subprocess.Popen([xvfb, f":{display}", "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    viewer = None
    try:
        if not _display_started(server, display):
            return {"measured": False, "reason": "Xvfb did not start"}
        start = time.perf_counter()
        viewer = _start_viewer(tmp, display, log, cold, scene)
        return _first_frame_logged(viewer, tmp, log, start, timeout, cold)
    finally:
        _stop_processes(viewer, server)
        shutil.rmtree(tmp, ignore_errors=True)


def _display_started(server, display: int) -> bool:
    """Wait (up to 10 s) for the Xvfb ``server`` to open its socket."""
    deadline = time.monotonic() + 10
    while not Path(f"/tmp/.X11-unix/X{display}").exists():
        if server.poll() is not None or time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def _start_viewer(tmp: Path, display: int, log: Path, cold: bool, scene: str | None):
    """``python -m app view [scene]`` on the display, logging to ``log`` (with ``cold``, from
    an empty kernel cache)."""
    env = dict(os.environ, DISPLAY=f":{display}", FVD_LOG=str(log))
    if cold:
        env["NUMBA_CACHE_DIR"] = str(tmp / "numba-cache")
    # stderr to a file: a pipe nobody reads while the viewer runs could fill and stall it
    errors = (tmp / "viewer.stderr").open("w")
    viewer = subprocess.Popen([sys.executable, "-m", "app", "view", *([scene] if scene else [])],
                              cwd=ROOT, env=env,
                              stdout=subprocess.DEVNULL, stderr=errors)
    errors.close()
    return viewer


def _first_frame_logged(viewer, tmp: Path, log: Path, start: float, timeout: float,
                        cold: bool) -> dict:
    """Watch the log for the viewer's "first frame" line: the measurement, or why there is none."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        text = log.read_text(errors="replace") if log.exists() else ""
        match = _FIRST_FRAME.search(text)
        if match:
            wall = time.perf_counter() - start
            value = float(match.group(1)) * (1e-3 if match.group(2).lower() == "ms" else 1.0)
            return {"measured": True, "logged_s": value, "wall_s": wall,
                    "cpu_s": float(match.group(3)) if match.group(3) else None,
                    "line": match.group(0), "cache": "empty" if cold else "normal",
                    "log": text.splitlines()[:60]}
        if viewer.poll() is not None:
            err = (tmp / "viewer.stderr").read_text(errors="replace").strip().splitlines()
            return {"measured": False, "reason": "the viewer exited before logging a first frame"
                    + (f": {err[-1]}" if err else f" (status {viewer.returncode})")}
        time.sleep(0.02)
    return {"measured": False, "reason": f"no 'first frame' line in FVD_LOG within {timeout:g} s"}


def _stop_processes(*procs) -> None:
    """SIGTERM each process still running, then kill it if it has not ended in 5 s."""
    for proc in procs:
        if proc is not None and proc.poll() is None:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


def first_frame_scenes() -> dict:
    """``first_frame_time`` (warm cache) for every shipped scene file, by file name."""
    from app.loading import shipped_scenes
    return {path.name: first_frame_time(scene=str(path.relative_to(ROOT)))
            for path in shipped_scenes()}


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


# ----------------------------------------------------------------------------- output

def format_depth(depth: dict) -> str:
    lines = ["depth complexity (core.pipeline.raster.rasterize alone, median ms):"]
    for label, row in depth.items():
        ratio = f", {row['ratio']:.2f}x one layer" if "ratio" in row else ""
        lines.append(f"  {label:28s} {row['triangles']:>9,} triangles {row['median']:9.2f} ms{ratio}")
    return "\n".join(lines)


def _ms(stat: dict) -> str:
    return f"{stat['median']:9.2f} ({stat['min']:.2f}–{stat['max']:.2f})"


def format_table(rows: list[dict]) -> str:
    head = (f"{'scene':<20} {'triangles':>10} {'shading':<8} {'ours ms median (min–max)':>28} "
            f"{'fps':>7} {'llvmpipe ms median (min–max)':>30} {'ours/llvmpipe':>13} "
            f"{'CPU ms ours/llvmpipe':>21} {'lean GL ms':>10} {'ours/lean':>9} "
            f"{'floor ms':>8} {'ours/floor':>10}")
    lines = [head, "-" * len(head)]
    for r in rows:
        lean, floor = r.get("lean"), r.get("floor")
        lean_text = (f"{lean['median']:>10.2f} {r['ratio_lean']:>9.2f}" if lean
                     else f"{'—':>10} {'—':>9}")
        floor_text = (f"{floor['median']:>8.2f} {r['ratio_floor']:>10.2f}" if floor
                      else f"{'—':>8} {'—':>10}")
        lines.append(f"{r['scene']:<20} {r['triangles']:>10,} {r['shading']:<8} "
                     f"{_ms(r['ours']):>28} {r['ours_fps']:>7.1f} {_ms(r['llvmpipe']):>30} "
                     f"{r['ratio']:>13.2f} "
                     f"{r['ours']['cpu_median']:>10.1f}/{r['llvmpipe']['cpu_median']:<10.1f} "
                     f"{lean_text} {floor_text}")
    return "\n".join(lines)


def format_threads(rows: list[dict]) -> str:
    """Speed-up from one thread to all, per stage (medians of the same frames)."""
    lines = []
    for r in rows:
        scaling = r.get("threads")
        if not scaling:
            continue
        n = scaling["threads"]
        total = scaling["total"]
        parts = ", ".join(f"{name} {v['speedup']:.2f}x ({v['1']:.2f}→{v[str(n)]:.2f})"
                          for name, v in sorted(scaling["stages"].items(),
                                                key=lambda kv: -kv[1]["1"]))
        lines.append(f"{r['triangles']:>10,} {r['shading']:<8} 1→{n} threads: frame "
                     f"{total['speedup']:.2f}x ({total['1']:.2f}→{total[str(n)]:.2f} ms); {parts}")
    return "\n".join(lines)


def format_stages(rows: list[dict]) -> str:
    """Where our time goes: the CPU frame's stage medians, largest first, per case."""
    lines = []
    for r in rows:
        stages = sorted(r["ours"]["stages_ms"].items(), key=lambda kv: -kv[1])
        parts = ", ".join(f"{name} {ms:.2f}" for name, ms in stages)
        lines.append(f"{r['triangles']:>10,} {r['shading']:<8} upload {r['ours']['upload_ms']:.2f}; {parts} "
                     f"(llvmpipe readback, not in its time: {r['llvmpipe']['readback_ms']:.2f})")
    return "\n".join(lines)


def format_startup(startup: dict) -> str:
    lines = []
    jit = startup.get("jit", {})
    for key in ("cold", "warm"):
        probe = jit.get(key)
        if probe is None:
            continue
        if "error" in probe:
            lines.append(f"JIT {key} start: failed: {probe['error']}")
            continue
        firsts = ", ".join(f"{s} {ms:.0f} ms" for s, ms in probe["first_frame_ms"].items())
        lines.append(f"JIT {key} start: import {probe['import_ms']:.0f} ms, first frames {firsts}; "
                     f"process wall {probe['process_wall_ms']:.0f} ms")
    for name, ff in startup.get("first_frame_scenes", {}).items():
        if ff.get("measured"):
            lines.append(f"first picture of scenes/{name}: {ff['logged_s']:.2f} s after process "
                         f"start as logged (warm cache)")
        else:
            lines.append(f"first picture of scenes/{name}: not measured: {ff['reason']}")
    for key in ("first_frame_warm", "first_frame_warm_torus", "first_frame_cold"):
        ff = startup.get(key)
        if ff is None:
            continue
        label = ("python -m app" + (" scenes/torus.toml" if key.endswith("torus") else "")
                 + " to first frame shown" + (" (empty JIT cache)" if key.endswith("cold") else ""))
        if ff.get("measured"):
            cpu = f", {ff['cpu_s']:.2f} s CPU" if ff.get("cpu_s") is not None else ""
            lines.append(f"{label}: {ff['logged_s']:.2f} s after process start as logged{cpu}; "
                         f"{ff['wall_s']:.2f} s wall until the line appeared")
        else:
            lines.append(f"{label}: not measured: {ff['reason']}")
    return "\n".join(lines)


def write_chart(rows: list[dict], path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = [f"{r['triangles']:,}\n{r['shading']}" for r in rows]
    x = np.arange(len(rows))
    ours = [r["ours"]["median"] for r in rows]
    gl = [r["llvmpipe"]["median"] for r in rows]
    fig, ax = plt.subplots(figsize=(max(6.0, 0.8 * len(rows) + 2), 4.5))
    width = 0.4
    for offset, values, key, name in ((-width / 2, ours, "ours", "ours (CPU pipeline + upload)"),
                                      (width / 2, gl, "llvmpipe", "llvmpipe (OpenGL, draw + finish)")):
        lo = [v - r[key]["min"] for v, r in zip(values, rows)]
        hi = [r[key]["max"] - v for v, r in zip(values, rows)]
        ax.bar(x + offset, values, width, yerr=[lo, hi], capsize=2, label=name)
    ax.set_yscale("log")
    ax.set_ylabel("frame time, ms (median, min–max)")
    ax.set_xticks(x, labels, fontsize=8)
    # sphere_torus_1000, sphere_torus_10000, ... → sphere_torus
    scene_names = sorted({re.sub(r"_\d+$", "", r["scene"]) for r in rows})
    ax.set_title(f"{', '.join(scene_names)}: {rows[0]['size'][0]} x {rows[0]['size'][1]}, "
                 f"{rows[0]['projection']}, ours vs llvmpipe")
    ax.legend()
    ax.grid(axis="y", which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


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
            _progress(f"{scene.name}: {scene.triangle_count:,} triangles uploaded to llvmpipe "
                      f"in {time.perf_counter() - t:.2f} s")
            comparable = bool(scene.lights) and projection == "perspective"
            if comparable:
                lean.load(scene)
                _progress(f"{scene.name} {scene.triangle_count:,}: the numba floor ...")
                floor = time_floor(Floor(scene, size), scene.views[0], frames, warmup)
            for shading in shadings:
                _progress(f"{scene.name} {scene.triangle_count:,} {shading}: ours ...")
                ours = time_ours(scene, projection, shading, size, frames, warmup, blit)
                _progress(f"{scene.name} {scene.triangle_count:,} {shading}: llvmpipe ...")
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
                    _progress(f"{scene.name} {scene.triangle_count:,} {shading}: 1 thread ...")
                    row["threads"] = thread_scaling(scene, projection, shading, size, frames,
                                                    warmup, blit)
                rows.append(row)
                _progress(f"    ours {ours['median']:.2f} ms, llvmpipe {ref['median']:.2f} ms, "
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
    _progress("building scenes ...")
    scenes = _scenes(args)
    rows = run_cases(scenes, args.shading, args.projection, args.size, args.frames, args.warmup,
                     threads=not getattr(args, "no_threads", False))

    _progress("lighting: float32 passes against the float64 kernels ...")
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
    if args.renderer == "raytrace":
        return raytrace_bench(args)
    if args.renderer == "volume":
        from app.bench.volume_bench import run as volume_run
        return volume_run(args)
    chosen = args.renderer.split(",")
    if any(name in PAINTERS for name in chosen):
        from app.bench.painters_bench import run
        return run(args, chosen)
    if any(name in GI_RENDERERS for name in chosen):
        from app.bench.gi_bench import main as gi_main
        return gi_main(args)
    return None


def _startup_times(args) -> dict:
    """The JIT's cold and warm starts and the viewer's first frames (none with --no-startup)."""
    startup = {}
    if not args.no_startup:
        _progress("JIT cold and warm start (fresh processes) ...")
        startup["jit"] = jit_start_times()
        _progress("python -m app view under Xvfb, to the first frame ...")
        startup["first_frame_warm"] = first_frame_time()
        startup["first_frame_warm_torus"] = first_frame_time(scene="scenes/torus.toml")
        _progress("python -m app view with an empty JIT cache ...")
        startup["first_frame_cold"] = first_frame_time(cold=True)
        _progress("first picture of every shipped scene (warm cache) ...")
        startup["first_frame_scenes"] = first_frame_scenes()
    return startup


def _depth_rows(args):
    if getattr(args, "no_depth", False):
        return None
    _progress("depth complexity: 100 layers of 10k triangles ...")
    return depth_complexity(args.size, min(args.frames, 7), min(args.warmup, 1))


def _animation_rows(args):
    if args.no_animation:            # the fountain and the fly-around, 1 process and 2 workers
        return None
    _progress("animation: the fountain and the fly-around at 500 x 500 on 1 process and "
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
        _progress("the full Stanford bunny is not on this machine: the glass bunny is the "
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
    from core.raytrace.renderer import TraceOptions, prepare, primary, render_raw
    _progress(f"{label}: build, primary rays, Whitted frames ...")
    bvh.build(np.eye(3), [[0, 1, 2]])                 # load the compiled build first
    geometry._cache.pop(scene, None)                  # time the build from nothing
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
    from core.raytrace.renderer import TraceOptions, prepare, render_raw
    from core.scene.formats import load_scene
    from core.scene.primitives import Sphere
    _progress(f"{SPHERES:,} spheres: {small}² and {large}² frames ...")
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

