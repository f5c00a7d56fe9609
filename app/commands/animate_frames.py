"""``animate``'s frames rendered: one frame's pixels or PNG, and where the frames run: in this
process, beside local worker processes (when a prediction from a frame's time and the idle
cores says they win: :func:`predict`), or on a Dask cluster in contiguous runs, each from the
particle state at its first frame (:class:`Runs`).
"""

from __future__ import annotations

import math
import os
import time
from collections import deque

import numpy as np

from app.commands.animate_job import job_hash, job_shutter
from app.commands.movie_files import frame_png


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


def _one_line(error: BaseException) -> str:
    text = " ".join(str(error).split()) or type(error).__name__
    return f"{type(error).__name__}: {text}" if not isinstance(error, RuntimeError) else text


def render_here(job, frames, on_frame, retries: int, animation, failed: list,
                stop=lambda: False) -> int:
    """Render ``frames`` in this process, in order, until ``stop()``; returns how many were
    taken (rendered or failed). Each goes to ``on_frame(k, None, pixels)``: its PNG is made
    where it is written (:class:`app.commands.animate.FrameWriter`), beside the next frame's
    rendering."""
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
    failure ``(frames, why)``. ``writer`` (:class:`app.commands.animate.FrameWriter`) takes
    the frames. ``since`` (:func:`idle_mark`, taken when the command started) is where the
    idle cores are measured from."""
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
