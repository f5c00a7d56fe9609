"""``python -m app animate SCENE --out movie.mp4``: an animation rendered to a movie.

Frames are independent (particles are recomputed from time 0 for a seed, so a frame does not
depend on who rendered the one before it), so they are rendered anywhere and in any order:

- in this process (the default),
- on ``--workers N`` local processes (a Dask ``LocalCluster``),
- on an existing Dask cluster (``--scheduler tcp://host:8786``; the workers need this package
  and the scene file at the same path).

Each frame comes back as PNG bytes and is written here, as soon as it completes, into the
frames folder (``movie.frames/frame_00042.png``; for a PNG-sequence ``--out`` the folder is the
output). A frame is written to a temporary name and renamed, so a frame on disk is a whole
frame: a run that is killed and started again skips the frames already there (**resumable**),
as long as the settings are the same (``job.json`` in the folder records them). A frame that
fails is retried (``--retries``, default 2) without stopping the others. When every frame is
there, the movie is encoded: ``.mp4`` as H.264 (PyAV: FFmpeg's libraries and libx264 come in
its wheel, so no system ffmpeg is needed), ``.gif`` with Pillow. Progress and an ETA go to
stderr.

Why Dask rather than Ray: Dask's wheels are pure Python (Ray's are a ~70 MB C++ core per
platform and Python version, which lag new Pythons), a ``LocalCluster`` starts in a few
seconds for the tests, and ``submit(..., retries=)`` and ``as_completed`` are exactly the
retry-a-frame and write-as-they-complete this needs.
"""

from __future__ import annotations

import argparse
import hashlib
import io
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from app.naming import frame_name

MOVIE_SUFFIXES = (".mp4", ".gif")
MAX_FRAMES = 100_000


def add_arguments(p: argparse.ArgumentParser, parse_size) -> None:
    """The options of ``animate`` (the sub-parser and ``WxH`` parser come from ``app/cli.py``)."""
    from core.settings import PROJECTIONS
    p.add_argument("scene", help="a scene file with [animation], [[key]] or [[emitter]] tables")
    p.add_argument("--out", required=True,
                   help="movie.mp4 (H.264), movie.gif, or a folder for a PNG sequence")
    p.add_argument("--fps", type=_positive(float), default=None,
                   help="frames per second of the movie (default: the scene's [animation] fps)")
    length = p.add_mutually_exclusive_group()
    length.add_argument("--frames", type=_positive(int), default=None, help="how many frames")
    length.add_argument("--duration", type=_positive(float), default=None, help="seconds")
    p.add_argument("--size", type=parse_size, default=None, help="WxH (default: the scene's)")
    p.add_argument("--renderer", default=None, help="a registered renderer (default: zbuffer)")
    p.add_argument("--samples", type=_positive(int), default=None, help="samples per pixel")
    p.add_argument("--projection", choices=PROJECTIONS, default=None)
    p.add_argument("--shading", default=None, help="wireframe | flat | gouraud | phong | …")
    p.add_argument("--view", type=_positive(int), default=1,
                   help="which view, counting from 1: the keyed view first (when the scene keys "
                        "one), then the file's views (default 1)")
    p.add_argument("--paths", action="store_true",
                   help="draw the keyed paths (the eye, objects, lights) over every frame")
    p.add_argument("--workers", type=_positive(int), default=1,
                   help="local worker processes (a Dask LocalCluster when more than 1)")
    p.add_argument("--scheduler", default=None,
                   help="address of a running Dask scheduler (tcp://host:8786)")
    p.add_argument("--retries", type=int, default=2, help="tries again per failed frame")
    p.add_argument("--crf", type=int, default=18, help="H.264 quality, 0 (lossless) to 51")


def _positive(kind):
    def parse(text):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not value > 0:
            raise argparse.ArgumentTypeError(f"must be greater than 0, got {text!r}")
        return value
    return parse


# ---------------------------------------------------------------------- the job


def job_of(args, animation) -> dict:
    """Everything a worker needs to render any frame, as plain data (sent to every worker)."""
    scene = animation.scene
    fps = args.fps or animation.fps
    if args.frames:
        count = args.frames
    elif args.duration:
        count = max(1, int(round(args.duration * fps)))
    else:
        count = max(1, int(round(animation.duration * fps)))
    settings = {"size": list(args.size or scene.size), "samples": args.samples or 1,
                "projection": args.projection or scene.projection,
                "shading": args.shading or scene.shading,
                "renderer": args.renderer or "zbuffer", "view": args.view, "paths": args.paths}
    path = Path(args.scene).resolve()
    # the file's digest: frames left by a run on an edited scene are not taken as this one's
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return {"scene": str(path), "scene_sha256": digest, "fps": fps,
            "frames": min(count, MAX_FRAMES), "settings": settings}


