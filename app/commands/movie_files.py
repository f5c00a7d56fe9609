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
from contextlib import ExitStack
from fractions import Fraction
from pathlib import Path

import numpy as np

from app.naming import frame_name          # one rule for the name of every file written
from app.output_files import beside, write_beside

MOVIE_SUFFIXES = (".mp4", ".gif")
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


# zlib's fastest level: a frame's PNG in 45 % of the default's time (8.7 against 19.4 ms for
# the Whitted picture at 500 x 500), a third larger; the folder is a resumable work area.
PNG_LEVEL = 1


def rgb_image(color: np.ndarray):
    """``color`` (H, W, 3) uint8 as a Pillow image. A frame's ``color`` is a view of its
    padded RGBX pixels (``Frame.rgbx``); Pillow unpacks RGBX in 0.1 ms, where numpy's copy of
    the strided view takes 1.5–1.9 ms at 500 x 500."""
    from PIL import Image
    padded = color.base
    if (isinstance(padded, np.ndarray) and padded.dtype == np.uint8 and padded.ndim == 3
            and padded.shape[2] == 4 and padded.flags.c_contiguous
            and padded.shape[:2] == color.shape[:2] and color.strides == padded.strides
            and color.__array_interface__["data"][0] == padded.__array_interface__["data"][0]):
        return Image.frombytes("RGB", (color.shape[1], color.shape[0]), padded.tobytes(),
                               "raw", "RGBX")
    return Image.fromarray(np.ascontiguousarray(color))


def packed_rgb(color: np.ndarray) -> np.ndarray:
    """``color`` as a C-contiguous (H, W, 3) array (see :func:`rgb_image`)."""
    if color.flags.c_contiguous:
        return color
    return np.asarray(rgb_image(color))


def frame_png(color: np.ndarray, job_hash: str, k: int) -> bytes:
    """Frame ``k`` as PNG bytes, signed with the job's hash and its number."""
    from PIL.PngImagePlugin import PngInfo
    info = PngInfo()
    info.add_text(TEXT_KEY, f"{job_hash} {k}")
    out = io.BytesIO()
    rgb_image(color).save(out, format="PNG", pnginfo=info, compress_level=PNG_LEVEL)
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


HOLD_BYTES = 256 << 20     # frames that came before their turn, held in memory at most


class Movie:
    """The movie of a job's ``count`` frames, encoded while they are rendered (MP4), so that
    no pass over the frames is left for the end; a GIF is made at the end from the folder
    (Pillow writes one in a single call).

    The encoder takes frames in order. :meth:`put` says frame k is in the folder, with its
    pixels when at hand: a frame that comes before its turn waits in memory (up to
    HOLD_BYTES), and one not held (a frame resumed from an earlier run, or one over the
    limit) is read back from the folder when its turn comes. The file is written beside
    ``out`` and renamed by :meth:`finish`; :meth:`abandon` (or a failed encoder) leaves
    ``out`` as it was and nothing behind. An encoder error is kept in ``error``: the frames
    are still rendered into the folder, and the caller reports it at the end."""

    def __init__(self, out: Path, folder: Path, count: int, fps: float, crf: int = 18,
                 done=()):
        self.out, self.folder, self.count, self.crf = out, folder, count, crf
        self.rate, _ = movie_rate(out, fps)
        self.done, self.held, self.held_bytes = set(done), {}, 0
        self.next, self.error = 0, None
        self._file = self._writer = None
        if out.suffix.lower() == ".mp4":
            self._file = ExitStack()
            try:
                self._writer = Mp4Writer(self._file.enter_context(beside(out)), self.rate, crf)
            except BaseException as error:
                self._fail(error)
                if not isinstance(error, OSError):
                    raise
        self._advance()

    def put(self, k: int, rgb: np.ndarray | None = None) -> None:
        """Frame ``k`` is in the folder; ``rgb``, its pixels, saves reading it back."""
        self.done.add(k)
        if self._writer is not None and rgb is not None and (
                k == self.next or self.held_bytes + rgb.nbytes <= HOLD_BYTES):
            self.held[k] = rgb
            self.held_bytes += rgb.nbytes
        self._advance()

    def _advance(self) -> None:
        """Encode every frame whose turn has come."""
        while self._writer is not None and self.next in self.done:
            rgb = self.held.pop(self.next, None)
            if rgb is not None:
                self.held_bytes -= rgb.nbytes
            try:
                self._writer.add(rgb if rgb is not None else read_frame(self.folder, self.next))
            except (OSError, ValueError) as error:
                self._fail(error)
                return
            self.next += 1

    def finish(self) -> None:
        """Encode what is left and rename the movie over ``out``; OSError or ValueError when
        it cannot be written (``out`` is left as it was)."""
        if self.error is not None:
            raise self.error
        if self._writer is None:
            paths = [self.folder / frame_name(k) for k in range(self.count)]
            write_beside(self.out, lambda temp: _gif(paths, temp, self.rate))
            return
        self.done.update(range(self.count))
        self._advance()
        if self.error is not None:
            raise self.error
        try:
            self._writer.close()
        except (OSError, ValueError) as error:
            self._fail(error)
            raise
        self._file.close()                          # renamed over out

    def abandon(self) -> None:
        """No movie this time: the temporary file goes, ``out`` stays as it was."""
        self._fail(None)

    def _fail(self, error) -> None:
        self.error = self.error or error
        self.held.clear()
        if self._writer is not None:
            self._writer.abort()
        self._writer = None
        if self._file is not None:
            stop = error if isinstance(error, BaseException) else OSError("abandoned")
            self._file.__exit__(type(stop), stop, None)         # removes the temporary file
            self._file = None


