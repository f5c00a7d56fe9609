"""The pixel inspector's commands: the bodies of ``inspect``, ``compare``, ``render --buffer``."""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import numpy as np

_PIXEL = re.compile(r"\s*([0-9]{1,6})\s*,\s*([0-9]{1,6})\s*")


def parse_pixel(text: str) -> tuple[int, int] | None:
    match = _PIXEL.fullmatch(text)
    return (int(match.group(1)), int(match.group(2))) if match else None


def inspect_main(scene, view, settings, pixel: str, as_json: bool) -> int:
    from app.session.state import announce_compiles
    from core.inspect import NotInspectable, inspect_pixel
    from core.inspect.text import describe
    xy = parse_pixel(pixel)
    if xy is None:
        print(f"error: --pixel must be X,Y in whole numbers from 0 (like 250,120), not "
              f"{pixel!r}", file=sys.stderr)
        return 2
    try:
        with announce_compiles():
            record = inspect_pixel(scene, view, settings, *xy)
    except NotInspectable as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    if as_json:
        print(json.dumps(strict_json(record), indent=1, allow_nan=False))
    else:
        print("\n".join(describe(record)))
    return 0


def strict_json(value):
    """``value`` with numpy's types made plain and each non-finite number written as the
    string "inf", "-inf" or "nan" (JSON has no Infinity or NaN; a volume's record has them)."""
    if isinstance(value, dict):
        return {k: strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [strict_json(v) for v in value]
    if isinstance(value, (np.generic, np.ndarray)):
        return strict_json(value.tolist())
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def render_buffer(scene, view, settings, name: str, out: Path, write_png) -> int:
    """``render --buffer NAME --out X.png``: the colour-mapped picture, and X.npy beside it
    (``write_png(color, path)``: the command line's atomic writer)."""
    from app.session.state import announce_compiles
    from core.inspect import NotInspectable
    from core.inspect.buffers import buffer
    try:
        with announce_compiles():
            values, picture = buffer(scene, view, settings, name)
    except NotInspectable as error:
        print(f"error: {error}", file=sys.stderr)
        return 1
    raw = out.with_suffix(".npy")
    try:
        write_png(picture, out)
        np.save(raw, values)
    except OSError as error:
        print(f"error: cannot write {out}: {error.strerror or error}", file=sys.stderr)
        return 2
    finite = np.asarray(values, dtype=np.float64)
    finite = finite[np.isfinite(finite)]
    span = (f", values {finite.min():.6g} .. {finite.max():.6g}" if finite.size else "")
    print(f"wrote {out} and {raw} ({name}, {values.shape[1]}x{values.shape[0]}{span})")
    return 0


def compare_main(scene, view, settings, args, write_png) -> int:
    """``compare``: 0 when no pixel is beyond the tolerance, 1 when some are, 2 for bad
    input."""
    from app.session.state import announce_compiles
    from core.inspect.compare import compare, heat_map
    picture = _read_picture(args.image)
    if picture is None:
        return 2
    size = (picture.shape[1], picture.shape[0])
    if args.size is not None and tuple(args.size) != size:
        print(f"error: --image {args.image} is {size[0]}x{size[1]}, --size says "
              f"{args.size[0]}x{args.size[1]}", file=sys.stderr)
        return 2
    if not 0 <= args.tolerance <= 1:
        print(f"error: --tolerance must be on 0..1 (1/255 = {1 / 255:.5f}), not "
              f"{args.tolerance}", file=sys.stderr)
        return 2
    if args.out is not None and Path(args.out).suffix.lower() != ".png":
        print(f"error: --out {args.out}: the heat map is a PNG (.png)", file=sys.stderr)
        return 2
    settings = settings.replace(size=size)
    with announce_compiles():
        reference, message = (opengl_reference(scene, view, settings) if args.opengl
                              else cpu_reference(scene, view, settings))
    if reference is None:
        print(f"error: {message}", file=sys.stderr)
        return 2
    result = compare(picture, reference, args.tolerance)
    print(f"compare {args.image} with {'OpenGL' if args.opengl else 'our render'}: "
          f"{result.verdict()}")
    if result.worst_levels:
        x, y = result.worst
        print(f"  the picture has {tuple(int(c) for c in picture[y, x])}, the reference "
              f"{tuple(int(c) for c in reference[y, x])}")
        print("  the inspector at that pixel: " + worst_story(scene, view, settings, x, y))
    if args.out:
        try:
            write_png(heat_map(result, reference), Path(args.out))
        except OSError as error:
            print(f"error: cannot write {args.out}: {error.strerror or error}",
                  file=sys.stderr)
            return 2
        print(f"wrote {args.out} (heat map: dimmed where equal, purple to yellow beyond)")
    return 0 if result.same else 1


def worst_story(scene, view, settings, x, y) -> str:
    from core.inspect import NotInspectable, inspect_pixel
    from core.inspect.text import describe
    try:
        return "\n    ".join(describe(inspect_pixel(scene, view, settings, x, y)))
    except NotInspectable as error:
        return str(error)


MAX_PICTURE_PIXELS = 64 << 20        # --image: beyond any picture we would draw to match it


def _read_picture(path: str):
    """``--image``: a regular file, its size read from its header before it is decoded, 16-bit
    samples scaled to 8 (not clipped); None after one ``error:`` line."""
    import os
    import stat
    import warnings
    from PIL import Image, UnidentifiedImageError
    from core.scene.model import MAX_IMAGE_SIDE
    try:
        mode = os.stat(path).st_mode
    except OSError as error:
        why = "no such file" if isinstance(error, FileNotFoundError) else error.strerror
        print(f"error: --image {path}: {why}", file=sys.stderr)
        return None
    if not stat.S_ISREG(mode):
        print(f"error: --image {path}: not a regular file (a FIFO, a device or a folder)",
              file=sys.stderr)
        return None
    try:
        with warnings.catch_warnings():      # its size is judged here, in one line
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            image = Image.open(path)
        with image:
            if image.width * image.height > MAX_PICTURE_PIXELS or \
                    max(image.width, image.height) > MAX_IMAGE_SIDE:
                print(f"error: --image {path}: {image.width} x {image.height} pixels is larger "
                      f"than any picture we draw to compare with", file=sys.stderr)
                return None
            if image.mode in ("I;16", "I;16B", "I;16L", "I"):
                wide = np.asarray(image, dtype=np.float64)
                grey = np.clip(np.rint(wide / 257.0), 0, 255).astype(np.uint8)
                return np.repeat(grey[..., None], 3, axis=2)
            return np.asarray(image.convert("RGB"))
    except (UnidentifiedImageError, OSError, ValueError, Image.DecompressionBombError) as error:
        print(f"error: --image {path}: not a picture that can be read ({error})",
              file=sys.stderr)
    return None


def cpu_reference(scene, view, settings):
    from app.session.state import render
    frame = render(scene, view, settings)
    if frame.message:
        return None, frame.message
    return frame.color.copy(), None


def opengl_reference(scene, view, settings):
    """The same view drawn by real OpenGL, or (None, why): app.oracles.reference_gl's,
    imported when asked (moderngl is not loaded for the other commands)."""
    from app.oracles.reference_gl import opengl_reference as reference
    return reference(scene, view, settings)