def _settings_problem(job: dict, animation) -> str | None:
    """What is wrong with the job's settings (a renderer, shading or sample count that does not
    exist), found once here rather than as the same failure of every frame."""
    from core.renderers import get_renderer
    from core.settings import RenderSettings
    s = job["settings"]
    try:
        RenderSettings.for_scene(animation.scene, size=tuple(s["size"]), samples=s["samples"],
                                 projection=s["projection"], shading=s["shading"],
                                 renderer=s["renderer"])
        get_renderer(s["renderer"])
    except ValueError as error:
        return str(error)
    views = (animation.view is not None) + len(animation.scene.views)
    if not 1 <= s["view"] <= views:
        return f"--view {s['view']}: the animation has {views} views (1 to {views})"
    from core.settings import SHADINGS
    from core.shading.registry import shader_names
    if s["shading"] not in SHADINGS[:1] + tuple(shader_names()):
        return f"shading must be one of {', '.join(SHADINGS[:1] + tuple(shader_names()))}, not {s['shading']!r}"
    return None


_loaded: dict = {}


def _animation(path: str):
    """The animation of a scene file, loaded once per process (and again if the file changed)."""
    from core.animation.animation import Animation
    from core.animation.keys import animation_of
    from core.scene.formats import load_scene
    stamp = os.stat(path).st_mtime_ns
    if _loaded.get("key") != (path, stamp):
        scene = load_scene(path)
        _loaded["animation"] = animation_of(scene) or Animation(scene=scene)
        _loaded["key"] = (path, stamp)
    return _loaded["animation"]


def render_png(job: dict, k: int) -> tuple[int, bytes]:
    """Frame k of the job, encoded as PNG bytes (what a worker sends back)."""
    from PIL import Image

    from core.animation.frames import render_at
    from core.settings import RenderSettings
    animation = _animation(job["scene"])
    s = job["settings"]
    settings = RenderSettings.for_scene(animation.scene, size=tuple(s["size"]),
                                        samples=s["samples"], projection=s["projection"],
                                        shading=s["shading"], renderer=s["renderer"])
    frame = render_at(animation, k / job["fps"], settings, view_index=s["view"] - 1,
                      paths=s["paths"])
    if frame.message:
        raise RuntimeError(f"frame {k}: {frame.message}")
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(frame.color)).save(out, format="PNG")
    return k, out.getvalue()


# ---------------------------------------------------------------------- frames on disk


def frames_folder(out: Path) -> Path:
    """Where the frames go: the output itself for a PNG sequence, else ``NAME.frames/``."""
    return out.with_suffix(".frames") if out.suffix.lower() in MOVIE_SUFFIXES else out


def prepare_folder(folder: Path, job: dict) -> list[int]:
    """Make the folder, check it holds frames of this same job, and return the frames to do."""
    folder.mkdir(parents=True, exist_ok=True)
    record = folder / "job.json"
    text = json.dumps(job, indent=1, sort_keys=True)
    if record.exists():
        if json.loads(record.read_text()) != json.loads(text):
            raise ValueError(f"{folder} holds frames rendered with other settings or another "
                             f"version of the scene (see {record}); remove it or choose "
                             "another --out")
    else:
        record.write_text(text)
    for stale in folder.glob("*.tmp"):                 # a frame half written when killed
        stale.unlink()
    return [k for k in range(job["frames"]) if not (folder / frame_name(k)).exists()]


def write_frame(folder: Path, k: int, data: bytes) -> None:
    """Write-then-rename: a frame on disk is always a whole frame."""
    target = folder / frame_name(k)
    tmp = target.with_name(target.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, target)


