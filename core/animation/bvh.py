"""Biovision hierarchy (BVH) motion capture: a plain reader, a writer, forward kinematics.

The dynamic control of the course's animation lecture ("tracking live action": indicators,
reflectors, data gloves) reaches a program as a recorded skeleton and its channels, frame
by frame; BVH is the common text form of that record::

    HIERARCHY
    ROOT Hips
    {
      OFFSET 0 0 0
      CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
      JOINT LeftHip
      {
        OFFSET 9 -6 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -42 0
        }
      }
    }
    MOTION
    Frames: 2
    Frame Time: 0.05
    0 96 0 0 0 0 0 -20 0
    0 95 2 0 0 0 0 -18 0

The semantics (Meredith and Maddock, *Motion Capture File Formats Explained*, 2001, and
what Blender's importer does): each joint's frame is its parent's, moved by its ``OFFSET``
plus its position channels, then turned by its rotation channels **in the order the
``CHANNELS`` line lists them**, each counter-clockwise about its own axis in degrees:
``Zrotation Xrotation Yrotation`` is ``R = Rz · Rx · Ry`` acting on column vectors (the
last listed turns first, in the joint's own frame). So a point ``x`` of joint j's frame is
``W_parent (offset_j + position_j + R_j x)``, and an ``End Site`` is a point of its joint's
frame (the end of the last bone). Every frame row lists every joint's channels, in the
hierarchy's order.

A plain reader, not a library: the format is a page long, and every bad input must be one
line naming the file and the line (the readers' rule, ``core.scene.formats.errors``). The
file is refused before it is read beyond :data:`MAX_INPUT_BYTES` (64 MiB); ``Frames`` is
refused above :data:`MAX_FRAMES` before any row is stored, and frames x channels above
:data:`MAX_VALUES`, so no count written in a file allocates memory by itself.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from core.scene.formats.errors import ReaderError, decode_text, read_file, short

MAX_JOINTS = 256              # as a linkage's (core.animation.linkage_keys)
MAX_FRAMES = 100_000          # 55 minutes at 30 frames a second, 14 at 120
MAX_VALUES = 8_000_000        # frames x channels held (64 MB of float64)
MAX_MAGNITUDE = 1e9           # an offset or a channel's value, in the file's units or degrees
MIN_FRAME_TIME, MAX_FRAME_TIME = 1e-5, 60.0

POSITIONS = ("Xposition", "Yposition", "Zposition")
ROTATIONS = ("Xrotation", "Yrotation", "Zrotation")
CHANNEL_NAMES = POSITIONS + ROTATIONS
_CANONICAL = {name.lower(): name for name in CHANNEL_NAMES}


@dataclass
class Motion:
    """A skeleton and its frames. Joints are in file order (so parents come first);
    ``columns[j]`` is the index of joint j's first channel in a frame row."""

    names: list[str]
    parent: np.ndarray                         # (J,) int, -1 for the root
    offsets: np.ndarray                        # (J, 3)
    channels: list[tuple[str, ...]]            # per joint, as listed
    ends: list[tuple[int, np.ndarray]]         # End Sites: (joint, offset in its frame)
    frames: np.ndarray                         # (F, C)
    frame_time: float
    file: str = "motion.bvh"
    columns: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        counts = [len(c) for c in self.channels]
        self.columns = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)

    @property
    def channel_count(self) -> int:
        return sum(len(c) for c in self.channels)

    @property
    def frame_count(self) -> int:
        return len(self.frames)

    @property
    def length(self) -> float:
        """Seconds from the first frame to the last."""
        return (self.frame_count - 1) * self.frame_time

    def channel(self, joint: int, name: str) -> int | None:
        """The column of ``name`` (``"Xrotation"``) of joint ``joint``, None if it has none."""
        if name not in self.channels[joint]:
            return None
        return int(self.columns[joint]) + self.channels[joint].index(name)

    def local(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each joint's frame relative to its parent's for frame rows ``(F, C)``:
        ``(translations (F, J, 3), rotations (F, J, 3, 3))``."""
        rows = np.atleast_2d(np.asarray(rows, np.float64))
        n, joints = len(rows), len(self.names)
        translations = np.broadcast_to(self.offsets, (n, joints, 3)).copy()
        rotations = np.broadcast_to(np.eye(3), (n, joints, 3, 3)).copy()
        for j, names in enumerate(self.channels):
            for k, name in enumerate(names):
                value = rows[:, self.columns[j] + k]
                if name in POSITIONS:
                    translations[:, j, POSITIONS.index(name)] += value
                else:
                    rotations[:, j] = rotations[:, j] @ axis_rotations(ROTATIONS.index(name),
                                                                       np.radians(value))
        return translations, rotations

    def world(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Forward kinematics of frame rows ``(F, C)``: every joint's position ``(F, J, 3)``
        and frame ``(F, J, 3, 3)`` in the file's space, and every End Site ``(F, E, 3)``."""
        local_t, local_r = self.local(rows)
        positions, frames = np.empty_like(local_t), np.empty_like(local_r)
        for j, p in enumerate(self.parent):
            if p < 0:
                positions[:, j], frames[:, j] = local_t[:, j], local_r[:, j]
            else:
                positions[:, j] = positions[:, p] + np.einsum("fab,fb->fa", frames[:, p],
                                                              local_t[:, j])
                frames[:, j] = frames[:, p] @ local_r[:, j]
        ends = np.empty((len(local_t), len(self.ends), 3))
        for e, (j, offset) in enumerate(self.ends):
            ends[:, e] = positions[:, j] + frames[:, j] @ offset
        return positions, frames, ends


def axis_rotations(axis: int, angles: np.ndarray) -> np.ndarray:
    """``(n, 3, 3)``: counter-clockwise turns by ``angles`` (radians) about x, y or z."""
    c, s = np.cos(angles), np.sin(angles)
    out = np.zeros(np.shape(angles) + (3, 3))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out[..., axis, axis] = 1.0
    out[..., i, i], out[..., j, j] = c, c
    out[..., i, j], out[..., j, i] = -s, s
    return out


# ---------------------------------------------------------------------- reading


class _Tokens:
    """The hierarchy's words with their lines, read one at a time."""

    def __init__(self, lines: list[str], file: str):
        self.file = file
        self.words: list[tuple[str, int]] = []
        self.motion_line = None
        for number, line in enumerate(lines, 1):
            words = line.split()
            if words and words[0] == "MOTION":
                self.motion_line = number
                if len(words) > 1:
                    raise ReaderError(file, f"unexpected {short(words[1])} after MOTION", number)
                break
            self.words.extend((w, number) for w in words)
        self.at = 0

    def fail(self, reason: str, line: int | None = None) -> ReaderError:
        if line is None:
            line = self.words[min(self.at, len(self.words) - 1)][1] if self.words else 1
        return ReaderError(self.file, reason, line)

    def peek(self) -> tuple[str | None, int]:
        if self.at < len(self.words):
            return self.words[self.at]
        return None, self.motion_line or (self.words[-1][1] if self.words else 1)

    def take(self, what: str) -> tuple[str, int]:
        word, line = self.peek()
        if word is None:
            raise self.fail(f"the hierarchy ends where {what} was expected", line)
        self.at += 1
        return word, line

    def expect(self, word: str, what: str) -> int:
        found, line = self.take(what)
        if found != word:
            raise self.fail(f"expected {what}, got {short(found)}", line)
        return line

    def rest_of_line(self, line: int) -> list[str]:
        out = []
        while self.at < len(self.words) and self.words[self.at][1] == line:
            out.append(self.words[self.at][0])
            self.at += 1
        return out

    def number(self, what: str) -> float:
        word, line = self.take(what)
        return _number(word, what, self.file, line)


def _number(word: str, what: str, file: str, line: int) -> float:
    try:
        value = float(word)
    except ValueError:
        raise ReaderError(file, f"{what}: {short(word)} is not a number", line) from None
    if not math.isfinite(value):
        raise ReaderError(file, f"{what}: {short(word)} is not a finite number", line)
    if abs(value) > MAX_MAGNITUDE:
        raise ReaderError(file, f"{what}: {value:g} is beyond ±{MAX_MAGNITUDE:g}", line)
    return value


def read_bvh(data: bytes | str, file: str) -> Motion:
    """The motion of a BVH file's text (or bytes), or a :class:`ReaderError` naming the line."""
    text = data if isinstance(data, str) else decode_text(data, file)
    lines = text.split("\n")
    tokens = _Tokens(lines, file)
    names, parent, offsets, channels, ends = _hierarchy(tokens)
    if tokens.motion_line is None:
        raise ReaderError(file, "no MOTION section after the hierarchy", len(lines))
    count = sum(len(c) for c in channels)
    if count == 0:
        raise ReaderError(file, "the hierarchy has no CHANNELS: nothing in it moves",
                          tokens.motion_line)
    frames, frame_time = _motion(lines, tokens.motion_line, count, channels, names, file)
    return Motion(names, np.array(parent, np.int64), np.array(offsets, np.float64).reshape(-1, 3),
                  channels, ends, frames, frame_time, file)


def load_bvh(path, shown: str | None = None) -> Motion:
    """:func:`read_bvh` of a file (at most 64 MiB, read only if it is a regular file)."""
    shown = str(path) if shown is None else shown
    return read_bvh(read_file(Path(path), shown, "motion"), shown)


def _hierarchy(tokens: _Tokens):
    names, parent, offsets, channels, ends = [], [], [], [], []
    tokens.expect("HIERARCHY", "HIERARCHY (the first word of a BVH file)")
    stack: list[tuple[int, int]] = []            # (joint, the line its '{' is on)
    while True:
        word, line = tokens.peek()
        if word is None:
            if stack:
                j, opened = stack[-1]
                where = ("MOTION begins" if tokens.motion_line is not None else "the file ends")
                raise tokens.fail(f"{where} inside joint {names[j]!r} (its '{{' on line "
                                  f"{opened}): a '}}' is missing", line)
            if not names:
                raise tokens.fail("the hierarchy has no ROOT", line)
            return names, parent, offsets, channels, ends
        tokens.at += 1
        if word in ("ROOT", "JOINT"):
            if word == "ROOT" and stack:
                raise tokens.fail(f"ROOT inside joint {names[stack[-1][0]]!r}: a '}}' is "
                                  "missing before it", line)
            if word == "ROOT" and names:
                raise tokens.fail("a second ROOT: one skeleton a file is read", line)
            if word == "JOINT" and not stack:
                raise tokens.fail("JOINT outside any ROOT (a '}' too many above it, or no "
                                  "ROOT)", line)
            words = tokens.rest_of_line(line)
            if words and words[-1] == "{":        # "JOINT Knee {" on one line: read next
                words, tokens.at = words[:-1], tokens.at - 1
            name = " ".join(words)
            if not name:
                raise tokens.fail(f"{word} without a name", line)
            if name in names:
                raise tokens.fail(f"a second joint named {short(name)}", line)
            if len(names) >= MAX_JOINTS:
                raise tokens.fail(f"more than {MAX_JOINTS} joints", line)
            opened = tokens.expect("{", f"'{{' after {word} {name}")
            what = f"joint {name!r}"
            word, at = tokens.peek()
            if word != "OFFSET":
                raise tokens.fail(f"{what} has no OFFSET: the first line inside its braces "
                                  f"must be OFFSET x y z (got {short(word or 'nothing')})", at)
            tokens.at += 1
            offset = [tokens.number(f"the OFFSET of {what}") for _ in range(3)]
            names.append(name)
            parent.append(stack[-1][0] if stack else -1)
            offsets.append(offset)
            channels.append(_channels(tokens, what))
            stack.append((len(names) - 1, opened))
        elif word == "End":
            if not stack:
                raise tokens.fail("End Site outside any joint", line)
            tokens.expect("Site", "Site after End")
            tokens.expect("{", "'{' after End Site")
            what = f"the End Site of {names[stack[-1][0]]!r}"
            word, at = tokens.peek()
            if word != "OFFSET":
                raise tokens.fail(f"{what} has no OFFSET (got {short(word or 'nothing')})", at)
            tokens.at += 1
            offset = np.array([tokens.number(f"the OFFSET of {what}") for _ in range(3)])
            tokens.expect("}", f"'}}' closing {what} (an End Site holds only its OFFSET)")
            ends.append((stack[-1][0], offset))
        elif word == "}":
            if not stack:
                raise tokens.fail("'}' closes no joint (one '}' too many)", line)
            stack.pop()
            if not stack:                                # the root is closed
                after, at = tokens.peek()
                if after == "}":
                    raise tokens.fail("'}' closes no joint (one '}' too many)", at)
                if after is not None:
                    raise tokens.fail(f"expected MOTION after the ROOT's closing '}}', got "
                                      f"{short(after)}", at)
        elif word == "{":
            raise tokens.fail("'{' without a ROOT, JOINT or End Site before it", line)
        else:
            raise tokens.fail(f"expected ROOT, JOINT, End Site or '}}', got {short(word)}", line)


def _channels(tokens: _Tokens, what: str) -> tuple[str, ...]:
    word, line = tokens.peek()
    if word != "CHANNELS":
        raise tokens.fail(f"{what} has no CHANNELS line after its OFFSET (got "
                          f"{short(word or 'nothing')})", line)
    tokens.at += 1
    word, line = tokens.take(f"the number of {what}'s channels")
    if not re.fullmatch(r"[0-6]", word):
        raise tokens.fail(f"CHANNELS of {what}: expected a count from 0 to 6, got "
                          f"{short(word)}", line)
    names = tokens.rest_of_line(line)
    if len(names) != int(word):
        raise tokens.fail(f"CHANNELS of {what} says {word} but names {len(names)}", line)
    out = []
    for name in names:
        if name.lower() not in _CANONICAL:
            raise tokens.fail(f"CHANNELS of {what}: {short(name)} is not a channel "
                              f"({', '.join(CHANNEL_NAMES)})", line)
        name = _CANONICAL[name.lower()]
        if name in out:
            raise tokens.fail(f"CHANNELS of {what} names {name} twice", line)
        out.append(name)
    return tuple(out)


def _motion(lines, start, count, channels, names, file):
    """The ``Frames:`` and ``Frame Time:`` lines, then exactly that many rows of ``count``."""
    at = start                                   # lines[at] is the line after MOTION
    header = []
    while len(header) < 2 and at < len(lines):
        line = lines[at].strip()
        at += 1
        if line:
            header.append((line, at))
    if len(header) < 2:
        raise ReaderError(file, "MOTION needs a 'Frames:' and a 'Frame Time:' line", at)
    (frames_line, frames_at), (time_line, time_at) = header
    found = re.fullmatch(r"Frames\s*:\s*(\S+)", frames_line, re.I)
    if not found:
        raise ReaderError(file, f"expected 'Frames: N' after MOTION, got {short(frames_line)}",
                          frames_at)
    digits = found.group(1)
    if not re.fullmatch(r"\+?[0-9]{1,18}", digits):
        raise ReaderError(file, f"Frames: expected a whole number, got {short(digits)}",
                          frames_at)
    frame_count = int(digits)
    if frame_count < 1:
        raise ReaderError(file, "Frames: 0: a motion needs at least one frame", frames_at)
    if frame_count > MAX_FRAMES:
        raise ReaderError(file, f"Frames: {frame_count:,} frames; at most {MAX_FRAMES:,} are "
                                "read (the reader's limit; cut the take into parts)", frames_at)
    if frame_count * count > MAX_VALUES:
        raise ReaderError(file, f"Frames: {frame_count:,} frames of {count} channels are "
                                f"{frame_count * count:,} numbers; at most {MAX_VALUES:,}",
                          frames_at)
    found = re.fullmatch(r"Frame\s+Time\s*:\s*(\S+)", time_line, re.I)
    if not found:
        raise ReaderError(file, f"expected 'Frame Time: SECONDS' after Frames, got "
                                f"{short(time_line)}", time_at)
    frame_time = _number(found.group(1), "Frame Time", file, time_at)
    if not MIN_FRAME_TIME <= frame_time <= MAX_FRAME_TIME:
        raise ReaderError(file, f"Frame Time: {frame_time:g} s is outside "
                                f"[{MIN_FRAME_TIME:g}, {MAX_FRAME_TIME:g}] s", time_at)
    labels = [f"{names[j]} {c}" for j, cs in enumerate(channels) for c in cs]
    frames = np.empty((frame_count, count))
    row = 0
    for number in range(at + 1, len(lines) + 1):
        words = lines[number - 1].split()
        if not words:
            continue
        if row == frame_count:
            raise ReaderError(file, f"more rows than 'Frames: {frame_count}' says (row "
                                    f"{row + 1} here)", number)
        if len(words) != count:
            raise ReaderError(file, f"frame {row + 1} has {len(words)} numbers; the "
                                    f"hierarchy's CHANNELS give {count}", number)
        try:
            values = np.array(words, np.float64)
        except ValueError:
            values = None
        if values is None or not np.all(np.abs(values) <= MAX_MAGNITUDE):
            for k, word in enumerate(words):            # the culprit (the error path)
                _number(word, f"frame {row + 1}, channel {labels[k]}", file, number)
        frames[row] = values
        row += 1
    if row < frame_count:
        raise ReaderError(file, f"'Frames: {frame_count}' but the file holds {row} rows",
                          frames_at)
    return frames, frame_time


# ---------------------------------------------------------------------- writing


def format_bvh(motion: Motion, digits: int = 4) -> str:
    """The text of a BVH file for ``motion`` (values with ``digits`` decimals): what
    :func:`read_bvh` reads back to the same skeleton, and to the frames within half a unit
    of the last decimal."""
    out = ["HIERARCHY"]
    children = {j: [k for k, p in enumerate(motion.parent) if p == j]
                for j in range(len(motion.names))}
    ends = {j: [o for e, o in motion.ends if e == j] for j in range(len(motion.names))}
    vector = lambda v: " ".join(_decimal(float(x), digits) for x in v)

    def joint(j: int, depth: int) -> None:
        pad = "  " * depth
        kind = "ROOT" if motion.parent[j] < 0 else "JOINT"
        out.append(f"{pad}{kind} {motion.names[j]}")
        out.append(f"{pad}{{")
        out.append(f"{pad}  OFFSET {vector(motion.offsets[j])}")
        names = motion.channels[j]
        out.append(f"{pad}  CHANNELS {len(names)}{''.join(' ' + n for n in names)}")
        for k in children[j]:
            joint(k, depth + 1)
        for offset in ends[j]:
            out.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {vector(offset)}",
                        f"{pad}  }}"])
        out.append(f"{pad}}}")

    for root in (j for j, p in enumerate(motion.parent) if p < 0):
        joint(root, 0)
    out += ["MOTION", f"Frames: {motion.frame_count}",
            f"Frame Time: {motion.frame_time:.{max(digits, 6)}g}"]
    out += [vector(row) for row in motion.frames]
    return "\n".join(out) + "\n"


def _decimal(value: float, digits: int) -> str:
    """``value`` with at most ``digits`` decimals, trailing zeros dropped (``-0`` is ``0``)."""
    text = f"{value:.{digits}f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text
