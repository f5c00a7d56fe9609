"""``python -m app colour [--out chromaticity.png] [--size WxH] [--scene FILE]``: the CIE 1931
chromaticity diagram (core.colour.diagram) with the sRGB gamut, D65 and, with ``--scene``,
the chromaticity of every material's O_d in the scene (a grey one sits on D65; O_d read as
the sRGB code value the z-buffer shows, or as linear light in a ``tone = "srgb"`` scene). The numbers
and words on it are Pillow's default bitmap font; the diagram itself is numpy.

``python -m app colour --perception [--out perception.png]``: the perception chart instead
(core.colour.perception): simultaneous contrast, and even steps of code beside even steps of
light with the rises of CIE L* along each printed.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

SIZE = (640, 720)
MARGIN = 48


def parse_size(text: str) -> tuple[int, int]:
    """``WxH`` → (W, H), each 200 to 4096 pixels."""
    import argparse
    parts = text.lower().split("x")
    if len(parts) != 2 or not all(p.isascii() and p.isdigit() for p in parts) \
            or not all(200 <= int(p) <= 4096 for p in parts):
        raise argparse.ArgumentTypeError(f"size must be WIDTHxHEIGHT, each 200 to 4096, like "
                                         f"640x720, not {text[:40]!r}")
    return int(parts[0]), int(parts[1])


def add_arguments(parser) -> None:
    parser.add_argument("--out", default=None,
                        help="the PNG to write (default chromaticity.png, or perception.png)")
    parser.add_argument("--perception", action="store_true",
                        help="draw the perception chart (simultaneous contrast; even steps of "
                             "code and of light) instead of the chromaticity diagram")
    parser.add_argument("--size", type=parse_size, default=SIZE, help="WxH (default 640x720)")
    parser.add_argument("--scene", default=None,
                        help="plot the chromaticities of this scene's material colours (O_d)")


def scene_colours(path: str):
    """(xy (P, 2), the dots' bytes (P, 3)) of the scene's distinct, non-black O_d, or None
    after printing the reader's message. The Phong model works on display values, so O_d is
    an sRGB code value (decoded to linear light for its chromaticity); a scene with
    ``tone = "srgb"`` gives reflectances in linear light (encoded for the dot)."""
    from app.loading import load_or_say
    from core.colour import srgb
    from core.colour.cie import chromaticity
    scene = load_or_say(path)
    if scene is None:
        return None
    ods = {tuple(float(c) for c in m.material.od) for m in scene.meshes}
    ods = np.array(sorted(od for od in ods if sum(od) > 0), np.float64).reshape(-1, 3)
    linear = ods if scene.tone == "srgb" else srgb.decode(ods)
    shown = srgb.encode(ods) if scene.tone == "srgb" else ods
    return chromaticity(linear @ srgb.RGB_TO_XYZ.T), np.round(shown * 255).astype(np.uint8)


def label(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """The axes' numbers, the marked wavelengths, D65 and sRGB, written beside their marks."""
    from PIL import Image, ImageDraw
    from core.colour import cie, diagram, srgb
    picture = Image.fromarray(image)
    draw = ImageDraw.Draw(picture)
    at = lambda xy: diagram.pixel_of(xy, width, height, MARGIN)     # noqa: E731
    for k in range(9):
        c, r = at([k / 10, 0])
        draw.text((c - 8, r + 6), f"{k / 10:.1f}", fill=(200, 200, 200))
    for k in range(10):
        c, r = at([0, k / 10])
        draw.text((c - 30, r - 6), f"{k / 10:.1f}", fill=(200, 200, 200))
    c, r = at([0.4, 0])
    draw.text((c - 3, r + 22), "x", fill=(230, 230, 230))
    c, r = at([0, 0.45])
    draw.text((c - 44, r - 6), "y", fill=(230, 230, 230))
    nm, xy = cie.spectral_locus()
    for tick in diagram.TICKS:
        p = xy[np.searchsorted(nm, tick)]
        out = p - srgb.D65
        c, r = at(p + 0.035 * out / np.hypot(*out))
        draw.text((c - 10, r - 6), f"{tick}", fill=(220, 220, 220))
    c, r = at(srgb.D65)
    draw.text((c + 8, r - 4), "D65", fill=(0, 0, 0))
    c, r = at(srgb.PRIMARIES[1])
    draw.text((c + 8, r - 4), "sRGB", fill=(0, 0, 0))
    return np.asarray(picture)


def write_png(image: np.ndarray, out: Path) -> None:
    """Beside ``out`` first, then renamed over it (app.output_files): no half-written file."""
    from PIL import Image
    from app.output_files import write_beside
    write_beside(out, lambda temp: Image.fromarray(image).save(temp, format="PNG"))


def perception_labels(image: np.ndarray) -> np.ndarray:
    """The chart's parts named on it."""
    from PIL import Image, ImageDraw
    from core.colour import perception
    picture = Image.fromarray(image)
    draw = ImageDraw.Draw(picture)
    rows = perception.layout(image.shape[1], image.shape[0])
    draw.text((8, 6), "the same grey on a dark and on a light ground", fill=(200, 200, 200))
    draw.text((8, rows["even codes"][0] + 4), "even steps of sRGB code", fill=(255, 60, 60))
    draw.text((8, rows["even light"][0] + 4), "even steps of light", fill=(255, 60, 60))
    return np.asarray(picture)


def perception_main(args, out: Path) -> int:
    from core.colour import perception
    width, height = args.size
    write_png(perception_labels(perception.perception_chart(width, height)), out)
    codes, light = perception.ramps()
    print(f"wrote {out}: simultaneous contrast (code {perception.PATCH:g} on "
          f"{perception.DARK_GROUND:g} and on {perception.LIGHT_GROUND:g}); "
          f"{perception.RAMP_STEPS} patches of even code and of even light")
    for name, ramp in (("even code", codes), ("even light", light)):
        rises = perception.lightness_steps(ramp)
        print(f"  {name:10s} L* rises " + " ".join(f"{r:4.1f}" for r in rises))
    return 0


def main(args) -> int:
    from core.colour.diagram import chromaticity_diagram
    from app.output_files import out_problem
    args.out = args.out or ("perception.png" if args.perception else "chromaticity.png")
    if args.perception and args.scene is not None:
        print("error: --scene plots a scene's colours on the chromaticity diagram; the "
              "perception chart takes none", file=sys.stderr)
        return 2
    width, height = args.size
    refusal = out_problem(Path(args.out), args.scene or "-", force=False)
    if refusal:
        print(f"error: --out {args.out}: {refusal}", file=sys.stderr)
        return 2
    if args.perception:
        return perception_main(args, Path(args.out))
    points = colours = None
    if args.scene is not None:
        found = scene_colours(args.scene)
        if found is None:
            return 2
        points, colours = found
    image = chromaticity_diagram(width, height, MARGIN, points, colours)
    write_png(label(image, width, height), Path(args.out))
    print(f"wrote {args.out}: the CIE 1931 xy diagram, the sRGB gamut and D65"
          + (f", {len(points)} material colours of {args.scene}" if points is not None else ""))
    return 0