class Progress:
    """``frame 12/90 (13%), 2.1 frames/s, ETA 37 s`` on stderr, one line updated in place."""

    def __init__(self, total: int, done: int, stream=sys.stderr):
        self.total, self.done, self.start_done = total, done, done
        self.t0 = time.perf_counter()
        self.stream = stream
        self.tty = hasattr(stream, "isatty") and stream.isatty()

    def tick(self) -> None:
        self.done += 1
        elapsed = time.perf_counter() - self.t0
        rate = (self.done - self.start_done) / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("inf")
        line = (f"frame {self.done}/{self.total} ({100 * self.done // self.total}%), "
                f"{rate:.2f} frames/s, ETA {eta:.0f} s")
        print(("\r" + line) if self.tty else line, end="" if self.tty else "\n",
              file=self.stream, flush=True)

    def finish(self) -> None:
        if self.tty:
            print(file=self.stream)


# ---------------------------------------------------------------------- running the frames


def run_local(job, todo, on_frame, retries: int) -> dict[int, str]:
    """Render ``todo`` in this process in order (the particles step on from frame to frame);
    returns {frame: error} for frames that failed every try."""
    failed = {}
    for k in todo:
        for attempt in range(retries + 1):
            try:
                on_frame(*render_png(job, k))
                failed.pop(k, None)
                break
            except Exception as error:                      # noqa: BLE001 - reported per frame
                failed[k] = f"{type(error).__name__}: {error}"
    return failed


def run_dask(job, todo, on_frame, retries: int, workers: int = 1,
             scheduler: str | None = None) -> dict[int, str]:
    """Render ``todo`` on a Dask cluster: a new local one of ``workers`` processes, or the one
    at ``scheduler``. Frames are handed out in order and written as they complete."""
    with dask_client(workers, scheduler) as client:
        return run_on(client, job, todo, on_frame, retries)


class dask_client:
    """A Dask client on a new ``LocalCluster`` of ``workers`` single-threaded processes, or on
    the scheduler at ``address``; closed (with its cluster) on leaving the block."""

    def __init__(self, workers: int = 1, address: str | None = None):
        try:
            from dask.distributed import Client, LocalCluster
        except ImportError:
            raise RuntimeError("--workers and --scheduler need Dask: "
                               "pip install 'fvd-viewer[anim]'") from None
        self.cluster = None
        if address is None:
            self.cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                        dashboard_address=None)
        try:
            self.client = Client(address or self.cluster)
        except OSError as error:
            if self.cluster is not None:
                self.cluster.close()
            raise RuntimeError(f"cannot reach the Dask scheduler at {address}: {error}") from None

    def __enter__(self):
        return self.client

    def __exit__(self, *exc) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def run_on(client, job, todo, on_frame, retries: int) -> dict[int, str]:
    """Submit every frame of ``todo`` (retried ``retries`` times by Dask), hand each result to
    ``on_frame`` as it completes; returns {frame: error} for frames that failed for good."""
    from dask.distributed import as_completed
    failed = {}
    futures = {client.submit(render_png, job, k, retries=retries, pure=False): k for k in todo}
    for future in as_completed(futures):
        k = futures[future]
        try:
            on_frame(*future.result())
        except Exception as error:                          # noqa: BLE001 - reported per frame
            failed[k] = f"{type(error).__name__}: {error}"
    return failed


# ---------------------------------------------------------------------- the bench row


def bench_animation(scene: str | Path | None = None, size=(500, 500), first: int = 60,
                    frames: int = 30) -> dict:
    """Frames per second rendering ``scenes/fountain.toml`` (frames ``first`` … ``first +
    frames - 1``, PNG encoding included), in this process and on a local cluster of 2 workers
    (timed after each worker has rendered a frame, so start-up and JIT are left out)."""
    from core.paths import ROOT
    scene = Path(scene or ROOT / "scenes" / "fountain.toml")
    job = {"scene": str(scene.resolve()), "fps": _animation(str(scene.resolve())).fps,
           "frames": first + frames,
           "settings": {"size": list(size), "samples": 1, "projection": "perspective",
                        "shading": _animation(str(scene.resolve())).scene.shading,
                        "renderer": "zbuffer", "view": 1, "paths": False}}
    todo = list(range(first, first + frames))
    render_png(job, first - 1)                                # warm: JIT, particles to first
    t0 = time.perf_counter()
    for k in todo:
        render_png(job, k)
    one = time.perf_counter() - t0
    with dask_client(2) as client:
        client.gather([client.submit(render_png, job, first - 2 + i, pure=False) for i in range(2)])
        t0 = time.perf_counter()
        run_on(client, job, todo, lambda k, data: None, 0)
        two = time.perf_counter() - t0
    particles = len(_animation(str(scene.resolve())).particle_system.particles)
    return {"scene": str(scene.name), "size": list(size), "frames": frames,
            "particles": particles, "fps_1": frames / one, "fps_2": frames / two,
            "scaling": one / two}


