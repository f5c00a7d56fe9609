"""What ``animate`` keeps on disk: the frames folder, and the movie made from it.

The frames go into a folder (``movie.frames/`` beside ``movie.mp4``; for a PNG-sequence
``--out`` the folder is the output), each written to a temporary name and renamed, so a frame
on disk is a whole frame. Each frame carries the job's hash and its number in a PNG text
chunk, and ``job.json`` records the job: a rerun resumes only frames that decode, have the
job's size and carry its hash; any other is rendered again (or, in a folder without our
``job.json``, the folder is refused rather than written over). Only our own temporary frames
(``frame_00042.png.tmp``) are ever removed, and after a finished movie the folder is removed
unless kept.

The movie follows the one output rule (:mod:`app.output_files`): written beside ``--out`` and
renamed when complete; nothing is left on failure.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
from fractions import Fraction
from pathlib import Path

import numpy as np

from app.naming import frame_name          # one rule for the name of every file written

MOVIE_SUFFIXES = (".mp4", ".gif")
_FRAME = re.compile(r"frame_([0-9]{5})\.png")
_OWN_TEMP = re.compile(r"frame_([0-9]{5})\.png\.tmp")
TEXT_KEY = "fvd-animate"             # the PNG text chunk: "<job hash> <frame number>"
GIF_MIN_CS, GIF_MAX_CS = 2, 65535    # a GIF frame's delay, hundredths of a second (16 bits;
                                     # browsers play anything below 2 as 10)


class FolderError(ValueError):
    """The frames folder cannot be used; the message names it and says why."""


def frames_folder(out: Path) -> Path:
    """Where the frames go: the output itself for a PNG sequence, else ``NAME.frames/``."""
    return out.with_suffix(".frames") if out.suffix.lower() in MOVIE_SUFFIXES else out


def out_problem(out: Path, source: str, force: bool) -> str | None:
    """Why ``--out`` cannot be written, or None: a movie by the one output rule, a PNG
    sequence into a folder whose parent exists (the folder itself is made)."""
    from app.output_files import out_problem as file_problem
    if out.suffix.lower() in MOVIE_SUFFIXES:
        return file_problem(out, source, force, MOVIE_SUFFIXES)
    if os.path.lexists(out) and not out.is_dir():
        return ("it exists and is not a folder (a PNG sequence goes into a folder; a movie's "
                f"name ends in {' or '.join(MOVIE_SUFFIXES)})")
    if not out.parent.is_dir():
        return f"the folder {str(out.parent)!r} does not exist (it is not created)"
    return None


# ---------------------------------------------------------------------- frames


def frame_png(color: np.ndarray, job_hash: str, k: int) -> bytes:
    """Frame ``k`` as PNG bytes, signed with the job's hash and its number."""
    from PIL import Image
    from PIL.PngImagePlugin import PngInfo
    info = PngInfo()
    info.add_text(TEXT_KEY, f"{job_hash} {k}")
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(color)).save(out, format="PNG", pnginfo=info)
    return out.getvalue()


def frame_problem(path: Path, job_hash: str, k: int, size) -> str | None:
    """Why the file at ``path`` is not frame ``k`` of the job, or None."""
    from PIL import Image
    try:
        with Image.open(path) as image:
            if image.format != "PNG":
                return f"not a PNG ({image.format})"
            if image.size != tuple(size):
                return f"{image.size[0]}x{image.size[1]}, not {size[0]}x{size[1]}"
            image.load()                                   # decodes every row
            if image.info.get(TEXT_KEY) != f"{job_hash} {k}":
                return "not rendered by this job (its hash differs)"
    except (OSError, ValueError, SyntaxError) as error:    # PIL's decoders raise all three
        return f"not a whole PNG ({error})"
    return None


def write_frame(folder: Path, k: int, data: bytes) -> None:
    """Write-then-rename: a frame on disk is always a whole frame."""
    target = folder / frame_name(k)
    tmp = target.with_name(target.name + ".tmp")
    tmp.write_bytes(data)
    os.replace(tmp, target)


def _record(job: dict) -> dict:
    """What must match for frames to be reused (the frame count may grow or shrink)."""
    return {k: v for k, v in job.items() if k != "frames"}


