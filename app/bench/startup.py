"""The bench's start-up rows: the numba JIT's cold and warm start (a fresh process rendering
one frame with an empty and with the normal cache) and the time from ``python -m app`` to the
first frame shown (the viewer under Xvfb, read from its log)."""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from core.paths import ROOT


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
