"""``python -m app animate SCENE --out movie.mp4``: an animation rendered to a movie.

Frames are rendered

- in this process (the default; the particles step on from frame to frame),
- with ``--workers N``, in this process and N - 1 local single-thread worker processes
  (:class:`app.commands.cluster.LocalPool`, started once per job while this process renders
  the first frames), or not at all when a prediction from two measurements (a frame's time
  here, the cores other processes left idle since the command started) says it would not
  win (:func:`predict`; the output says why), or
- on a running Dask cluster (``--scheduler tcp://host:8786``; the workers need only this
  package: the scene file and every file it names travel with the job, content-addressed,
  :mod:`app.commands.bundle`).

On a cluster the frames go out in contiguous runs, long first and short at the end
(:class:`Runs`), each with the particle state at its first frame
(:mod:`core.animation.checkpoint`, from a simulation-only pass here), so no worker simulates
from t = 0; a run that fails is retried by Dask (``--retries``). Frames come back as PNG bytes
and pixels: the PNG is written, as it completes, into the frames folder, which makes a killed
run resumable, and the pixels go to the MP4 encoder in order
(:class:`~app.commands.movie_files.Movie`), so the movie is encoded while the frames are
rendered (a GIF at the end): all on a writer thread beside the rendering (:class:`FrameWriter`;
a frame rendered here is made into its PNG there too). The folder is removed after the movie
(``--keep-frames`` keeps it). Progress and an ETA go to stderr.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import sys
import time
from collections import deque
from pathlib import Path

import numpy as np

from app.commands.movie_files import (MOVIE_SUFFIXES, FolderError, Movie, clean_folder,
                                   frame_png, frames_folder, movie_rate, out_problem,
                                   prepare_folder, write_frame)

MAX_FRAMES = 100_000
MIN_FPS, MAX_FPS = 1e-3, 1000.0
MAX_RETRIES = 100
CLUSTER_START_SECONDS = 1.0    # from starting local workers to their first frames back
                               # (measured here: ready 0.5 s after the start, a first run of
                               # the fly-around back at 0.9 s: the package, kernels, scene)
MIN_GAIN = 1.2                 # local workers start only when predicted this much faster
WORKER_SHARE = 0.35            # of a core, what a second process adds here: with this one
                               # writing on a thread of its own, the workers' start, the
                               # checkpoints and the pixels sent back leave 0.2-0.35 (the
                               # fountain, the fly-around, 500 x 500, two cores); 0.7 before
RUN_SHARE = 2                  # a run is at most 1/(RUN_SHARE x renderers) of what is left
MAX_RUN = 30                   # frames in one run at most
RENDER_WHILE_STARTING = True   # this process renders while a local cluster starts
HEAD = 4                       # frames here before deciding on workers (the first untimed)


def add_arguments(p: argparse.ArgumentParser, parse_size) -> None:
    """The options of ``animate`` (the sub-parser and ``WxH`` parser come from ``app/cli.py``)."""
    from core.settings import PROJECTIONS
    p.add_argument("scene", help="a scene file with [animation], [[key]] or [[emitter]] tables")
    p.add_argument("--out", required=True,
                   help="movie.mp4 (H.264), movie.gif, or a folder for a PNG sequence; the "
                        "movie's folder must exist, and an existing file that is not an MP4 or "
                        "GIF is kept unless --force")
    p.add_argument("--force", action="store_true",
                   help="replace an existing --out that is not a movie; render over frames "
                        "that are not this job's")
    p.add_argument("--keep-frames", action="store_true",
                   help="keep the frames folder (NAME.frames/) after the movie is written")
    p.add_argument("--fps", type=_number(float, MIN_FPS, MAX_FPS), default=None,
                   help=f"frames per second, {MIN_FPS:g} to {MAX_FPS:g} (default: the scene's)")
    length = p.add_mutually_exclusive_group()
    length.add_argument("--frames", type=_number(int, 1, MAX_FRAMES), default=None,
                        help=f"how many frames (at most {MAX_FRAMES})")
    length.add_argument("--duration", type=_number(float, 0.0, math.inf, low_open=True),
                        default=None, help="seconds")
    p.add_argument("--size", type=parse_size, default=None, help="WxH (default: the scene's)")
    p.add_argument("--renderer", default=None, help="a registered renderer (default: zbuffer)")
    p.add_argument("--samples", type=_number(int, 1, 1024), default=None, help="samples per pixel")
    p.add_argument("--motion-blur", type=_number(int, 1, 1024), default=None, metavar="SAMPLES",
                   help="motion blur: SAMPLES times a frame over the shutter interval (the "
                        "ray tracer: a time per ray, SAMPLES rays a film sample; the others: "
                        "the mean of SAMPLES frames, the accumulation buffer; 1: sharp; "
                        "default: the scene's [animation] motion_blur, else 1)")
    p.add_argument("--shutter", type=_number(float, -1.0, 1.0), nargs=2, default=None,
                   metavar=("OPEN", "CLOSE"),
                   help="when the shutter opens and closes, in frames from the frame's time "
                        "(default -0.25 0.25: a 180-degree shutter centred on it)")
    p.add_argument("--blur-method", choices=("auto", "accumulate", "per-ray"), default=None,
                   help="how the motion blur is sampled: accumulate whole frames, or (the ray "
                        "tracer's) a time per ray; auto (default): per-ray for the ray tracer, "
                        "accumulate for the others")
    p.add_argument("--projection", choices=PROJECTIONS, default=None)
    p.add_argument("--shading", default=None, help="wireframe | flat | gouraud | phong | …")
    p.add_argument("--view", type=_number(int, 1, 10 ** 6), default=None, metavar="K",
                   help="the file's view K (its position in the file, counting from 1, as "
                        "everywhere); default: the keyed view, or the first valid view")
    p.add_argument("--paths", action="store_true",
                   help="draw the keyed paths (the eye, objects, lights) over every frame")
    p.add_argument("--workers", type=_number(int, 1, 10 ** 4), default=1, metavar="N",
                   help="renderers on this machine: this process and N - 1 worker processes "
                        "(a Dask LocalCluster; at most one a core, and as many as the memory "
                        "holds; none when they cannot win: a short job, a busy machine)")
    p.add_argument("--scheduler", default=None, metavar="ADDR",
                   help="address of a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--retries", type=_number(int, 0, MAX_RETRIES), default=2,
                   help="tries again per failed frame (or run of frames on a cluster)")
    p.add_argument("--crf", type=_number(int, 0, 51), default=18,
                   help="H.264 quality, 0 (lossless) to 51")


def _number(kind, low, high, low_open=False):
    """An argparse type: a finite ``kind`` in [low, high] ((low, high] with ``low_open``)."""
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a {'whole ' if kind is int else ''}"
                                             f"number, got {text!r}") from None
        inside = (value > low if low_open else value >= low) and value <= high
        if not (math.isfinite(value) and inside):
            bounds = f"greater than {low:g}" if low_open else f"at least {low:g}"
            if math.isfinite(high):
                bounds = f"{'above' if low_open else 'from'} {low:g} {'up ' if low_open else ''}to {high:g}"
            raise argparse.ArgumentTypeError(f"must be {bounds} (a finite number), got {text!r}")
        return value
    return parse


# ---------------------------------------------------------------------- the job


class JobError(ValueError):
    """The options cannot make a movie of this scene; the message says which and why."""


def job_of(args, animation, bundle, view_index: int) -> dict:
    """Everything a worker needs to render any frame, as plain data (sent to every worker)."""
    scene = animation.scene
    fps = args.fps or animation.fps
    if not MIN_FPS <= fps <= MAX_FPS:
        raise JobError(f"the scene's fps {fps:g} is outside {MIN_FPS:g} to {MAX_FPS:g}")
    seconds = args.duration if args.duration else animation.duration
    count = args.frames or max(1, round(min(seconds * fps, 2.0 * MAX_FRAMES)))
    if count > MAX_FRAMES:
        raise JobError(f"{'--duration ' + format(args.duration, 'g') if args.duration else 'the scene'}"
                       f" at {fps:g} fps is {seconds * fps:.3g} frames; at most {MAX_FRAMES} "
                       "are rendered")
    settings = {"size": list(args.size or scene.size), "samples": args.samples or 1,
                "projection": args.projection or scene.projection,
                "shading": args.shading or scene.shading,
                "renderer": args.renderer or "zbuffer", "view": view_index, "paths": args.paths}
    shutter = _shutter(args, animation)
    if shutter.method == "per-ray" and not _blurs_per_ray(settings["renderer"]):
        from core.renderers import names_that
        raise JobError(f"--blur-method per-ray is the ray tracer's: give --renderer "
                       f"{' or '.join(names_that('blur_per_ray'))} (the other renderers "
                       f"accumulate whole frames)")
    if shutter.samples > 1 or getattr(animation, "shutter", None) is not None:
        # (recorded only where frames are blurred, or kept sharp against the scene's
        # blur: the sharp jobs of sharp scenes keep the hash they had)
        settings["motion_blur"] = [shutter.samples, shutter.open, shutter.close]
        if shutter.method != "auto":          # (auto keeps the hash jobs had before)
            settings["motion_blur"].append(shutter.method)
    return {"scene": Path(args.scene).name, "bundle": bundle.digest, "fps": fps,
            "frames": int(count), "settings": settings,
            "load_size": list(args.size) if args.size else None}


def _blurs_per_ray(name: str) -> bool:
    """Whether renderer ``name`` may give each primary ray its own time (False for a name
    that is no renderer's: the job's settings check words that)."""
    from core.renderers import get_renderer, renderer_names
    return name in renderer_names() and get_renderer(name).blur_per_ray


def _shutter(args, animation):
    """The options' :class:`~core.animation.frames.Shutter`, else the scene file's (None:
    sharp); JobError when it cannot be."""
    from core.animation.frames import Shutter
    scene = getattr(animation, "shutter", None)
    samples = getattr(args, "motion_blur", None)
    opening = getattr(args, "shutter", None)
    if samples is None:
        samples = scene.samples if scene is not None else 1
    if opening is not None and samples == 1:
        raise JobError("--shutter is the motion blur's: give --motion-blur SAMPLES too")
    if opening is None and scene is not None:
        opening = (scene.open, scene.close)
    method = getattr(args, "blur_method", None)
    if method not in (None, "auto") and samples == 1:
        raise JobError("--blur-method is the motion blur's: give --motion-blur SAMPLES too")
    try:
        return Shutter(samples, *(opening or (Shutter.open, Shutter.close)), method or "auto")
    except ValueError as error:
        raise JobError(f"--shutter: {error}") from None


def job_shutter(job: dict):
    from core.animation.frames import Shutter
    blur = job["settings"].get("motion_blur")
    return Shutter(*blur) if blur else None


def job_hash(job: dict) -> str:
    """What every frame of the job carries: the hash of what its pixels depend on."""
    same = {k: v for k, v in job.items() if k not in ("frames", "scene", "path")}
    return hashlib.sha256(json.dumps(same, sort_keys=True).encode()).hexdigest()[:32]


def _settings_problem(job: dict, animation) -> str | None:
    """What is wrong with the job's settings (a renderer, shading or sample count that does not
    exist), found once here rather than as the same failure of every frame."""
    from core.renderers import get_renderer
    from core.registry import shading_names
    from core.settings import RenderSettings
    s = job["settings"]
    try:
        RenderSettings.for_scene(animation.scene, size=tuple(s["size"]), samples=s["samples"],
                                 projection=s["projection"], shading=s["shading"],
                                 renderer=s["renderer"])
        get_renderer(s["renderer"])
    except ValueError as error:
        return str(error)
    if s["shading"] not in shading_names():
        return f"shading must be one of {', '.join(shading_names())}, not {s['shading']!r}"
    return None


def view_index_of(scene, animation, number: int | None) -> int:
    """The index in ``scene_at(t).views`` of ``--view number`` (the file's view, by position;
    the keyed view, or else the first valid one, when None); ViewNumberError when invalid."""
    from core.scene.view_numbers import index_of
    keyed = animation.view is not None
    if number is None:
        return 0
    return int(keyed) + index_of(scene, number)


# ---------------------------------------------------------------------- rendering a frame

_loaded: dict = {}


def _animation(path: str, size=None):
    """The animation of a scene file, loaded once per process (and again if the file changed)."""
    from core.animation.animation import Animation
    from core.animation.keys import animation_of
    from core.scene.formats import load_scene
    key = (path, os.stat(path).st_mtime_ns, tuple(size) if size else None)
    if _loaded.get("key") != key:
        scene = load_scene(path, size=tuple(size) if size else None)
        _loaded["animation"] = animation_of(scene) or Animation(scene=scene)
        _loaded["key"] = key
    return _loaded["animation"]


def render_frame(job: dict, k: int, animation=None) -> tuple[int, bytes, np.ndarray]:
    """Frame k of the job: ``(k, PNG bytes signed with the job's hash, RGB pixels)`` (the
    pixels go to the movie's encoder, which need not decode the PNG)."""
    color = render_pixels(job, k, animation)
    return k, frame_png(color, job_hash(job), k), color


def render_pixels(job: dict, k: int, animation=None) -> np.ndarray:
    """Frame k of the job, its RGB pixels."""
    from core.animation.frames import render_at
    from core.settings import RenderSettings
    animation = animation or _animation(job["path"], job.get("load_size"))
    s = job["settings"]
    settings = RenderSettings.for_scene(animation.scene, size=tuple(s["size"]),
                                        samples=s["samples"], projection=s["projection"],
                                        shading=s["shading"], renderer=s["renderer"])
    frame = render_at(animation, k / job["fps"], settings, view_index=s["view"],
                      paths=s["paths"], shutter=job_shutter(job))
    if frame.message:
        raise RuntimeError(f"frame {k}: {frame.message}")
    return frame.color


def render_run(job: dict, bundle, frames: list[int], checkpoint=None) -> list[tuple]:
    """A worker's task: the contiguous ``frames`` of the job, the scene read from the bundle
    (unpacked once per worker), the simulations restored from ``checkpoint`` (their state at
    the first frame), so that nothing is simulated from t = 0."""
    from app.commands.bundle import unpack
    animation = _animation(str(unpack(bundle)), job.get("load_size"))
    if checkpoint is not None:
        from core.animation.checkpoint import restore_animation
        restore_animation(animation, checkpoint)
    return [render_frame(job, k, animation) for k in frames]


# ---------------------------------------------------------------------- progress


class Progress:
    """The frames done, on the command's progress line (:class:`app.progress_line.ProgressLine`:
    ``rendering the frames: frame 12 of 90 (13 %); 6 s, about 37 s left``, shown once the
    command has run a second or two, silent with -q); counted as the frames are written."""

    def __init__(self, total: int, done: int, line=None):
        from app.progress_line import ProgressLine
        self.total, self.done = total, done
        self.line = line or ProgressLine()
        self.line(FRAMES, done, total, "frame")

    def tick(self) -> None:
        self.done += 1
        self.line(FRAMES, self.done, self.total, "frame")

    def say(self, line: str) -> None:
        self.line.say(line)

    def finish(self) -> None:
        self.line.finish()


FRAMES = "rendering the frames"


class FrameWriter:
    """Frames made into PNGs, written to the folder and encoded into the movie on a thread of
    its own, in the order they come, while the next frame renders: Pillow's zlib and x264 let
    go of Python's lock, so the two run on two cores (one process's fly-around spent 12 of its
    18 ms a frame on these after rendering). At most DEPTH frames wait. A write that fails
    stops the writing; :meth:`put` and :meth:`close` raise its error in the caller."""

    DEPTH = 4

    def __init__(self, consume):
        import queue
        import threading
        self.consume, self.error = consume, None
        self.queue = queue.Queue(maxsize=self.DEPTH)
        self.thread = threading.Thread(target=self._run, name="frame writer", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while (item := self.queue.get()) is not None:
            if self.error is None:
                try:
                    self.consume(*item)
                except BaseException as error:              # noqa: BLE001 - raised in put
                    self.error = error
            self.queue.task_done()

    def put(self, *item) -> None:
        if self.error is not None:
            raise self.error
        self.queue.put(item)

    def wait(self) -> None:
        """Until every frame put so far is written (or the writing stopped)."""
        self.queue.join()

    def close(self) -> None:
        """Write what waits; raise a write's error."""
        if self.thread.is_alive():
            self.queue.put(None)
            self.thread.join()
        if self.error is not None:
            raise self.error


# ---------------------------------------------------------------------- running the frames


def _one_line(error: BaseException) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return f"{type(error).__name__}: {text}" if not isinstance(error, RuntimeError) else text


def render_here(job, frames, on_frame, retries: int, animation, failed: list,
                stop=lambda: False) -> int:
    """Render ``frames`` in this process, in order, until ``stop()``; returns how many were
    taken (rendered or failed). Each goes to ``on_frame(k, None, pixels)``: its PNG is made
    where it is written (:class:`FrameWriter`), beside the next frame's rendering."""
    taken = 0
    for k in frames:
        if stop():
            break
        for attempt in range(retries + 1):
            try:
                pixels = render_pixels(job, k, animation)
            except Exception as error:                      # noqa: BLE001 - reported per frame
                if attempt == retries:
                    failed.append(([k], _one_line(error)))
            else:
                on_frame(k, None, pixels)
                break
        taken += 1
    return taken


class Runs:
    """The frames still to deal, cut on demand into contiguous runs (a gap starts a new one)
    whose length follows what is left (guided self-scheduling): long runs first, few
    checkpoints and round trips; short ones at the end, so that every renderer finishes at
    about the same time instead of one waiting for another's long last run."""

    def __init__(self, frames: list[int], renderers: int):
        self.left, self.renderers = deque(frames), max(1, renderers)

    def __bool__(self) -> bool:
        return bool(self.left)

    def next(self) -> list[int]:
        length = max(1, min(MAX_RUN, math.ceil(len(self.left) / (RUN_SHARE * self.renderers))))
        run = [self.left.popleft()]
        while self.left and len(run) < length and self.left[0] == run[-1] + 1:
            run.append(self.left.popleft())
        return run


def render_on_cluster(client, job, bundle, frames, on_frame, retries: int, animation,
                      failed: list, workers: int, here: bool = False) -> None:
    """Deal ``frames`` to the cluster in runs (:class:`Runs`), each with the particles'
    checkpoint at its first frame (made here by stepping a copy of the simulation on, no
    picture drawn), two runs in flight a worker; hand each run's frames to ``on_frame`` as
    it completes. With ``here`` this process takes runs from the same queue too, looking at
    what came back between its frames."""
    from app.commands.cluster import completed
    shipped = client.scatter(bundle, broadcast=True, hash=False)
    runs = Runs(frames, workers + here)
    checkpoints = _Checkpoints(animation, job["fps"], job_shutter(job))
    in_flight = {}
    done = completed(client)

    def submit():
        run = runs.next()
        future = client.submit(render_run, job, shipped, run, checkpoints.at(run[0]),
                               retries=retries, pure=False)
        in_flight[future] = run
        done.add(future)

    def collect(futures):
        for future in futures:
            run = in_flight.pop(future)
            try:
                for frame in future.result():
                    on_frame(*frame)
            except Exception as error:                      # noqa: BLE001 - reported per run
                failed.append((run, _one_line(error)))
            if runs:
                submit()

    for _ in range(2 * workers):
        if runs:
            submit()
    while runs or in_flight:
        if here and runs:
            run = runs.next()
            checkpoints.restore(run[0])
            for k in run:
                render_here(job, [k], on_frame, retries, animation, failed)
                if done.has_ready():
                    collect(done.next_batch(block=False))
        else:
            collect(done.next_batch(block=True))


class _Checkpoints:
    """The simulations' state (particles, rigid bodies, flocks) at the first frame of each
    run, asked for in order: copies of the simulations step on from where this process's
    are (simulation only, :class:`core.animation.checkpoint.Shadow`). Without any there is
    nothing to carry (None)."""

    def __init__(self, animation, fps: float, shutter=None):
        from core.animation.checkpoint import Shadow
        self.animation, self.fps, self.shutter = animation, fps, shutter
        self.shadow = Shadow(animation)

    def at(self, k: int):
        """The state at frame k's first time (its shutter's opening when blurred)."""
        t = k / self.fps
        return self.shadow.at(self.shutter.opens(t, self.fps) if self.shutter else t)

    def restore(self, k: int) -> None:
        """Put this process's simulations at frame ``k`` (the start of a run it renders)."""
        from core.animation.checkpoint import restore_animation
        state = self.at(k)
        if state is not None:
            restore_animation(self.animation, state)


def idle_mark() -> tuple[float, float] | None:
    """``(wall clock, seconds every core has been idle)`` now, to measure the idle cores over
    an interval with :func:`idle_cores`; None where the machine does not say."""
    try:
        import psutil                                   # comes with Dask
        return time.perf_counter(), psutil.cpu_times().idle
    except (ImportError, OSError, AttributeError):
        return None


def idle_cores(since: tuple[float, float] | None) -> float:
    """How many cores were idle on average since ``since`` (:func:`idle_mark`): what other
    processes on the machine leave to workers (this process's own core is busy)."""
    now = idle_mark()
    if since is None or now is None or now[0] <= since[0]:
        return float(_cores() - 1)                      # unknown: assume a quiet machine
    return max(0.0, (now[1] - since[1]) / (now[0] - since[0]))


def _cores() -> int:
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def predict(frames: int, seconds: float, workers: int, idle: float,
            used: float = 1.0) -> tuple[float, float]:
    """``(seconds here, seconds with local workers)`` for ``frames`` more frames of
    ``seconds`` each: this process renders alone while the workers start
    (CLUSTER_START_SECONDS), then with ``workers - 1`` workers on the ``idle`` cores
    measured, each adding WORKER_SHARE of a core. ``used``: the cores this process keeps
    busy rendering alone (its kernel threads and the frame writer): its speed is that many
    cores' worth, not one's."""
    here = frames * seconds
    cores = 1 + WORKER_SHARE * min(workers - 1, idle)
    return here, (CLUSTER_START_SECONDS
                  + max(0.0, here - CLUSTER_START_SECONDS) * max(1.0, used) / cores)


def _cannot_win(frames: int, seconds: float, workers: int, idle: float,
                used: float = 1.0) -> str | None:
    """Why local workers would not finish these frames MIN_GAIN times sooner than this
    process by :func:`predict`, or None."""
    here, there = predict(frames, seconds, workers, idle, used)
    if there * MIN_GAIN <= here:
        return None
    return (f"the remaining {frames} frames would take ~{there:.1f} s with {workers - 1} local "
            f"worker{'s' if workers > 2 else ''} (~{CLUSTER_START_SECONDS:g} s to start, "
            f"{idle:.1f} idle core{'' if round(idle, 1) == 1 else 's'} measured) against "
            f"~{here:.1f} s in this process (on {used:.1f} cores): a cluster starts when it "
            f"promises x{MIN_GAIN:g}, this is x{here / max(there, 1e-9):.2f}")


def _one_numba_thread() -> int:
    """This process renders beside the workers: one kernel thread, as each of them has.
    Returns the count before, to restore."""
    import numba
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    return before


def render_frames(args, job, bundle, animation, todo, writer, progress,
                  since=None) -> tuple[list, str | None]:
    """Render ``todo`` where the options say; returns ``(failures, what ran where)``, each
    failure ``(frames, why)``. ``writer`` (:class:`FrameWriter`) takes the frames. ``since``
    (:func:`idle_mark`, taken when the command started) is where the idle cores are measured
    from."""
    from app.commands import cluster
    failed: list = []
    on_frame = writer.put
    if args.scheduler:
        return failed, _render_on_scheduler(args, job, bundle, todo, on_frame, animation, failed)
    workers = args.workers
    if workers > 1 and todo:
        workers, why = cluster.worker_cap(workers)
        if why:
            progress.say(f"note: {why}")
    if workers == 1 or not todo:
        render_here(job, todo, on_frame, args.retries, animation, failed)
        return failed, None
    head, seconds, used = _time_first_frames(job, todo, writer, args.retries, animation, failed)
    todo = todo[head:]
    if not todo:
        progress.say(f"note: --workers {workers}: not starting a local cluster: all {head} "
                     "frames were rendered here while timing one")
        return failed, "in this process (a cluster could not win)"
    idle = idle_cores(since)
    why = _cannot_win(len(todo), seconds, workers, idle, used)
    if why:
        progress.say(f"note: --workers {workers}: not starting a local cluster: {why}")
        render_here(job, todo, on_frame, args.retries, animation, failed)
        return failed, "in this process (a cluster could not win)"
    return failed, _render_beside_local_cluster(job, bundle, animation, todo, writer, args.retries,
                                                failed, progress, workers, head,
                                                (seconds, idle, used))


def _render_on_scheduler(args, job, bundle, todo, on_frame, animation, failed) -> str:
    """All of ``todo`` on the cluster at --scheduler; says where it ran."""
    from app.commands import cluster
    client = cluster.connect(args.scheduler)
    try:
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        render_on_cluster(client, job, bundle, todo, on_frame, args.retries, animation,
                          failed, workers)
    finally:
        client.close()
    return f"on the cluster at {args.scheduler} ({workers} workers)"


def _time_first_frames(job, todo, writer, retries, animation, failed) -> tuple[int, float, float]:
    """A few frames here first: the first may load kernels; the next HEAD - 1, written too,
    time a frame and the cores this process keeps busy, to predict whether a cluster can
    win at all. Returns (frames rendered, seconds a frame, cores used)."""
    on_frame = writer.put
    head = render_here(job, todo[:1], on_frame, retries, animation, failed)
    writer.wait()
    t0, cpu0 = time.perf_counter(), time.process_time()
    timed = render_here(job, todo[1:HEAD], on_frame, retries, animation, failed)
    writer.wait()
    wall = max(time.perf_counter() - t0, 1e-9)
    seconds = wall / max(timed, 1)
    used = max(1.0, (time.process_time() - cpu0) / wall)
    return head + timed, seconds, used


def _render_beside_local_cluster(job, bundle, animation, todo, writer, retries, failed, progress,
                                 workers, head, measured) -> str | None:
    """Start a local cluster of ``workers - 1`` and render here while it starts, then hand it
    what is left; says where the frames ran. ``measured``: (seconds a frame, idle cores,
    cores this process uses)."""
    from app.commands import cluster
    seconds, idle, used = measured
    on_frame = writer.put
    here_s, there_s = predict(len(todo), seconds, workers, idle, used)
    start = cluster.LocalStart(workers - 1, preload=(__name__,))   # this process: the N-th
    threads = _one_numba_thread()                    # a core for the start, then the worker
    try:
        if not RENDER_WHILE_STARTING:
            start.ready.wait()
        here = render_here(job, todo, on_frame, retries, animation, failed,
                           stop=start.ready.is_set)
        if here == len(todo):
            return (f"in this process: it finished before the local cluster started "
                    f"(this process rendered {head + here} frames)")
        if start.error is not None:
            progress.say(f"note: the local cluster did not start ({_one_line(start.error)}): "
                         "rendering here")
            render_here(job, todo[here:], on_frame, retries, animation, failed)
            return None
        render_on_cluster(start.client, job, bundle, todo[here:], on_frame, retries,
                          animation, failed, workers - 1, here=True)
        return (f"this process and {workers - 1} local worker"
                f"{'s' if workers > 2 else ''}, started once in {start.seconds:.1f} s "
                f"while this process rendered {head + here} frames (predicted "
                f"x{here_s / there_s:.2f} with {idle:.1f} idle cores measured, "
                f"this process alone on {used:.1f})")
    finally:
        import numba
        numba.set_num_threads(threads)
        start.close()


# ---------------------------------------------------------------------- the command


def _frames_text(frames: list[int]) -> str:
    """``frame 4``, ``frames 3-9``, ``5 frames (2, 4, 7, ...)``."""
    if len(frames) == 1:
        return f"frame {frames[0]}"
    if frames[-1] - frames[0] == len(frames) - 1:
        return f"frames {frames[0]}-{frames[-1]}"
    shown = ", ".join(map(str, frames[:4])) + (", ..." if len(frames) > 4 else "")
    return f"{len(frames)} frames ({shown})"


def _load(path: str, size=None):
    """The scene, or None after printing the reader's message (:mod:`app.loading`)."""
    from app.loading import load_or_say
    return load_or_say(path, size)


def _error(message: str, code: int) -> int:
    print(f"error: {message}", file=sys.stderr)
    return code


def main(args) -> int:
    since = idle_mark()                                  # the idle cores are measured from here
    out = Path(args.out)
    status = _refused(args, out)
    if status:
        return status
    loaded = _job_to_run(args, out)
    if isinstance(loaded, int):
        return loaded
    job, bundle, animation = loaded
    folder = frames_folder(out)
    todo = _frames_to_render(job, folder, args.force)
    if isinstance(todo, int):
        return todo
    total = job["frames"]
    progress = Progress(total, total - len(todo), getattr(args, "progress", None))
    movie = None
    if out.suffix.lower() in MOVIE_SUFFIXES:             # encoded as the frames come
        movie = Movie(out, folder, total, job["fps"], args.crf, done=set(range(total)) - set(todo))
    try:
        ran = _render_and_write(args, job, bundle, animation, todo, folder, movie, progress,
                                since)
    except KeyboardInterrupt:       # the frames written stay; the movie was abandoned whole
        return _interrupted(progress, out, folder, movie is not None)
    if isinstance(ran, int):
        return ran
    failed, where, seconds = ran
    if failed:
        return _report_failures(failed, total, args.retries, movie)
    return _finish(args, out, job, folder, movie, f"{len(todo)} rendered in {seconds:.1f} s"
                   + (f", {where}" if where else ""))


def _refused(args, out: Path) -> int:
    """The exit status when --out or --scheduler cannot be used (said why), else 0."""
    from app.commands import cluster
    refusal = out_problem(out, args.scene, args.force)
    if refusal:
        return _error(f"--out {args.out}: {refusal}", 2)
    if args.scheduler:
        try:
            cluster.scheduler_address(args.scheduler)
        except cluster.ClusterError as error:
            return _error(str(error), 2)
    return 0


def _job_to_run(args, out: Path):
    """(job, bundle, animation) for the scene and the options, or an exit status (said why)."""
    from app.commands.bundle import load_recorded
    from core.animation.animation import Animation
    from core.animation.keys import animation_of
    from core.scene.view_numbers import ViewNumberError
    scene, bundle = load_recorded(args.scene, lambda path: _load(path, size=args.size))
    if scene is None:
        return 2
    animation = animation_of(scene) or Animation(scene=scene)
    if not scene.views and animation.view is None:
        return _error(f"{scene.name}: no view to render", 2)
    try:
        view_index = view_index_of(scene, animation, args.view)
        job = job_of(args, animation, bundle, view_index)
        problem = _settings_problem(job, animation)
        if problem:
            raise JobError(problem)
        note = movie_rate(out, job["fps"])[1] if out.suffix.lower() in MOVIE_SUFFIXES else None
    except (ViewNumberError, JobError, ValueError) as error:
        return _error(str(error), 2)
    if note:
        print(note, file=sys.stderr)
    job["path"] = str(Path(args.scene).resolve())        # where this process reads it
    return job, bundle, animation


def _frames_to_render(job, folder: Path, force: bool):
    """The frames the folder does not hold yet for this job, or an exit status (said why)."""
    try:
        todo, notes = prepare_folder(folder, {k: v for k, v in job.items() if k != "path"},
                                     job_hash(job), force)
    except (OSError, ValueError) as error:
        return _error(str(error) if isinstance(error, FolderError)
                      else f"{folder}: {getattr(error, 'strerror', None) or error}", 2)
    for line in notes[:5] + ([f"... and {len(notes) - 5} more"] if len(notes) > 5 else []):
        print(line, file=sys.stderr)
    total = job["frames"]
    if len(todo) < total:
        print(f"{total - len(todo)} of {total} frames already in {folder}: skipped", file=sys.stderr)
    return todo


def _render_and_write(args, job, bundle, animation, todo, folder, movie, progress, since):
    """Render ``todo``, each frame written to the folder (and the movie) as it comes; returns
    (failures, where they ran, seconds), or an exit status (said why)."""
    from app.commands import cluster
    signature = job_hash(job)

    def write(k: int, data: bytes | None, rgb: np.ndarray) -> None:
        write_frame(folder, k, data if data is not None else frame_png(rgb, signature, k))
        if movie is not None:
            movie.put(k, rgb)
        progress.tick()

    t0 = time.perf_counter()
    writer = FrameWriter(write)
    try:
        try:
            failed, where = render_frames(args, job, bundle, animation, todo, writer,
                                          progress, since)
        finally:
            writer.close()                               # (interrupted: nothing left waiting)
    except (cluster.ClusterError, OSError) as error:
        progress.finish()
        if movie is not None:
            movie.abandon()
        return _error(_one_line(error) if not isinstance(error, cluster.ClusterError)
                      else str(error), 1)
    except BaseException:
        if movie is not None:
            movie.abandon()                              # (interrupted: nothing left beside)
        raise
    progress.finish()
    return failed, where, time.perf_counter() - t0


def _interrupted(progress, out: Path, folder: Path, movie: bool) -> int:
    """Say what Ctrl+C stopped and which frames stay; the status of an interrupted command."""
    from app.progress_line import INTERRUPTED
    kept = (f"{progress.done} of {progress.total} frames are in {folder}; the same command "
            f"renders the rest" + (f" and writes {out} (not written now)" if movie else ""))
    progress.say(progress.line.stopped(kept))
    return INTERRUPTED


def _report_failures(failed, total: int, retries: int, movie) -> int:
    """Say which frames failed and why; the same command renders only those again."""
    if movie is not None:
        movie.abandon()
    frames = sorted(k for run, _ in failed for k in run)
    first = min(failed, key=lambda f: f[0][0])[1]
    others = len({why for _, why in failed}) - 1
    print(f"error: {_frames_text(frames)} of {total} failed after {retries + 1} tries"
          f"{'' if len(frames) == 1 else ', the first'}: {first}"
          f"{f' (and {others} other reasons)' if others else ''}; the same command renders "
          "only the missing frames", file=sys.stderr)
    return 1


def _finish(args, out: Path, job, folder: Path, movie, rendered: str) -> int:
    """Finish the movie (if any), say what was written, and tidy the frames folder."""
    total = job["frames"]
    w, h = job["settings"]["size"]
    if out.suffix.lower() not in MOVIE_SUFFIXES:
        print(f"wrote {out} ({total} frames, {w}x{h}, {job['fps']:g} fps; {rendered})")
        return 0
    try:
        movie.finish()
    except (OSError, ValueError) as error:
        reason = getattr(error, "strerror", None) or error
        return _error(f"cannot write {out}: {reason} (the frames stay in {folder}; the same "
                      "command resumes from them)", 1)
    print(f"wrote {out} ({total} frames, {w}x{h}, {job['fps']:g} fps; {rendered})")
    if args.keep_frames:
        print(f"the frames stay in {folder} (--keep-frames)", file=sys.stderr)
    else:
        left = clean_folder(folder, total)
        if left:
            print(f"removed the frames from {folder}; it is kept for what else it holds: "
                  f"{', '.join(left[:3])}{' ...' if len(left) > 3 else ''}", file=sys.stderr)
    return 0


# ---------------------------------------------------------------------- the bench row


def bench_animation(scenes=None, size=(500, 500), frames: int = 240, workers: int = 2,
                    repeats: int = 1) -> dict:
    """The whole command, timed as a user meets it: ``animate`` of ``frames`` frames of the
    fountain and the fly-around in one process and with ``--workers`` (cluster start
    included), each in a fresh process (:mod:`app.commands.scaleout`)."""
    from app.commands.scaleout import SCENES, compare
    from core.paths import ROOT
    return {"rows": [compare(ROOT / scene, frames, size, workers, repeats)
                     for scene in (scenes or SCENES)]}


def format_animation(result: dict) -> str:
    from app.commands.scaleout import format_row
    return "\n".join(format_row(row) for row in result["rows"])