def read_frame(folder: Path, k: int) -> np.ndarray:
    from PIL import Image
    with Image.open(folder / frame_name(k)) as image:
        return np.asarray(image.convert("RGB"))


def encode(folder: Path, count: int, out: Path, fps: float, crf: int = 18) -> None:
    """The frames of ``folder`` into ``out`` (H.264 MP4 with PyAV, or GIF with Pillow),
    written beside it and renamed when complete."""
    Movie(out, folder, count, fps, crf, done=range(count)).finish()


def _gif(paths, temp: Path, cs: int) -> None:
    from PIL import Image
    images = [Image.open(p).convert("RGB") for p in paths]
    images[0].save(temp, format="GIF", save_all=True, append_images=images[1:], loop=0,
                   duration=cs * 10)


class Mp4Writer:
    """H.264 frames into an MP4, one at a time, in one thread with fixed options and stated
    timestamps (x264's frame threads make its choices depend on timing). The same frames
    almost always give the same bytes; rarely, runs were seen to code them a little
    differently (a few pixels up to 28 levels apart once decoded), so tests compare the
    pictures, not the bytes."""

    def __init__(self, temp: Path, rate: Fraction, crf: int):
        try:
            import av
        except ImportError:
            raise OSError("MP4 needs PyAV: pip install 'fvd-viewer[anim]' (or write .gif or "
                          "PNGs)") from None
        self.av, self.crf = av, crf
        self.container = av.open(str(temp), "w", format="mp4")
        self.stream = self.container.add_stream("libx264", rate=rate)
        self.size, self.rate, self.count = None, rate, 0

    def add(self, rgb: np.ndarray) -> None:
        if self.size is None:
            # yuv420p halves the chroma resolution, so both sides must be even: pad by one
            self.size = rgb.shape[0] + rgb.shape[0] % 2, rgb.shape[1] + rgb.shape[1] % 2
            self.stream.height, self.stream.width = self.size
            self.stream.pix_fmt = "yuv420p"
            self.stream.codec_context.thread_count = 1
            self.stream.options = {"crf": str(self.crf), "preset": "veryfast", "threads": "1"}
        height, width = self.size
        if rgb.shape[:2] != (height, width):
            rgb = np.pad(rgb, ((0, height - rgb.shape[0]), (0, width - rgb.shape[1]), (0, 0)),
                         mode="edge")
        frame = self.av.VideoFrame.from_ndarray(packed_rgb(rgb), format="rgb24")
        # Each frame's time stated (frame k at k / rate): left unset, the encoder is handed
        # no timestamps and its choices need not be the same from one run to the next.
        frame.pts, frame.time_base = self.count, 1 / self.rate
        self.count += 1
        for packet in self.stream.encode(frame):
            self.container.mux(packet)

    def close(self) -> None:
        for packet in self.stream.encode():
            self.container.mux(packet)
        self.container.close()

    def abort(self) -> None:
        try:
            self.container.close()
        except Exception:                       # noqa: BLE001 - the file is removed anyway
            pass
