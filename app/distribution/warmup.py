"""``python -m app warmup``: compile every kernel once, saying how far along it is.

numba compiles a kernel the first time it runs with given argument types and keeps the machine
code on disk (``cache=True``); later processes load it in a fraction of a second. Without this
step the first frame of each shading mode would compile in front of the user (seconds each).
``make`` runs it when it creates ``.venv``; the window runs the same steps in the background
after its first frame, so that switching modes later loads cached kernels off the UI thread.

:func:`app.distribution.warmup_steps.steps` lists one small render per path through the
renderers: every shading mode, both projections and both rasterizers, a closed mesh large
enough for the parallel set-up (back-face culling, ≥ 10 000 triangles), an open one
(two-sided lighting), lines, and several samples a pixel.
:func:`~app.distribution.warmup_steps.scene_steps` then opens every shipped scene
(``scenes/``) the way the window does (:class:`app.session.state.ViewerState`), in every
renderer and shading, and in every texture filter when it has textures, so that no first
picture the user asks for compiles (``tests/app/distribution/test_warmup_complete.py`` checks
it from an empty kernel cache).

The steps run in worker processes, one a core (``--jobs``), each taking the next step from
one queue, the longest first by :data:`COSTS` (``app/distribution/warmup_pool.py``). When every step
has succeeded a stamp says the cache is warm (``app/distribution/warm_stamp.py``: :func:`is_warm`).
``--progress-json`` prints one JSON object a line instead of the table, and
:class:`app.distribution.background_warmup.BackgroundWarmup` runs the whole thing as a
subprocess for the window, so that the window opens at once and its kernels compile beside
it.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import sys
import threading
import time
from pathlib import Path

from app.distribution.warm_stamp import is_warm  # noqa: F401  (the viewer's import)
from app.distribution.warmup_steps import foundation_label, opening_label, step_scenes
from app.loading import shipped_scenes  # noqa: F401  (tests and the smoke set read it here)


def compile_bytecode() -> bool:
    """Write the ``.pyc`` of ``app`` and ``core`` now: a process started with
    PYTHONDONTWRITEBYTECODE (or from a read-only checkout) would otherwise compile every
    module from source at each start, about 0.1 s before the first picture."""
    import compileall
    from core.paths import ROOT
    return all(compileall.compile_dir(ROOT / package, quiet=2) for package in ("app", "core"))


# Seconds each step took from an empty kernel cache, all of them one after another in one
# process (`python -m app.distribution.compile_profile --json F`, its "steps"; a 2-core
# machine): the scheduler starts the longest first, so that no long step is left for the
# end while the other cores idle. A step's cost includes the kernels it was the first to
# need; a step not listed counts as DEFAULT_COST. Refresh it when the steps change.
COSTS: dict[str, float] = {
    "ray traced (Whitted)": 37.13,
    "flat, perspective, edge rasterizer": 13.70,
    "rigid bodies": 11.71,
    "volume: marching cubes": 10.75,
    "BSP tree (painter's)": 10.75,
    "volume: emission-absorption and MIP": 10.74,
    "path traced": 8.17,
    "linkages (both IK solvers)": 7.39,
    "depth sort (painter's), depth-cued": 6.71,
    "terrain.toml, every renderer, shading and filter": 6.52,
    "blocks_falling.toml, every renderer, shading and filter": 5.38,
    "big.toml, every renderer, shading and filter": 5.37,
    "phong, perspective, edge rasterizer": 5.28,
    "bump_demo.toml, every renderer, shading and filter": 4.80,
    "the Liang-Barsky and homogeneous clippers": 4.60,
    "phong, the float64 kernels": 4.24,
    "flat, the float64 kernels": 4.24,
    "gouraud, the float64 kernels": 3.65,
    "radiosity (raycast)": 3.55,
    "scan-line visible surface (Watkins)": 3.42,
    "arm_torques.toml, every renderer, shading and filter": 3.35,
    "fast_wheel.toml, every renderer, shading and filter": 3.05,
    "two-pass (radiosity, then rays)": 2.93,
    "barr_deformations.toml, every renderer, shading and filter": 2.66,
    "flat, perspective, open mesh and lines": 2.21,
    "texture_bump_sphere.toml, every renderer, shading and filter": 1.94,
    "flat, perspective, scanline rasterizer": 1.94,
    "flat, 50k faces culled on all cores": 1.85,
    "cook_torrance.toml, every renderer, shading and filter": 1.85,
    "radiosity (hemicube)": 1.75,
    "texture_env_normal.toml, every renderer, shading and filter": 1.48,
    "whitted.toml, every renderer, shading and filter": 1.37,
    "wireframe, perspective": 1.26,
    "depth, perspective, edge rasterizer": 0.98,
    "texture_sphere_torus.toml, every renderer, shading and filter": 0.89,
    "refraction.toml, every renderer, shading and filter": 0.86,
    "flat, 4 samples a pixel": 0.71,
    "volume_mip.toml, every renderer, shading and filter": 0.70,
    "glass_bunny.toml, every renderer, shading and filter": 0.70,
    "gouraud, perspective, edge rasterizer": 0.64,
    "a large frame in two batches (early z)": 0.60,
    "mocap_walk.toml, every renderer, shading and filter": 0.55,
    "texture_floor.toml, every renderer, shading and filter": 0.50,
    "cornell_box.toml, every renderer, shading and filter": 0.44,
    "flock.toml, every renderer, shading and filter": 0.39,
    "volume_isosurface.toml, every renderer, shading and filter": 0.37,
    "gouraud, perspective, open mesh and lines": 0.33,
    "bezier.toml, every renderer, shading and filter": 0.32,
    "fountain.toml, every renderer, shading and filter": 0.31,
    "reactive_chase.toml, every renderer, shading and filter": 0.27,
    "sphere.toml, every renderer, shading and filter": 0.23,
    "update_dynamics.toml, every renderer, shading and filter": 0.20,
    "volume_phantom.toml, every renderer, shading and filter": 0.18,
    "torus.toml, every renderer, shading and filter": 0.17,
    "two_pass.toml, every renderer, shading and filter": 0.16,
    "icosphere.toml, every renderer, shading and filter": 0.13,
    "transparent_pane.toml, every renderer, shading and filter": 0.12,
    "house_flyaround.toml, every renderer, shading and filter": 0.12,
    "robot_arm.toml, every renderer, shading and filter": 0.11,
    "crossing_front_plane.tri, every renderer, shading and filter": 0.11,
    "snow_house.toml, every renderer, shading and filter": 0.08,
    "house_mirror.toml, every renderer, shading and filter": 0.07,
    "radiosity_room.toml, every renderer, shading and filter": 0.07,
    "particle_constraints.toml, every renderer, shading and filter": 0.06,
    "fireworks.toml, every renderer, shading and filter": 0.06,
    "three_bars.toml, every renderer, shading and filter": 0.06,
    "volume_alone.toml, every renderer, shading and filter": 0.05,
    "smoke.toml, every renderer, shading and filter": 0.05,
    "house_solid.obj, every renderer, shading and filter": 0.05,
    "interpenetrating.tri, every renderer, shading and filter": 0.05,
    "few_triangles.tri, every renderer, shading and filter": 0.05,
    "mach_bands.toml, every renderer, shading and filter": 0.05,
    "cube.toml, every renderer, shading and filter": 0.04,
    "pierced_triangles.tri, every renderer, shading and filter": 0.04,
    "house_depth_cue.toml, every renderer, shading and filter": 0.03,
    "house.toml, every renderer, shading and filter": 0.02,
    "house_projections.toml, every renderer, shading and filter": 0.01,
    "gouraud, perspective, scanline rasterizer": 0.00,
    "phong, perspective, scanline rasterizer": 0.00,
    "phong, perspective, open mesh and lines": 0.00,
    "depth, perspective, open mesh and lines": 0.00,
    "flat, parallel, scanline rasterizer": 0.00,
    "depth, perspective, scanline rasterizer": 0.00,
    "gouraud, parallel, scanline rasterizer": 0.00,
    "gouraud, parallel, open mesh and lines": 0.00,
    "flat, parallel, open mesh and lines": 0.00,
    "depth, parallel, open mesh and lines": 0.00,
    "phong, parallel, open mesh and lines": 0.00,
    "flat, parallel, edge rasterizer": 0.00,
    "depth, parallel, scanline rasterizer": 0.00,
    "gouraud, parallel, edge rasterizer": 0.00,
    "phong, parallel, scanline rasterizer": 0.00,
    "wireframe, parallel": 0.00,
    "phong, parallel, edge rasterizer": 0.00,
    "depth, parallel, edge rasterizer": 0.00,
}
DEFAULT_COST = 5.0


def add_arguments(parser: argparse.ArgumentParser) -> argparse.ArgumentParser:
    """The options of ``python -m app warmup``."""
    parser.add_argument("--jobs", type=int, default=None, metavar="N",
                        help="worker processes (default: one a core)")
    parser.add_argument("--progress-json", action="store_true",
                        help="one JSON object a line instead of the progress table")
    parser.add_argument("--first", default=None, metavar="PATH",
                        help="first, the picture this file opens on (the window's first "
                             "frame)")
    parser.add_argument("--only", action="append", default=None, metavar="TEXT",
                        help=argparse.SUPPRESS)     # steps whose label contains TEXT (tests)
    parser.add_argument("--extra-steps", default=None, metavar="MODULE:FUNCTION",
                        help=argparse.SUPPRESS)     # more (label, run) steps (tests)
    parser.add_argument("--stamp", default=None, metavar="PATH",
                        help=argparse.SUPPRESS)     # the stamp's path (tests)
    parser.add_argument("--until-stdin-closes", action="store_true",
                        help=argparse.SUPPRESS)     # the window's: end when the window has gone
    parser.add_argument("--nice", type=int, default=0, metavar="N",
                        help="lower the warm-up's priority by N (0-19; the window's warm-up "
                             "runs at 19, so that its frames come first)")
    return parser


def _lower_priority(by: int) -> str | None:
    """This process's scheduling priority lowered by ``by`` (its workers inherit it); what
    went wrong, or None. The window's warm-up renders every shipped scene after compiling:
    at the window's own priority it took half of each core from a drag (the bunny at
    500 x 500: 26 pictures a second against 42 without it)."""
    if by <= 0:
        return None
    if not hasattr(os, "nice"):
        return "this system cannot lower a process's priority: the warm-up runs at the window's"
    try:
        os.nice(min(by, 19))
    except OSError as error:
        return f"the warm-up's priority could not be lowered ({error}); it runs at the window's"
    return None


def _end_when_stdin_closes() -> None:
    """A daemon thread that interrupts the warm-up (as SIGTERM does) once standard input is
    closed: the window that started it holds the other end, so a window that is killed or
    crashes does not leave this process compiling on."""
    def watch():
        try:        # the raw descriptor: a daemon thread in a buffered read aborts at exit
            while os.read(0, 4096):
                pass
        except OSError:
            pass
        os.kill(os.getpid(), signal.SIGTERM)
    threading.Thread(target=watch, name="end with the window", daemon=True).start()


def _options(args) -> argparse.Namespace:
    """``args`` as parsed by app/cli_arguments.py (which may not know these options yet: their
    defaults), a list of strings, or None (``sys.argv``)."""
    parser = add_arguments(argparse.ArgumentParser(prog="python -m app warmup"))
    if args is None or isinstance(args, (list, tuple)):
        return parser.parse_args(args)
    defaults = parser.parse_args([])
    for name, value in vars(defaults).items():
        if not hasattr(args, name):
            setattr(args, name, value)
    return args


class _Interrupted(KeyboardInterrupt):
    """SIGTERM, handled as Ctrl-C is."""


def _on_sigterm(signum, frame):
    raise _Interrupted()


class _Report:
    """What a warm-up run says: JSON events (``--progress-json``, for the window) or lines."""

    def __init__(self, as_json: bool):
        self.as_json = as_json
        self.out = sys.stdout                   # where the lines go, as when the run began
        self.finished: list = []
        self.total, self.scenes, self.first = 0, {}, None

    def emit(self, event: dict) -> None:
        try:
            print(json.dumps(event), flush=True)
        except BrokenPipeError:               # the reader (a window) has gone: no one to tell
            sys.stdout = open(os.devnull, "w")

    def say(self, text: str) -> None:
        if not self.as_json:
            print(text, file=self.out, flush=True)

    def start(self, total: int, jobs: int, scenes: dict, first: str | None) -> None:
        self.total, self.scenes, self.first = total, scenes, first
        if self.as_json:
            self.emit({"event": "start", "total": total, "jobs": jobs})
        else:
            self.say(f"  {total} steps on {jobs} worker process{'es' if jobs > 1 else ''}")

    def on_begin(self, label) -> None:
        if self.as_json:
            self.emit({"event": "begin", "label": label, "scenes": self.scenes.get(label, [])})

    def on_outcome(self, outcome) -> None:
        self.finished.append(outcome)
        k, n = len(self.finished), self.total
        common = {"k": k, "total": n, "label": outcome.label,
                  "seconds": round(outcome.seconds, 3),
                  "scenes": self.scenes.get(outcome.label, [])}
        if self.first is not None and outcome.label == opening_label(self.first):
            common["opens"] = self.first        # the window's first picture will load now
        if outcome.error is None:
            if self.as_json:
                self.emit({"event": "done", **common})
            self.say(f"  [{k:2d}/{n}] {outcome.label}: {outcome.seconds:.2f} s")
        elif self.as_json:
            self.emit({"event": "failed", **common, "error": outcome.error})
        else:
            print(f"  [{k:2d}/{n}] FAILED {outcome.label}: {outcome.error}",
                  file=sys.stderr, flush=True)


def main(args=None) -> int:
    """``python -m app warmup``: every step on ``--jobs`` workers; the stamp when all succeed.
    Exit status 0 when every step succeeded, 1 when one failed, 130 when interrupted."""
    options = _options(args)
    report = _Report(options.progress_json)
    stamp = _stamp_to_write(options)
    report.say("warming up: compiling the kernels once (numba keeps them on disk)")
    problem = _lower_priority(options.nice)
    if problem:                                 # (the window's warm-up.log: its stderr)
        print(f"warm-up: {problem}", file=sys.stderr, flush=True)
    if not compile_bytecode():
        report.say("  (some Python bytecode could not be written: starts will compile it)")
    todo, scenes, first = _steps_to_run(options)
    jobs = _job_count(options, todo)
    report.start(len(todo), jobs, scenes, first)
    ran = _run_steps(options, todo, jobs, first, report)
    if ran is None:
        return 130
    outcomes, seconds = ran
    return _finish(outcomes, seconds, stamp, jobs, report)


def _stamp_to_write(options) -> Path | None:
    """The stamp this run writes when all its steps succeed (another version's is removed)."""
    from app.distribution import warm_stamp
    # A run of some steps (--only) says nothing about the whole cache: it writes a stamp only
    # where it is told to (the tests), never the real one.
    partial = bool(options.only or options.extra_steps)
    stamp = Path(options.stamp) if options.stamp else None if partial else warm_stamp.stamp_path()
    if stamp is not None and not warm_stamp.is_warm(stamp):
        warm_stamp.remove(stamp)                # another version's stamp: not ours to keep
    return stamp


def _steps_to_run(options) -> tuple[list, dict, str | None]:
    """(the steps in the order they run, the scenes each warms, the file the window opens)."""
    from app.distribution import warmup_pool
    listed = [label for label, _ in warmup_pool.load_steps(options.extra_steps)]
    if options.only:
        listed = [label for label in listed if any(text in label for text in options.only)]
    scenes = step_scenes()
    first = str(Path(options.first).resolve()) if options.first else None
    if first is not None and not Path(first).is_file():
        first = None                            # nothing to open: no step of its own
    if first is not None:
        listed.append(opening_label(first))
    todo = warmup_pool.order(listed, COSTS, DEFAULT_COST,
                             first=lambda label: label == foundation_label() or (
                                 first is not None and label == opening_label(first)),
                             later=lambda label: label in scenes)
    return todo, scenes, first


def _job_count(options, todo) -> int:
    """--jobs (by default the pool's), never more than there are steps."""
    from app.distribution import warmup_pool
    jobs = options.jobs if options.jobs and options.jobs > 0 else warmup_pool.default_jobs()
    return max(1, min(jobs, len(todo) or 1))


def _run_steps(options, todo, jobs, first, report):
    """Run the steps on the workers: (outcomes, seconds), or None when interrupted (said)."""
    from app.distribution import warmup_pool
    start = time.perf_counter()
    previous = signal.signal(signal.SIGTERM, _on_sigterm)
    if options.until_stdin_closes:
        _end_when_stdin_closes()
    try:
        outcomes = warmup_pool.run_parallel(todo, jobs, extra=options.extra_steps, first=first,
                                            on_begin=report.on_begin,
                                            on_outcome=report.on_outcome)
    except KeyboardInterrupt:
        seconds = time.perf_counter() - start
        if report.as_json:
            report.emit({"event": "finished", "seconds": round(seconds, 3), "ok": False,
                         "interrupted": True, "failed": []})
        else:
            print(f"warm-up interrupted after {seconds:.1f} s ({len(report.finished)} of "
                  f"{len(todo)} steps done; run it again for the rest)", file=sys.stderr,
                  flush=True)
        return None
    finally:
        signal.signal(signal.SIGTERM, previous)
    return outcomes, time.perf_counter() - start


def _finish(outcomes, seconds: float, stamp, jobs: int, report) -> int:
    """Write or remove the stamp, and say how the run went: 0 when every step succeeded."""
    from app.distribution import warm_stamp
    n = report.total
    failed = [outcome for outcome in outcomes if outcome.error is not None]
    if stamp is not None:
        if failed:
            warm_stamp.remove(stamp)
        else:
            warm_stamp.write(seconds, n, stamp)
    if report.as_json:
        report.emit({"event": "finished", "seconds": round(seconds, 3), "ok": not failed,
                     "failed": [outcome.label for outcome in failed]})
    elif failed:
        print(f"warm-up: {len(failed)} of {n} steps failed ("
              + "; ".join(outcome.label for outcome in failed) + "); the cache is not marked "
              "warm", file=sys.stderr, flush=True)
    else:
        report.say(f"warm: {seconds:.1f} s in all on {jobs} worker process"
                   f"{'es' if jobs > 1 else ''}; later starts load the compiled kernels")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