def prepare_folder(folder: Path, job: dict, job_hash: str, force: bool = False
                   ) -> tuple[list[int], list[str]]:
    """Make the folder (not its parents), check it holds frames of this same job, and return
    ``(frames to render, notes)``: every frame not on disk or not passing
    :func:`frame_problem`."""
    if not folder.is_dir():
        try:
            folder.mkdir()
        except OSError as error:
            raise FolderError(f"{folder}: cannot make the frames folder: "
                              f"{error.strerror or error}") from None
    record = folder / "job.json"
    ours = record.exists()
    if ours:
        try:
            recorded = json.loads(record.read_text())
        except (OSError, ValueError) as error:
            raise FolderError(f"{record}: not a job record ({error}); remove it (the frames "
                              "beside it are checked one by one on the next run)") from None
        if not isinstance(recorded, dict) or _record(recorded) != _record(job):
            raise FolderError(f"{folder} holds frames rendered with other settings or another "
                              f"version of the scene (see {record}); remove it or choose "
                              "another --out")
    for entry in folder.iterdir():                 # a frame half written when killed
        if _OWN_TEMP.fullmatch(entry.name) and entry.is_file():
            entry.unlink()
    todo, notes, foreign = [], [], []
    size = job["settings"]["size"]
    for k in range(job["frames"]):
        path = folder / frame_name(k)
        if not os.path.lexists(path):
            todo.append(k)
            continue
        why = frame_problem(path, job_hash, k, size) if path.is_file() else "not a file"
        if why is not None:
            todo.append(k)
            (notes if ours else foreign).append(f"{path.name}: {why}")
    if foreign and not force:
        raise FolderError(f"{folder} holds files that are not frames of this job "
                          f"({foreign[0]}{f', and {len(foreign) - 1} more' if len(foreign) > 1 else ''}); "
                          "choose another --out, or --force to render over them")
    notes = [f"{n}: rendered again" for n in notes + foreign]
    text = json.dumps(job, indent=1, sort_keys=True)
    if not ours or record.read_text() != text:
        temp = record.with_name(".job.json.tmp")
        temp.write_text(text)
        os.replace(temp, record)
    return todo, notes


def clean_folder(folder: Path, count: int) -> list[str]:
    """Remove the job's frames, its record and the folder; return the names of what is left
    (files that are not ours stay, and so does the folder then)."""
    for k in range(count):
        path = folder / frame_name(k)
        if path.is_file():
            path.unlink()
    (folder / "job.json").unlink(missing_ok=True)
    left = sorted(entry.name for entry in folder.iterdir())
    if not left:
        folder.rmdir()
    return left


# ---------------------------------------------------------------------- the movie


def movie_rate(out: Path, fps: float) -> tuple[object, str | None]:
    """The rate the movie stores for ``fps`` (MP4: a fraction; GIF: a delay in hundredths of
    a second) and a note when it differs from ``fps``; ValueError when it cannot be stored."""
    if out.suffix.lower() == ".gif":
        cs = round(100 / fps)
        if cs > GIF_MAX_CS:
            raise ValueError(f"a GIF frame lasts at most {GIF_MAX_CS / 100:g} s, so --fps must be "
                             f"at least {100 / GIF_MAX_CS:.5f} (got {fps:g})")
        cs = max(GIF_MIN_CS, cs)
        stored = 100 / cs
        note = None if math.isclose(stored, fps, rel_tol=1e-3) else (
            f"note: a GIF stores each frame's delay in hundredths of a second: {fps:g} fps "
            f"is written as {cs / 100:g} s a frame ({stored:.3g} fps)")
        return cs, note
    rate = Fraction(fps).limit_denominator(1001)
    note = None if math.isclose(float(rate), fps, rel_tol=1e-6) else (
        f"note: the MP4 stores its rate as a fraction: {fps:g} fps is written as {rate} fps")
    return rate, note


def encode(folder: Path, count: int, out: Path, fps: float, crf: int = 18) -> None:
    """The frames of ``folder`` into ``out`` (H.264 MP4 with PyAV, or GIF with Pillow),
    written beside it and renamed when complete."""
    from app.output_files import write_beside
    paths = [folder / frame_name(k) for k in range(count)]
    rate, _ = movie_rate(out, fps)
    if out.suffix.lower() == ".gif":
        write_beside(out, lambda temp: _gif(paths, temp, rate))
    else:
        write_beside(out, lambda temp: _mp4(paths, temp, rate, crf))


def _gif(paths, temp: Path, cs: int) -> None:
    from PIL import Image
    images = [Image.open(p).convert("RGB") for p in paths]
    images[0].save(temp, format="GIF", save_all=True, append_images=images[1:], loop=0,
                   duration=cs * 10)


def _mp4(paths, temp: Path, rate: Fraction, crf: int) -> None:
    """H.264 in one thread with fixed options: the same frames give the same bytes (x264's
    frame threads make its choices depend on timing)."""
    try:
        import av
    except ImportError:
        raise OSError("MP4 needs PyAV: pip install 'fvd-viewer[anim]' (or write .gif or PNGs)") from None
    from PIL import Image
    with av.open(str(temp), "w", format="mp4") as container:
        stream = container.add_stream("libx264", rate=rate)
        first = np.asarray(Image.open(paths[0]).convert("RGB"))
        # yuv420p halves the chroma resolution, so both sides must be even: pad by one pixel
        height, width = first.shape[0] + first.shape[0] % 2, first.shape[1] + first.shape[1] % 2
        stream.width, stream.height, stream.pix_fmt = width, height, "yuv420p"
        stream.codec_context.thread_count = 1
        stream.options = {"crf": str(crf), "preset": "medium", "threads": "1"}
        for p in paths:
            rgb = np.asarray(Image.open(p).convert("RGB"))
            rgb = np.pad(rgb, ((0, height - rgb.shape[0]), (0, width - rgb.shape[1]), (0, 0)),
                         mode="edge")
            for packet in stream.encode(av.VideoFrame.from_ndarray(rgb, format="rgb24")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
