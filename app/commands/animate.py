"""``python -m app animate SCENE --out movie.mp4``: an animation rendered to a movie.

Frames are rendered

- in this process (the default; the particles step on from frame to frame),
- with ``--workers N``, in this process and N - 1 local single-thread worker processes
  (:class:`app.commands.cluster.LocalPool`, started once per job while this process renders
  the first frames), or not at all when a prediction from two measurements (a frame's time
  here, the cores other processes left idle since the command started) says it would not
  win (:func:`app.commands.animate_frames.predict`; the output says why), or
- on a running Dask cluster (``--scheduler tcp://host:8786``; the workers need only this
  package: the scene file and every file it names travel with the job, content-addressed,
  :mod:`app.commands.bundle`).

On a cluster the frames go out in contiguous runs, long first and short at the end
(:class:`~app.commands.animate_frames.Runs`), each with the particle state at its first frame
(:mod:`core.animation.checkpoint`, from a simulation-only pass here), so no worker simulates
from t = 0; a run that fails is retried by Dask (``--retries``). Frames come back as PNG bytes
and pixels: the PNG is written, as it completes, into the frames folder, which makes a killed
run resumable, and the pixels go to the MP4 encoder in order
(:class:`~app.commands.movie_files.Movie`), so the movie is encoded while the frames are
rendered (a GIF at the end): all on a writer thread beside the rendering (:class:`FrameWriter`;
a frame rendered here is made into its PNG there too). The folder is removed after the movie
(``--keep-frames`` keeps it). Progress and an ETA go to stderr.

The job its arguments make is :mod:`app.commands.animate_job`'s, the frames' rendering
:mod:`app.commands.animate_frames`'; here: the movie written as they come, and the command.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from app.commands.movie_files import (MOVIE_SUFFIXES, FolderError, Movie, clean_folder,
                                   frame_png, frames_folder, movie_rate, out_problem,
                                   prepare_folder, write_frame)
from app.commands.animate_frames import _one_line, idle_mark, render_frames
from app.commands.animate_job import (JobError, _settings_problem, job_hash, job_of,
                                      view_index_of)


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