def format_animation(row: dict) -> str:
    return (f"animation: {row['scene']} at {row['size'][0]} x {row['size'][1]}, "
            f"{row['frames']} frames, ~{row['particles']:,} live particles: "
            f"{row['fps_1']:.1f} frames/s on 1 process, {row['fps_2']:.1f} on 2 Dask workers "
            f"(x{row['scaling']:.2f})")


# ---------------------------------------------------------------------- the movie


def encode(folder: Path, count: int, out: Path, fps: float, crf: int = 18) -> None:
    """The frames of ``folder`` into ``out``: H.264 MP4 (PyAV) or GIF (Pillow)."""
    from PIL import Image
    paths = [folder / frame_name(k) for k in range(count)]
    if out.suffix.lower() == ".gif":
        images = [Image.open(p).convert("RGB") for p in paths]
        images[0].save(out, save_all=True, append_images=images[1:], loop=0,
                       duration=max(20, int(round(1000 / fps))))
        return
    try:
        import av
    except ImportError:
        raise OSError("MP4 needs PyAV: pip install 'fvd-viewer[anim]' (or write .gif or PNGs)") from None
    from fractions import Fraction
    tmp = out.with_name(out.name + ".tmp.mp4")
    with av.open(str(tmp), "w") as container:
        stream = container.add_stream("libx264", rate=Fraction(fps).limit_denominator(1001))
        first = np.asarray(Image.open(paths[0]).convert("RGB"))
        # yuv420p halves the chroma resolution, so both sides must be even: pad by one pixel
        height, width = first.shape[0] + first.shape[0] % 2, first.shape[1] + first.shape[1] % 2
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        stream.options = {"crf": str(crf), "preset": "medium"}
        for p in paths:
            rgb = np.asarray(Image.open(p).convert("RGB"))
            rgb = np.pad(rgb, ((0, height - rgb.shape[0]), (0, width - rgb.shape[1]), (0, 0)), mode="edge")
            for packet in stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    os.replace(tmp, out)


def main(args) -> int:
    from core.animation.animation import Animation
    from core.animation.keys import animation_of
    from core.scene.formats import ReaderError, load_scene
    try:
        scene = load_scene(args.scene, size=args.size)
    except ReaderError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    animation = animation_of(scene) or Animation(scene=scene)
    if not scene.views and animation.view is None:
        print(f"error: {scene.name}: no view to render", file=sys.stderr)
        return 2
    job = job_of(args, animation)
    problem = _settings_problem(job, animation)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    out = Path(args.out)
    folder = frames_folder(out)
    try:
        todo = prepare_folder(folder, job)
    except (OSError, ValueError) as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    total = job["frames"]
    if len(todo) < total:
        print(f"{total - len(todo)} of {total} frames already in {folder}: skipped", file=sys.stderr)
    progress = Progress(total, total - len(todo))

    def on_frame(k: int, data: bytes) -> None:
        write_frame(folder, k, data)
        progress.tick()

    t0 = time.perf_counter()
    try:
        if args.scheduler or args.workers > 1:
            failed = run_dask(job, todo, on_frame, args.retries, args.workers, args.scheduler)
        else:
            failed = run_local(job, todo, on_frame, args.retries)
    except (RuntimeError, OSError) as error:
        progress.finish()
        print(f"error: {error}", file=sys.stderr)
        return 1
    progress.finish()
    if failed:
        for k, why in sorted(failed.items()):
            print(f"error: frame {k} failed after {args.retries + 1} tries: {why}", file=sys.stderr)
        print(f"{len(failed)} frames missing; run the same command again to render only them",
              file=sys.stderr)
        return 1
    seconds = time.perf_counter() - t0
    if out.suffix.lower() in MOVIE_SUFFIXES:
        try:
            encode(folder, total, out, job["fps"], args.crf)
        except (OSError, ValueError) as error:
            print(f"error: cannot write {out}: {error}", file=sys.stderr)
            return 1
    w, h = job["settings"]["size"]
    print(f"wrote {out} ({total} frames, {w}x{h}, {job['fps']:g} fps; {len(todo)} rendered in "
          f"{seconds:.1f} s)")
    return 0
