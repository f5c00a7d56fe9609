"""``animate``'s job: its arguments, the job they make (scene, frames, size, settings, shutter;
:func:`job_of` says what is wrong with one) and its hash, which names its frames on disk.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
from pathlib import Path

MAX_FRAMES = 100_000
MIN_FPS, MAX_FPS = 1e-3, 1000.0
MAX_RETRIES = 100


def add_arguments(p: argparse.ArgumentParser, parse_size) -> None:
    """The options of ``animate`` (the sub-parser and ``WxH`` parser come from
    ``app/cli_arguments.py``)."""
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
    from core.registry import shading_names
    from core.renderers import renderer_names
    p.add_argument("--renderer", default=None,     # the registered ones, checked with the job
                   help=f"{' | '.join(renderer_names())} (default: zbuffer)")
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
    p.add_argument("--shading", default=None, help=" | ".join(shading_names()))
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
